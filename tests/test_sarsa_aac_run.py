"""SarsaAAC's own behaviour in training (policies, exploration, bootstrapping, divergence); what every algorithm does
alike is in test_run.py."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import DummyVecEnv

from sb3_aac import DeepPolicy, MlpPolicy, RbfMlpPolicy, RbfPolicy, SarsaAAC, TilePolicy
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.sarsa_aac.policies import DenseBankPolicy
from sb3_aac.sarsa_aac.exploration import select_types
from tests.helpers import OneStepEnv, PoisonWeights


def test_policy_aliases_and_classes():
    assert SarsaAAC.policy_aliases == {
        "MlpPolicy": MlpPolicy,
        "RbfMlpPolicy": RbfMlpPolicy,
        "RbfPolicy": RbfPolicy,
        "TilePolicy": TilePolicy,
        "DeepPolicy": DeepPolicy,
    }
    model = SarsaAAC(RbfPolicy, ParameterizedTargetEnv(), seed=0)
    assert isinstance(model.policy, RbfPolicy)
    with pytest.raises(ValueError, match="Policy CnnPolicy unknown"):
        SarsaAAC("CnnPolicy", ParameterizedTargetEnv())


@pytest.mark.parametrize(
    "policy, policy_kwargs, n_features, hidden",
    [
        ("MlpPolicy", dict(hidden_units=2), 2, 2),
        ("MlpPolicy", dict(hidden_units=20), 2, 20),
        ("RbfMlpPolicy", dict(hidden_units=2, n_rbf=5), 10, 2),
        ("RbfPolicy", dict(n_rbf=30), 60, None),
        ("RbfPolicy", dict(n_rbf=50, rbf_width=0.5, obs_bounds=([-2, -2], [2, 2])), 100, None),
        # Inputs 0, 1 and the pair, 8 tilings: (9 + 9 + 81) * 8 features.
        ("TilePolicy", dict(), 792, None),
        ("TilePolicy", dict(tile_groups=[(0, 1)], tiles_per_input=4, n_tilings=2), 50, None),
    ],
)
def test_policy_kwargs(policy, policy_kwargs, n_features, hidden):
    model = SarsaAAC(policy, ParameterizedTargetEnv(), policy_kwargs=policy_kwargs, seed=0)
    bank = model.policy.approximators
    assert bank.n_features == n_features
    if isinstance(model.policy, DenseBankPolicy):
        assert bank.hidden_units == model.policy.hidden_units == hidden
    else:  # tiles have a linear head
        assert isinstance(model.policy, TilePolicy) and hidden is None
    # K=3 Q approximators, 1 + 2 + 2 parameter approximators, 1 critic.
    assert bank.n_outputs == 3 + 5 + 1
    model.learn(200)


def test_boltzmann_exploration():
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), type_exploration="boltzmann", exploration_initial_eps=1.0, seed=0)
    model.learn(300)
    assert model.exploration_rate == pytest.approx(0.05)


@pytest.mark.parametrize(
    "mode, rate, expected",
    [
        ("boltzmann", 1.0, [0.25, 0.5, 0.25]),  # softmax of [0, log 2, 0]
        ("boltzmann", 0.0, [0.0, 1.0, 0.0]),
        ("epsilon_greedy", 0.3, [0.1, 0.8, 0.1]),
        ("epsilon_greedy", 0.0, [0.0, 1.0, 0.0]),
    ],
)
def test_select_types_distribution(mode, rate, expected):
    q = np.tile([0.0, np.log(2.0), 0.0], (40_000, 1))
    k = select_types(q, rate, mode, np.random.default_rng(0))
    np.testing.assert_allclose(np.bincount(k, minlength=3) / len(k), expected, atol=0.01)


def test_exploration_schedules():
    model = SarsaAAC(
        "RbfPolicy",
        ParameterizedTargetEnv(),
        exploration_fraction=0.5,
        exploration_initial_eps=0.8,
        exploration_final_eps=0.1,
        param_noise_initial=0.4,
        param_noise_final=0.0,
        seed=0,
    )
    model.learn(1000)
    assert model.exploration_rate == pytest.approx(0.1)
    assert model.param_noise == pytest.approx(0.0)
    # With no noise and epsilon 0, non-deterministic predict is the greedy action.
    model.exploration_rate = 0.0
    obs = np.array([0.3, -0.2], np.float32)
    greedy, _ = model.predict(obs, deterministic=True)
    explored, _ = model.predict(obs, deterministic=False)
    assert greedy[0] == explored[0]
    for a, b in zip(greedy[1], explored[1], strict=True):
        np.testing.assert_array_equal(a, b)


class EpisodeRates(BaseCallback):
    """Records (episodes, exploration rate, parameter noise) after every step."""

    def __init__(self):
        super().__init__()
        self.rates = []

    def _on_step(self):
        self.rates.append((self.model.episode_num, self.model.exploration_rate, self.model.param_noise))
        return True


@pytest.mark.parametrize("budget", [300, 3000])
def test_exploration_by_episodes_ignores_the_budget(budget):
    """With exploration_episodes=10 (one-step episodes) both rates reach their final values after 10 episodes,
    halfway at 5, whatever total_timesteps."""
    env = OneStepEnv(truncate=False)
    model = SarsaAAC(
        "TilePolicy", env, exploration_episodes=10, exploration_initial_eps=0.8, exploration_final_eps=0.2, seed=0
    )
    callback = EpisodeRates()
    model.learn(budget, callback=callback)
    rates = {episodes: (rate, noise) for episodes, rate, noise in callback.rates}
    assert rates[0] == pytest.approx((0.8, 0.3))
    assert rates[5] == pytest.approx((0.5, 0.175))  # (0.8 + 0.2) / 2, (0.3 + 0.05) / 2
    assert rates[10] == pytest.approx((0.2, 0.05))
    assert (model.exploration_rate, model.param_noise) == pytest.approx((0.2, 0.05))


def test_predict_explores_when_not_deterministic():
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), exploration_initial_eps=1.0, seed=0)
    obs = np.array([0.3, -0.2], np.float32)
    assert len({model.predict(obs, deterministic=True)[0][0] for _ in range(20)}) == 1
    assert len({model.predict(obs, deterministic=False)[0][0] for _ in range(50)}) == 3
    params = {model.predict(obs, deterministic=False)[0][1][2][0] for _ in range(20)}
    assert len(params) > 1  # Gaussian parameter noise


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(type_exploration="softmax"), "Unknown type_exploration 'softmax'"),
        (dict(gamma=1.5), "gamma must be in"),
        (dict(exploration_fraction=0.0), "exploration_fraction must be in"),
        (dict(param_noise_initial=-0.1), "param_noise_initial must be a finite number >= 0"),
        (dict(exploration_initial_eps=2.0), "epsilon-greedy exploration rates must be <= 1"),
        (dict(exploration_episodes=0), "exploration_episodes must be None or a whole number of episodes >= 1"),
        (dict(exploration_episodes=2.5), "exploration_episodes must be None or a whole number"),
    ],
)
def test_bad_hyperparameters(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), **kwargs)


class DictObsEnv(gym.Env):
    observation_space = spaces.Dict({"a": spaces.Box(-1.0, 1.0, (2,), np.float32)})
    action_space = ParameterizedTargetEnv().action_space


class InfiniteObsEnv(ParameterizedTargetEnv):
    def __init__(self):
        super().__init__()
        self.observation_space = spaces.Box(-np.inf, np.inf, (2,), np.float32)


@pytest.mark.parametrize(
    "policy, env, message",
    [
        ("RbfPolicy", DictObsEnv(), "Unsupported observation space Dict"),  # P-DQN: SB3 asks for MultiInputPolicy
        ("RbfPolicy", InfiniteObsEnv(), "infinite bounds, so RBF centres cannot be placed"),
        ("RbfMlpPolicy", InfiniteObsEnv(), "infinite bounds, so RBF centres cannot be placed"),
    ],
)
def test_unsupported_envs(policy, env, message):
    with pytest.raises(ValueError, match=message):
        SarsaAAC(policy, env)


def test_infinite_obs_bounds_mlp_and_rbf_with_bounds():
    SarsaAAC("MlpPolicy", InfiniteObsEnv(), seed=0).learn(100)
    model = SarsaAAC("RbfPolicy", InfiniteObsEnv(), policy_kwargs=dict(obs_bounds=([-1, -1], [1, 1])), seed=0)
    model.learn(100)


def values(model, obs):
    out, _ = model.policy.evaluate(np.array(obs, np.float64).reshape(-1, 1))
    return out[:, model.policy.q_slice], out[:, model.policy.value_index]


def test_termination_does_not_bootstrap_truncation_does():
    """With reward 1 per one-step episode and gamma=0.5: V = Q = 1 on termination, 1 / (1 - 0.5) = 2 on a time limit."""
    env = DummyVecEnv([lambda: OneStepEnv(truncate=False, obs=-0.5), lambda: OneStepEnv(truncate=True, obs=0.5)])
    model = SarsaAAC("RbfPolicy", env, gamma=0.5, learning_rate=0.5, q_learning_rate=0.5, exploration_initial_eps=0.5, seed=0)
    model.learn(4000)
    q, v = values(model, [-0.5, 0.5])
    np.testing.assert_allclose(v, [1.0, 2.0], atol=0.05)
    np.testing.assert_allclose(q, [[1.0, 1.0], [2.0, 2.0]], atol=0.05)


def test_divergence_raises_clear_error():
    """A critic weight gone non-finite: the error names the approximators and the remedies."""
    model = SarsaAAC("RbfPolicy", OneStepEnv(truncate=False), seed=0)
    critic = PoisonWeights(300)
    with pytest.raises(FloatingPointError, match=r"SarsaAAC diverged: .* became non-finite .* Lower the learning"):
        model.learn(2000, callback=critic)
