"""SarsaAAC's critic of the parameters (``parameter_update="critic"``, :mod:`sb3_aac.sarsa_aac.parameter_critic`)."""

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from gymnasium import spaces
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac import RuntimePolicy, SarsaAAC, export_policy
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.sarsa_aac.parameter_critic import ParameterCritic
from sb3_aac.sarsa_aac.policies import MlpPolicy
from tests.helpers import POLICIES

TWO_TYPES = spaces.Tuple((spaces.Discrete(2), spaces.Tuple((spaces.Box(-1, 1, (1,)), spaces.Box(-1, 1, (1,))))))


def linear_critic() -> ParameterCritic:
    """A critic of linear heads on one scaled input, two types of one parameter each (outputs b_0, b_1, g_0, g_1, V)."""
    policy = MlpPolicy(spaces.Box(-1, 1, (1,)), TWO_TYPES, hidden_units=None)
    critic = ParameterCritic(policy)
    bank = critic.approximators.approximators
    with th.no_grad():
        bank.weight.copy_(th.tensor([[0.2], [0.4], [1.0], [-2.0], [0.0]], dtype=th.float64))
        bank.bias.copy_(th.tensor([0.1, -0.1, 0.0, 0.5, 0.0], dtype=th.float64))
    critic.reset_kernel()
    return critic


def test_critic_starts_at_zero():
    """A new critic claims no gain: every output 0, so no parameter moves before the critic has seen a sample."""
    critic = ParameterCritic(MlpPolicy(spaces.Box(-1, 1, (1,)), TWO_TYPES, hidden_units=3))
    out, _ = critic.approximators.evaluate(np.array([[0.3], [-0.7]]))
    np.testing.assert_array_equal(out, 0.0)


def test_critic_step_by_hand():
    """One sample, type 1: b_1 = 0.1 and g_1 = -0.5 at s = 0.5, noise 0.6 on type 1's parameter (type 0's is not
    its noise), 1.2 in units of the exploration's 0.5, so the gain -0.6 < 0 keeps the actor still, and the residual
    (1 - 0.1 + 0.6) / (1 + 1.44) moves b_1 and g_1 (times the noise 1.2) by the normalised linear step."""
    critic = linear_critic()
    obs, k = np.array([[0.5]]), np.array([1])
    params, mu, delta = np.array([[0.3, 0.8]]), np.array([[0.1, 0.2]]), np.array([1.0])
    errors = critic.parameter_errors(obs, k, params, mu, delta, rate=0.5, hidden_gain=1.0, noise_scale=0.5)
    np.testing.assert_array_equal(errors, 0.0)
    residual = 1.5 / 2.44
    step = 0.5 / (1 + 0.5**2)  # rate / (1 + |x|^2), x = 0.5
    bank = critic.approximators.approximators
    expected_w = np.array([0.2, 0.4 + step * residual * 0.5, 1.0, -2.0 + step * residual * 1.2 * 0.5, 0.0])
    expected_b = np.array([0.1, -0.1 + step * residual, 0.0, 0.5 + step * residual * 1.2, 0.0])
    np.testing.assert_allclose(bank.weight.numpy().ravel(), expected_w, rtol=1e-12)
    np.testing.assert_allclose(bank.bias.numpy(), expected_b, rtol=1e-12)


def test_critic_gain_gates_the_actor():
    """Where the critic says the executed parameters gain (g . noise > 0), the actor's error is the noise of the
    chosen type's parameters (CACLA's target), whatever the sign of delta; elsewhere 0."""
    critic = linear_critic()
    obs, k = np.array([[0.5], [0.5]]), np.array([0, 1])
    # type 0: g_0 = 1.0 * 0.5 + 0 = 0.5, noise +0.2: gains; type 1: g_1 = -0.5, noise -0.4: gains too (0.2)
    params, mu = np.array([[0.3, -0.9], [0.0, -0.2]]), np.array([[0.1, 0.5], [0.6, 0.2]])
    errors = critic.parameter_errors(obs, k, params, mu, np.array([-5.0, -5.0]), rate=0.5, hidden_gain=1.0, noise_scale=0.5)
    np.testing.assert_allclose(errors, [[0.2, 0.0], [0.0, -0.4]], rtol=1e-12)


def test_rate_one_lands_on_delta():
    """For one sample and linear heads a rate of 1 moves A_k(s, x) onto delta (the step is normalised); the noise 0.7
    is 2 in units of the exploration's 0.35."""
    critic = linear_critic()
    obs, k = np.array([[-0.3]]), np.array([0])
    params, mu, delta = np.array([[0.9, 0.0]]), np.array([[0.2, 0.0]]), np.array([2.5])
    critic.parameter_errors(obs, k, params, mu, delta, rate=1.0, hidden_gain=1.0, noise_scale=0.35)
    out, _ = critic.approximators.evaluate(obs)
    np.testing.assert_allclose(out[0, 0] + out[0, 2] * 2.0, 2.5, rtol=1e-12)


class RiskyBandit(gym.Env[np.ndarray, Any]):
    """One-step episodes, one type with one parameter ``p``: reward ``p`` with probability 0.9, else ``-12 p``. The
    mean, ``-0.3 p``, is best at ``p = -1``, but a larger ``p`` than the policy's wins most single samples, so CACLA,
    which moves toward the executed parameters where one sample's TD error is positive, climbs to ``p = +1``; a critic
    that averages the samples finds the mean's slope."""

    observation_space = spaces.Box(-1, 1, (1,))
    action_space = spaces.Tuple((spaces.Discrete(1), spaces.Tuple((spaces.Box(-1, 1, (1,)),))))

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        return np.zeros(1, np.float32), {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        p = float(action[1][0][0])
        reward = p if self.np_random.random() < 0.9 else -12.0 * p
        return np.zeros(1, np.float32), reward, True, False, {}


@pytest.mark.parametrize("parameter_update", ["cacla", "critic"])
def test_critic_follows_the_mean_where_cacla_follows_the_majority(parameter_update):
    """Seeded, 3,000 pulls: the critic's actor sends p < -0.5 (the mean's side), CACLA's p > 0.5."""
    model = SarsaAAC(
        MlpPolicy,
        RiskyBandit(),
        policy_kwargs=dict(hidden_units=None),
        learning_rate=0.02,  # the critics average over about 50 samples
        q_learning_rate=0.1,
        param_learning_rate=0.1,  # the actor moves faster than the critics average
        parameter_update=parameter_update,
        replay_ratio=0,  # the two update rules alone
        seed=0,
    )
    model.learn(3000)
    action, _ = model.predict(np.zeros(1, np.float32), deterministic=True)
    p = float(action[1][0][0])
    assert p < -0.5 if parameter_update == "critic" else p > 0.5


@pytest.mark.parametrize("policy", POLICIES)
def test_save_load_keeps_the_critic(tmp_path, policy):
    """The critic is saved and loaded with the model (and keeps learning); a paper model saves none."""
    kwargs = dict(hidden_units=4) if policy in ("MlpPolicy", "RbfMlpPolicy") else None
    model = SarsaAAC(policy, ParameterizedTargetEnv(), policy_kwargs=kwargs, parameter_update="critic", seed=1)
    model.learn(300)
    assert model.parameter_critic is not None
    model.save(tmp_path / "model.zip")
    loaded = SarsaAAC.load(tmp_path / "model.zip", env=ParameterizedTargetEnv())
    assert loaded.parameter_update == "critic" and loaded.parameter_critic is not None
    saved, restored = model.parameter_critic.state_dict(), loaded.parameter_critic.state_dict()
    assert saved.keys() == restored.keys()
    for name, value in saved.items():
        th.testing.assert_close(restored[name], value, rtol=0, atol=0)
    assert any(value.abs().sum() > 0 for name, value in restored.items() if "obs" not in name)  # it has learned
    loaded.learn(100)
    paper = SarsaAAC(policy, ParameterizedTargetEnv(), policy_kwargs=kwargs, seed=1)
    assert paper.parameter_critic is None
    assert set(paper.get_parameters()) == {"policy"}


def test_export_decides_as_predict(tmp_path):
    """The critic only shapes training: the exported policy decides as ``predict`` does."""
    model = SarsaAAC("TilePolicy", ParameterizedTargetEnv(), parameter_update="critic", seed=2)
    model.learn(500)
    path = export_policy(model, tmp_path / "policy")
    observations = np.random.default_rng(3).uniform(-1, 1, (20, 2)).astype(np.float32)
    exported, _ = RuntimePolicy.load(path).predict(observations)
    actions, _ = model.predict(observations, deterministic=True)
    for (k, params), (k_exported, params_exported) in zip(actions, exported, strict=True):
        assert k == k_exported
        for p, q in zip(params, params_exported, strict=True):
            np.testing.assert_allclose(p, q, atol=1e-6)


def test_unknown_parameter_update():
    with pytest.raises(ValueError, match="parameter_update must be one of"):
        SarsaAAC("TilePolicy", ParameterizedTargetEnv(), parameter_update="dpg")


@pytest.mark.parametrize("policy", POLICIES)
def test_reward_units_do_not_change_what_the_critic_teaches(policy):
    """Rewards x0.02 or x50: the critic's outputs scale with the rewards, so its gate, and the greedy actions, do not
    change."""
    obs = np.random.default_rng(5).uniform(-1, 1, (500, 2))
    greedy = {}
    for scale in (0.02, 50.0):
        env = make_vec_env(
            ParameterizedTargetEnv,
            n_envs=4,
            seed=0,
            wrapper_class=gym.wrappers.TransformReward,
            wrapper_kwargs=dict(func=lambda r, scale=scale: r * scale),
        )
        model = SarsaAAC(policy, env, seed=0, parameter_update="critic")
        before = model.policy.evaluate(obs)[0][:, model.policy.param_slice]
        model.learn(2_000)
        out, _ = model.policy.evaluate(obs)
        assert np.abs(out[:, model.policy.param_slice] - before).max() > 1e-2  # the critic let the actor move
        greedy[scale] = out[:, model.policy.q_slice].argmax(1), out[:, model.policy.param_slice]
    (types_small, params_small), (types_large, params_large) = greedy[0.02], greedy[50.0]
    assert (types_small == types_large).mean() >= 0.99
    np.testing.assert_allclose(params_small, params_large, atol=1e-6)
