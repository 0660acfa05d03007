"""HybridPPO's rollouts: the numpy draw is the distribution's, the numpy actors are the torch ones, and the stored
values and log-probabilities are the policy's, step by step and env by env."""

import numpy as np
import pytest
import torch as th
from gymnasium import spaces
from hypothesis import given, settings
from hypothesis import strategies as st
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor

from sb3_aac import HybridPPO
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.hppo import hppo as hppo_module
from sb3_aac.hppo.acting import RolloutActor
from sb3_aac.hppo.distributions import HybridDistribution, sample_packed
from sb3_aac.hppo.policies import HybridActorCriticPolicy


@settings(max_examples=50, deadline=None)
@given(
    n_types=st.integers(1, 4),
    n_params=st.integers(1, 5),
    seed=st.integers(0, 2**31 - 1),
    scale=st.floats(0.1, 10.0),
)
def test_sample_packed_is_the_distributions_draw_on_the_same_noise(n_types, n_params, seed, scale):
    """HybridDistribution.sample draws an Exp(1) per type, then a normal per parameter: given those draws, the numpy
    sampler picks the same types and the same parameters."""
    generator = th.Generator().manual_seed(seed)
    n = 32
    logits = th.randn(n, n_types, generator=generator) * scale
    mean = th.randn(n, n_params, generator=generator)
    log_std = th.randn(n_params, generator=generator) * 0.5
    param_type = np.arange(n_params) % n_types
    dist = HybridDistribution(param_type, n_types).proba_distribution(logits, mean, log_std)
    th.manual_seed(seed)
    expected = dist.sample()
    th.manual_seed(seed)
    exponential = th.empty(n, n_types).exponential_().numpy()
    normal = th.randn(n, n_params).numpy()
    packed = sample_packed(logits.numpy().astype(np.float64), mean.numpy(), log_std.exp().numpy(), exponential, normal)
    assert np.array_equal(packed[:, 0], expected[:, 0].numpy())
    np.testing.assert_allclose(packed[:, 1:], expected[:, 1:].numpy(), rtol=1e-6, atol=1e-6)


def test_sample_packed_draws_types_with_the_softmax_probabilities():
    rng = np.random.default_rng(0)
    n, logits = 20_000, np.log([[0.2, 0.5, 0.3]])
    packed = sample_packed(
        np.repeat(logits + 7.0, n, axis=0), np.zeros((n, 1)), np.ones(1), rng.exponential(size=(n, 3)), np.zeros((n, 1))
    )
    shares = np.bincount(packed[:, 0].astype(int), minlength=3) / n
    np.testing.assert_allclose(shares, [0.2, 0.5, 0.3], atol=0.015)  # > 4 standard errors


class ScaledSum(BaseFeaturesExtractor):
    """A features extractor the ``.aacp`` format cannot hold."""

    def __init__(self, observation_space: spaces.Box):
        super().__init__(observation_space, features_dim=3)
        self.linear = th.nn.Linear(int(np.prod(observation_space.shape)), 3)

    def forward(self, observations: th.Tensor) -> th.Tensor:
        return self.linear(observations.flatten(1))


def _observations(env, n=64):
    rng = np.random.default_rng(1)
    space = env.observation_space
    return rng.uniform(space.low, space.high, size=(n, *space.shape)).astype(np.float32)


@pytest.mark.parametrize(
    "policy_kwargs",
    [
        None,
        dict(net_arch=dict(shared=[16], type=[8], params=[], vf=[16])),
        dict(net_arch=[32], activation_fn=th.nn.ReLU, ortho_init=False),
        dict(net_arch=[], activation_fn=th.nn.LeakyReLU),
    ],
)
def test_rollout_actor_runs_the_policys_networks_in_numpy(policy_kwargs):
    env = ParameterizedTargetEnv()
    model = HybridPPO("MlpPolicy", env, seed=0, policy_kwargs=policy_kwargs)
    actor = RolloutActor(model.policy)
    assert actor.networks is not None
    obs = _observations(env)
    type_logits, mean = actor(obs)
    with th.no_grad():
        expected_logits, expected_mean = model.policy.actor_outputs(th.as_tensor(obs))
    np.testing.assert_allclose(type_logits, expected_logits.numpy(), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(mean, expected_mean.numpy(), rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize(
    "policy_kwargs", [dict(features_extractor_class=ScaledSum), dict(activation_fn=th.nn.ELU)], ids=["extractor", "elu"]
)
def test_rollout_actor_falls_back_to_torch_where_the_policy_does_not_export(policy_kwargs):
    env = ParameterizedTargetEnv()
    model = HybridPPO("MlpPolicy", env, seed=0, policy_kwargs=policy_kwargs, n_steps=16, batch_size=16, n_epochs=1)
    actor = RolloutActor(model.policy)
    assert actor.networks is None
    obs = _observations(env)
    with th.no_grad():
        expected = model.policy.actor_outputs(th.as_tensor(obs))
    for got, want in zip(actor(obs), expected, strict=True):
        assert np.array_equal(got, want.numpy())
    model.learn(32)
    assert model._n_updates > 0


@pytest.mark.parametrize("evaluation_rows", [hppo_module.EVALUATION_ROWS, 5])
def test_rollout_stores_the_policys_values_and_log_probabilities_per_step_and_env(evaluation_rows, monkeypatch):
    """The batched passes at the rollout's end (one, or chunks of 5 rows) write each (step, env) entry with that row's
    own evaluation."""
    monkeypatch.setattr(hppo_module, "EVALUATION_ROWS", evaluation_rows)
    env = make_vec_env(ParameterizedTargetEnv, n_envs=3, seed=0)
    model = HybridPPO("MlpPolicy", env, seed=0, n_steps=8, batch_size=8, n_epochs=1)
    model._setup_learn(24, None)
    model.collect_rollouts(model.env, model._init_callback(None), model.rollout_buffer, 8)
    buffer = model.rollout_buffer
    assert buffer.full and np.isfinite(buffer.param_log_probs).all()
    for step in (0, 3, 7):
        for lane in range(3):
            obs = th.as_tensor(buffer.observations[step, lane][None])
            actions = th.as_tensor(buffer.actions[step, lane][None])
            with th.no_grad():
                value, type_log_prob, param_log_prob, _, _ = model.policy.evaluate_actions(obs, actions)
            assert buffer.values[step, lane] == pytest.approx(value.item(), rel=1e-5, abs=1e-6)
            assert buffer.log_probs[step, lane] == pytest.approx(type_log_prob.item(), rel=1e-5, abs=1e-6)
            assert buffer.param_log_probs[step, lane] == pytest.approx(param_log_prob.item(), rel=1e-5, abs=1e-6)


@pytest.mark.parametrize("normalize_images", [True, False])
def test_rollout_actor_reads_images_as_sb3s_preprocessing_does(normalize_images):
    """SB3 divides image observations by 255 before the features extractor (``normalize_images``): the numpy actors,
    and so the exported file, fold that into the input scaling."""
    image_space = spaces.Box(0, 255, (3, 4, 4), np.uint8)
    action_space = ParameterizedTargetEnv().action_space
    policy = HybridActorCriticPolicy(image_space, action_space, lambda _: 3e-4, normalize_images=normalize_images)
    actor = RolloutActor(policy)
    assert actor.networks is not None
    obs = np.random.default_rng(0).integers(0, 256, (16, 3, 4, 4)).astype(np.uint8)
    with th.no_grad():
        expected = policy.actor_outputs(th.as_tensor(obs))
    for got, want in zip(actor(obs), expected, strict=True):
        np.testing.assert_allclose(got, want.numpy(), rtol=1e-5, atol=1e-6)
