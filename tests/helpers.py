"""Shared test constants, the registry of algorithms the feature tests run, and tiny envs."""

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any
import math

import gymnasium as gym
import numpy as np
import torch as th
import pytest
from stable_baselines3.common.callbacks import BaseCallback
from gymnasium import spaces

from sb3_aac import MPDQN, PDQN, HybridPPO, SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv

POLICIES = ["MlpPolicy", "RbfMlpPolicy", "RbfPolicy", "TilePolicy", "DeepPolicy"]
LAYOUTS = ["nested", "flat", "shared", "oneof"]
# P-DQN / MP-DQN small and fast: learning from step 50 on minibatches of 16, one hidden layer of 16.
PDQN_SMALL = dict(learning_starts=50, batch_size=16, policy_kwargs=dict(net_arch=[16]))
# HybridPPO small and fast: rollouts of 16 steps per lane, two epochs over minibatches of 16, hidden layers of 16.
HPPO_SMALL = dict(n_steps=16, batch_size=16, n_epochs=2, policy_kwargs=dict(net_arch=[16]))


@dataclass(frozen=True)
class Algo:
    """One algorithm configuration of the feature tests (tests that every algorithm of the package must pass)."""

    algo: type[Any]  # the algorithm class
    policy: str  # a key of its policy_aliases
    cli: str  # its name for ``sb3-aac train --algo`` and rl-zoo3
    kwargs: dict[str, Any] = field(default_factory=dict)  # small, fast settings for tests
    own_tags: tuple[str, ...] = ()  # the log keys of its own (besides tests/test_logging.py's COMMON_TAGS)
    log_often: dict[str, Any] = field(default_factory=dict)  # settings under which log_interval alone sets the dumps
    on_policy: bool = False  # whether it collects whole rollouts of n_steps per lane (kwargs' n_steps) between updates
    value_stats: str = "train/q"  # the prefix of its critic's value statistics (common.action_stats.ActionStats)
    # A hyperparameter that _setup_model turns into a schedule, and the value the model uses at the end of a learn:
    # loading with another value of the hyperparameter must change it.
    rebuilt: tuple[str, Callable[[Any], float]] = ("exploration_final_eps", lambda model: model.exploration_rate)

    @property
    def id(self) -> str:
        return f"{self.algo.__name__}-{self.policy}"

    def make(self, env: Any, **kwargs: Any) -> Any:
        """The algorithm on ``env`` with the case's policy and settings, ``kwargs`` on top."""
        return self.algo(self.policy, env, **{**self.kwargs, **kwargs})

    @property
    def rollout(self) -> dict[str, int]:
        """The settings that fix how many steps per lane it collects between updates (a run keeps them over a
        sampler's draws): an on-policy algorithm's ``n_steps``, nothing for one that updates between single steps."""
        return {"n_steps": self.kwargs["n_steps"]} if self.on_policy else {}

    @property
    def rollout_steps(self) -> int:
        """Env steps per lane collected between updates."""
        return self.rollout.get("n_steps", 1)

    def cli_settings(self) -> list[str]:
        """The case's settings as ``sb3-aac train`` options (``--set key=value``)."""
        return [arg for key, value in self.kwargs.items() for arg in ("--set", f"{key}={value!r}")]

    def timesteps(self, budget: int, n_envs: int = 1, start: int = 0) -> int:
        """
        ``num_timesteps`` after ``learn(budget)`` from ``start`` on ``n_envs`` lanes, unless a callback stops it: the
        algorithm collects ``rollout_steps`` steps of every lane at a time, so it runs on to the first multiple of
        ``rollout_steps * n_envs`` steps at or beyond the budget (as SB3's PPO and DQN do).
        """
        chunk = self.rollout_steps * n_envs
        return start + math.ceil(budget / chunk) * chunk


# The keys of the algorithms that explore with a decaying epsilon and name their critic's loss critic_loss.
_EPSILON_TAGS = ("rollout/exploration_rate", "train/critic_loss")
_SARSA_AAC_TAGS = (
    *("rollout/type_freq_1", "train/td_error_abs_mean", "train/q_loss", "train/param_update_fraction", "train/param_noise"),
    *_EPSILON_TAGS,
)
_PDQN_TAGS = ("train/actor_loss", "train/learning_rate", "train/actor_learning_rate", *_EPSILON_TAGS)
_HPPO_TAGS = (
    *("train/policy_loss_discrete", "train/policy_loss_params", "train/clip_fraction_discrete"),
    *("train/clip_fraction_params", "train/entropy_discrete", "train/entropy_params", "train/value_loss"),
    *("train/approx_kl", "train/explained_variance", "train/std", "train/clip_range", "train/clip_range_params"),
    *("train/learning_rate", "rollout/type_freq_2", "rollout/param_mean_1_1"),
)
# Every algorithm, and SarsaAAC with each policy: a new algorithm (or policy) joins the feature tests by one line.
ALGOS = [
    # RbfPolicy first: the SarsaAAC case of ALGO_CLASSES.
    *(
        Algo(
            SarsaAAC,
            name,
            "sarsa_aac",
            own_tags=_SARSA_AAC_TAGS,
            log_often=dict(log_min_timesteps=0),
            value_stats="train/value",
        )
        for name in ("RbfPolicy", "MlpPolicy", "RbfMlpPolicy", "TilePolicy", "DeepPolicy")
    ),
    Algo(PDQN, "MlpPolicy", "pdqn", PDQN_SMALL, _PDQN_TAGS),
    Algo(MPDQN, "MlpPolicy", "mpdqn", PDQN_SMALL, _PDQN_TAGS),
    Algo(
        HybridPPO,
        "MlpPolicy",
        "hppo",
        HPPO_SMALL,
        _HPPO_TAGS,
        on_policy=True,
        value_stats="train/value",
        rebuilt=("clip_range", lambda model: model.clip_range_schedule(model._current_progress_remaining)),
    ),
]
# One case per algorithm class (the first listed), for the tests of what the policy does not change.
ALGO_CLASSES = [case for i, case in enumerate(ALGOS) if all(other.algo is not case.algo for other in ALGOS[:i])]


def algos(cases: list[Algo] = ALGOS) -> Any:
    """``@algos()``: parametrise a test's ``case`` argument over ``cases``, with readable ids."""
    return pytest.mark.parametrize("case", cases, ids=[case.id for case in cases])


class OneStepEnv(gym.Env):
    """Constant observation, reward 1, every episode ends after one step: terminated, or truncated (time limit)."""

    def __init__(self, truncate: bool, obs: float = 0.0, reward: float = 1.0):
        self.truncate, self.obs, self.reward = truncate, np.array([obs], np.float32), reward
        self.observation_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.action_space = spaces.Tuple((spaces.Discrete(2), spaces.Box(-1.0, 1.0, (1,), np.float32)))

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return self.obs.copy(), {}

    def step(self, action):
        return self.obs.copy(), self.reward, not self.truncate, self.truncate, {}


class PoisonWeights(BaseCallback):
    """From env step ``at`` on, sets one weight of ``module(model)`` to NaN at every step: a divergence as training
    would cause it (the env's output stays finite, so the divergence checks, not the env checks, must catch it)."""

    def __init__(self, at: int, module: Any = lambda model: model.policy) -> None:
        super().__init__()
        self.at, self.module = at, module

    def _on_step(self) -> bool:
        if self.num_timesteps >= self.at:
            with th.no_grad():
                next(self.module(self.model).parameters()).view(-1)[0] = float("nan")
        return True


class PoisonedRewardEnv(ParameterizedTargetEnv):
    """Returns a NaN reward from step ``poison_at`` on; records whether every action it received was finite."""

    def __init__(self, poison_at: int):
        super().__init__(loss_threshold=0.0)
        self.poison_at, self.count, self.all_finite = poison_at, 0, True

    def step(self, action):
        self.all_finite &= bool(np.isfinite(np.concatenate([np.ravel(p) for p in action[1]])).all())
        obs, reward, terminated, truncated, info = super().step(action)
        self.count += 1
        return obs, (np.nan if self.count >= self.poison_at else reward), terminated, truncated, info
