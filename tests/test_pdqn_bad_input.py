"""Bad input to P-DQN / MP-DQN: clear errors, and a divergence stops before the env sees a non-finite action."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

from sb3_aac import MPDQN, PDQN
from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import PoisonedRewardEnv, PoisonWeights

SMALL = dict(learning_starts=50, batch_size=16, policy_kwargs=dict(net_arch=[16]))


class SpacesEnv(gym.Env):
    def __init__(self, observation_space, action_space):
        self.observation_space, self.action_space = observation_space, action_space

    def reset(self, *, seed=None, options=None):
        return self.observation_space.sample(), {}

    def step(self, action):
        return self.observation_space.sample(), 0.0, False, False, {}


OBS = spaces.Box(-1.0, 1.0, (2,), np.float32)


@pytest.mark.parametrize("algo", [PDQN, MPDQN])
@pytest.mark.parametrize(
    "action_space, match",
    [
        (spaces.Box(-1.0, 1.0, (2,)), "Box is not a parameterized action space"),
        (spaces.Discrete(3), "Discrete is not a parameterized action space"),
        (spaces.Tuple((spaces.Discrete(2), spaces.Box(-np.inf, np.inf, (1,)))), "infinite bounds"),
        (spaces.Tuple((spaces.Discrete(3), spaces.Box(-1, 1, (1,)), spaces.Box(-1, 1, (1,)))), "declares 3 action types"),
        (spaces.Tuple((spaces.Discrete(2), spaces.Box(0, 5, (1,), np.int64))), "dtype int64"),
    ],
)
def test_unsupported_action_spaces(algo, action_space, match):
    with pytest.raises(ValueError, match=match):
        algo("MlpPolicy", SpacesEnv(OBS, action_space))


def test_unsupported_observation_space():
    action_space = spaces.Tuple((spaces.Discrete(2), spaces.Box(-1, 1, (1,))))
    with pytest.raises(ValueError, match="take a Box observation"):
        PDQN("MlpPolicy", SpacesEnv(spaces.Discrete(4), action_space))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(loss="l1"), "Unknown loss"),
        (dict(gamma=1.5), "gamma must be in"),
        (dict(actor_tau=-0.1), "actor_tau must be in"),
        (dict(exploration_fraction=0.0), "exploration_fraction must be in"),
        (dict(target_update_interval=0), "target_update_interval must be an integer"),
        (dict(max_grad_norm=0.0), "max_grad_norm must be > 0"),
        (dict(param_noise="pink"), "Unknown param_noise"),
        (dict(param_noise_std=-1.0), "Noise std must be >= 0"),
        (dict(policy_kwargs=dict(multi_pass=True)), "use PDQN .single pass. or MPDQN"),
        (dict(policy_kwargs=dict(param_bounding="clip")), "Unknown param_bounding"),
        (dict(policy_kwargs=dict(initial_params=[9.0, 0.0, 0.0, 0.0, 0.0])), "inside the parameter bounds"),
        (dict(policy_kwargs=dict(initial_params=[0.0])), "must hold 5 values"),
        (dict(optimize_memory_usage=True), "cannot be combined"),
    ],
)
def test_bad_hyperparameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        PDQN("MlpPolicy", ParameterizedTargetEnv(), **kwargs)


def test_unknown_policy():
    with pytest.raises(ValueError, match="Policy RbfPolicy unknown"):
        PDQN("RbfPolicy", ParameterizedTargetEnv())


@pytest.mark.parametrize("algo", [PDQN, MPDQN])
def test_nan_loss_names_the_network_before_a_nan_action(algo):
    env = PoisonedRewardEnv(poison_at=10**9)  # finite rewards: the Q network's weights go bad instead
    model = algo("MlpPolicy", env, seed=0, **SMALL)
    with pytest.raises(FloatingPointError, match=f"{algo.__name__} diverged: the Q network's loss became non-finite"):
        model.learn(1000, callback=PoisonWeights(80, lambda model: model.policy.q_net))
    assert env.all_finite and model.num_timesteps < 200
