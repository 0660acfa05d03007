"""SB3 baselines on the dribbling env: their training envs, and adapters that make them act in the Tuple env.

A baseline trains on ``Box`` (:class:`~sb3_aac.FlattenParameterizedAction`) or ``Discrete``
(:class:`~sb3_aac.DiscretizeParameterizedAction`) actions. To evaluate it with the same code as SarsaAAC
(:func:`robocup_dribble.evaluation.evaluate_dribbling` steps a ``DribbleVecEnv`` with Tuple actions), an adapter's
``predict`` maps the model's actions to env actions with the wrappers' own batched conversions
(:func:`~sb3_aac.wrappers.scores_to_action`, :func:`~sb3_aac.wrappers.grid_to_action`), so it acts exactly as the
wrapped training env interpreted the same action.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3 import A2C, DDPG, DQN, PPO, SAC, TD3
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.noise import NormalActionNoise
from stable_baselines3.common.vec_env import VecEnv

import robocup_dribble  # noqa: F401  (registers the env ids)
from benchmarks.presets import BASELINES
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.wrappers import DiscretizeParameterizedAction, FlattenParameterizedAction, grid_to_action, make_grid, scores_to_action

ALGOS: dict[str, type[BaseAlgorithm]] = {"PPO": PPO, "A2C": A2C, "SAC": SAC, "TD3": TD3, "DDPG": DDPG, "DQN": DQN}


class FlatActionAdapter:
    """``predict`` of a model trained through :class:`FlattenParameterizedAction`, returning the env's Tuple actions.

    :param model: anything with SB3's ``predict`` giving ``(K + n_params,)`` flat actions (or a batch of them)
    :param action_space: the parameterized action space of the env (not the wrapper's Box)
    """

    def __init__(self, model: Any, action_space: gym.spaces.Space):
        self.model = model
        self.spec = ParameterizedActionSpec.from_space(action_space)

    def convert(self, actions: np.ndarray) -> np.ndarray:
        """``(n, K + n_params)`` flat actions -> ``(n,)`` object array of env actions."""
        k, params_scaled = scores_to_action(np.asarray(actions).reshape(-1, self.spec.n_types + self.spec.n_params), self.spec.n_types)
        return self.spec.to_env(k, params_scaled)

    def predict(self, observation: np.ndarray, state: Any = None, episode_start: Any = None, deterministic: bool = True):
        actions, state = self.model.predict(observation, state, episode_start, deterministic=deterministic)
        env_actions = self.convert(actions)
        return (env_actions[0] if np.ndim(observation) == 1 else env_actions), state


class DiscreteActionAdapter:
    """``predict`` of a model trained through :class:`DiscretizeParameterizedAction`, returning Tuple actions.

    :param model: anything with SB3's ``predict`` giving discrete action indices
    :param action_space: the parameterized action space of the env
    :param bins: the wrapper's ``bins`` (the same grid is rebuilt with :func:`make_grid`)
    """

    def __init__(self, model: Any, action_space: gym.spaces.Space, bins: int | list[int]):
        self.model = model
        self.spec = ParameterizedActionSpec.from_space(action_space)
        self.types, self.params_scaled = make_grid(self.spec.dims, bins)

    def convert(self, actions: np.ndarray) -> np.ndarray:
        """``(n,)`` discrete actions -> ``(n,)`` object array of env actions."""
        k, params_scaled = grid_to_action(np.asarray(actions).reshape(-1).astype(np.int64), self.types, self.params_scaled)
        return self.spec.to_env(k, params_scaled)

    def predict(self, observation: np.ndarray, state: Any = None, episode_start: Any = None, deterministic: bool = True):
        actions, state = self.model.predict(observation, state, episode_start, deterministic=deterministic)
        env_actions = self.convert(actions)
        return (env_actions[0] if np.ndim(observation) == 1 else env_actions), state


def env_action_space(env_id: str) -> gym.spaces.Space:
    """The Tuple action space of a registered env id."""
    env = gym.make(env_id)
    try:
        return env.action_space
    finally:
        env.close()


def baseline_env(env_id: str, algo: str, n_envs: int | None = None, seed: int = 0) -> VecEnv:
    """The training VecEnv of a baseline: ``n_envs`` copies of ``gym.make(env_id)``, Monitor, then the action wrapper."""
    spec = BASELINES[algo]
    if spec["wrapper"] == "flatten":
        wrapper, wrapper_kwargs = FlattenParameterizedAction, None
    else:
        wrapper, wrapper_kwargs = DiscretizeParameterizedAction, {"bins": spec["bins"]}
    return make_vec_env(env_id, n_envs=n_envs or spec["n_envs"], seed=seed, wrapper_class=wrapper, wrapper_kwargs=wrapper_kwargs)


def build_baseline(env_id: str, algo: str, seed: int, overrides: dict[str, Any] | None = None) -> BaseAlgorithm:
    """An untrained SB3 baseline with the hyperparameters of :data:`benchmarks.presets.BASELINES`."""
    spec = BASELINES[algo]
    kwargs = {**spec["kwargs"], **(overrides or {})}
    n_envs = kwargs.pop("n_envs", spec["n_envs"])
    env = baseline_env(env_id, algo, n_envs, seed)
    if "action_noise_sigma" in spec:
        dim = env.action_space.shape[0]
        kwargs["action_noise"] = NormalActionNoise(np.zeros(dim), spec["action_noise_sigma"] * np.ones(dim))
    return ALGOS[algo]("MlpPolicy", env, seed=seed, device="cpu", verbose=0, **kwargs)


def adapter_for(model: BaseAlgorithm, algo: str, env_id: str) -> FlatActionAdapter | DiscreteActionAdapter:
    """The evaluation adapter of a trained baseline."""
    spec = BASELINES[algo]
    space = env_action_space(env_id)
    if spec["wrapper"] == "flatten":
        return FlatActionAdapter(model, space)
    return DiscreteActionAdapter(model, space, spec["bins"])
