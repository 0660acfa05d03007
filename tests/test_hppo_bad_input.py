"""Bad input to HybridPPO: clear errors at construction; a divergence stops with the last finite weights."""

import numpy as np
import pytest
import torch as th
from gymnasium import spaces

from sb3_aac import HybridPPO
from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import PoisonedRewardEnv
from tests.test_pdqn_bad_input import OBS, SpacesEnv

SMALL = dict(n_steps=32, batch_size=32, n_epochs=2, policy_kwargs=dict(net_arch=[16]))


@pytest.mark.parametrize(
    "action_space, match",
    [
        (spaces.Box(-1.0, 1.0, (2,)), "Box is not a parameterized action space.*A space without a discrete part"),
        (spaces.Discrete(3), "Discrete is not a parameterized action space"),
        (spaces.Tuple((spaces.Discrete(2), spaces.Box(-np.inf, np.inf, (1,)))), "infinite bounds.*no squashing"),
        (spaces.Tuple((spaces.Discrete(3), spaces.Box(-1, 1, (1,)), spaces.Box(-1, 1, (1,)))), "declares 3 action types"),
    ],
)
def test_unsupported_action_spaces(action_space, match):
    with pytest.raises(ValueError, match=f"HybridPPO cannot act in this action space.*{match}"):
        HybridPPO("MlpPolicy", SpacesEnv(OBS, action_space))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(gamma=1.5), "gamma must be in"),
        (dict(gae_lambda=-0.1), "gae_lambda must be in"),
        (dict(n_steps=0), "n_steps must be an integer"),
        (dict(batch_size=1.5), "batch_size must be an integer"),
        (dict(n_epochs=0), "n_epochs must be an integer"),
        (dict(clip_range=0.0), "clip_range must be > 0"),
        (dict(clip_range_params=-0.2), "clip_range_params must be > 0"),
        (dict(clip_range_vf=0.0), "clip_range_vf must be > 0"),
        (dict(clip_range="abc"), r"clip_range must be a finite number or a schedule .* got 'abc'"),
        (dict(policy_kwargs=dict(log_std_init=float("nan"))), "log_std_init must be a finite number"),
        (dict(ent_coef=float("nan")), "ent_coef must be a finite number"),
        (dict(max_grad_norm=0.0), "max_grad_norm must be > 0"),
        (dict(target_kl=0.0), "target_kl must be > 0"),
        (dict(n_steps=1, batch_size=1), "normalize_advantage needs batch_size >= 2"),
        (dict(policy_kwargs=dict(net_arch=dict(pi=[64]))), "Unknown net_arch keys"),
        (dict(policy_kwargs=dict(net_arch=[0])), "integer layer sizes >= 1"),
    ],
)
def test_bad_hyperparameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        HybridPPO("MlpPolicy", ParameterizedTargetEnv(), **{**SMALL, **kwargs})


def test_unknown_policy():
    with pytest.raises(ValueError, match="Policy RbfPolicy unknown"):
        HybridPPO("RbfPolicy", ParameterizedTargetEnv())


def test_nan_reward_is_refused_before_learning():
    env = PoisonedRewardEnv(poison_at=40)
    model = HybridPPO("MlpPolicy", env, seed=0, **SMALL)
    with pytest.raises(ValueError, match=r"non-finite .NaN or inf. rewards of lanes .0. at timestep 40"):
        model.learn(64)
    assert env.all_finite


def collected(**kwargs):
    """A model with one rollout collected and not yet trained on."""
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(), seed=0, **{**SMALL, **kwargs})
    model._setup_learn(32, None)
    model.collect_rollouts(model.env, model._init_callback(None), model.rollout_buffer, 32)
    return model


def test_nan_value_loss_stops_with_the_last_finite_weights():
    model = collected()
    before = {k: v.clone() for k, v in model.policy.state_dict().items()}
    model.rollout_buffer.returns[5] = np.nan
    with pytest.raises(FloatingPointError, match=r"HybridPPO diverged: the value loss became non-finite.*last finite"):
        model.train()
    for key, value in model.policy.state_dict().items():
        assert th.equal(value, before[key]) and th.isfinite(value).all(), key  # no step was taken


def test_nan_policy_loss_names_the_part():
    """A NaN advantage reaches the policy losses first (the discrete part is checked first)."""
    model = collected(normalize_advantage=False)
    model.rollout_buffer.advantages[3] = np.nan
    with pytest.raises(FloatingPointError, match="the discrete policy loss became non-finite"):
        model.train()


def test_non_finite_policy_output_stops_before_the_env_sees_it():
    env = PoisonedRewardEnv(poison_at=10**9)
    model = HybridPPO("MlpPolicy", env, seed=0, **SMALL)
    with th.no_grad():
        model.policy.log_std.fill_(float("inf"))
    with pytest.raises(FloatingPointError, match="the policy's output"):
        model.learn(32)
    assert env.all_finite and env.count == 0


def test_non_finite_type_logits_stop_before_the_env_sees_them():
    env = PoisonedRewardEnv(poison_at=10**9)
    model = HybridPPO("MlpPolicy", env, seed=0, **SMALL)
    with th.no_grad():
        model.policy.type_head.bias.fill_(float("nan"))
    with pytest.raises(FloatingPointError, match=r"the policy's output \(the type logits\)"):
        model.learn(32)
    assert env.count == 0
