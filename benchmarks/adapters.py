"""SB3 baselines on the dribbling env: their training envs, and adapters that make them act in the Tuple env.

A baseline trains on ``Box`` (:class:`~sb3_aac.FlattenParameterizedAction`) or ``Discrete``
(:class:`~sb3_aac.DiscretizeParameterizedAction`) actions. To evaluate it with the same code as SarsaAAC
(:func:`robocup_dribble.evaluation.evaluate_dribbling` steps a ``DribbleVecEnv`` with Tuple actions), an adapter's
``predict`` maps the model's actions to env actions with the wrappers' own batched conversions
(:func:`~sb3_aac.wrappers.scores_to_action`, :func:`~sb3_aac.wrappers.grid_to_action`), so it acts exactly as the
wrapped training env interpreted the same action.
"""

from __future__ import annotations

import copy
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3 import A2C, DDPG, DQN, PPO, SAC, TD3
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.noise import NormalActionNoise
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

import robocup_dribble  # noqa: F401  (registers the env ids)
from benchmarks import domains
from benchmarks.presets import BASELINES
from robocup_dribble import DribbleEnv, DribbleVecEnv
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.wrappers import (
    DiscretizeParameterizedAction,
    FlattenParameterizedAction,
    grid_to_action,
    make_grid,
    scores_to_action,
)

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
        k, params_scaled = scores_to_action(
            np.asarray(actions).reshape(-1, self.spec.n_types + self.spec.n_params), self.spec.n_types
        )
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
    """The parameterized action space of a benchmark env id."""
    env = gym.make(env_id) if domains.is_dribbling(env_id) else domains.episodic_env(env_id)
    try:
        return env.action_space
    finally:
        env.close()


class WrappedDribbleVecEnv(VecEnvWrapper):
    """A :class:`~robocup_dribble.DribbleVecEnv` presenting the action space of an action wrapper, batched.

    The action space, and the table of discrete actions, are those of a :class:`FlattenParameterizedAction` or
    :class:`DiscretizeParameterizedAction` instance; a batch of actions is converted with the same batched functions
    the wrappers use and stepped in one call (``step_packed``). Per transition this costs a few microseconds instead
    of the ~100-400 of SB3's ``DummyVecEnv`` over wrapped single envs (Python per env, a ``deepcopy`` of the infos,
    one reset call per finished episode), which was half of A2C's and PPO's training time. The parameters pass
    through float32, as the wrapped single env receives them, so both paths step the same physics with the same
    numbers (``tests/test_benchmarks.py`` checks a one-lane trajectory against the wrapped ``DribbleEnv``).

    :param venv: the dribbling lanes
    :param wrapper: a wrapper instance around a ``DribbleEnv`` of the same profile (only its spaces and tables are used)
    """

    def __init__(self, venv: VecEnv, wrapper: FlattenParameterizedAction | DiscretizeParameterizedAction):
        super().__init__(venv, action_space=wrapper.action_space)
        self.spec = wrapper.action_spec
        self.wrapper = wrapper
        self._actions: np.ndarray | None = None

    def convert(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Action types ``(n,)`` and parameters in env units ``(n, n_params)`` of a batch of wrapper actions."""
        if isinstance(self.wrapper, FlattenParameterizedAction):
            k, scaled = scores_to_action(np.asarray(actions).reshape(self.num_envs, -1), self.spec.n_types)
        else:
            k, scaled = grid_to_action(
                np.asarray(actions).reshape(-1).astype(np.int64), self.wrapper.types, self.wrapper.params_scaled
            )
        return k, self.spec.unscale(scaled).astype(np.float32).astype(np.float64)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        k, params = self.convert(self._actions)
        self._actions = None
        return self.venv.step_packed(k, params)

    def reset(self):
        return self.venv.reset()


def baseline_env(env_id: str, algo: str, n_envs: int | None = None, seed: int = 0, batched: bool = True) -> VecEnv:
    """The training VecEnv of a baseline: ``n_envs`` lanes of ``env_id`` behind the algorithm's action wrapper.

    :param batched: for dribbling, True (the benchmark's choice): one :class:`WrappedDribbleVecEnv`; False: SB3's
        ``make_vec_env`` over ``gym.make(env_id)`` with Monitor and the gym wrapper (the same env and actions, about 2x
        slower for A2C). Platform always runs in SB3's ``DummyVecEnv``.
    """
    spec = BASELINES[algo]
    if spec["wrapper"] == "flatten":
        wrapper, wrapper_kwargs = FlattenParameterizedAction, {}
    else:
        wrapper, wrapper_kwargs = DiscretizeParameterizedAction, {"bins": spec["bins"]}
    n_envs = n_envs or spec["n_envs"]
    if not domains.is_dribbling(env_id):
        return domains.train_env(env_id, n_envs, seed, lambda env: wrapper(env, **wrapper_kwargs))
    if not batched:
        return make_vec_env(env_id, n_envs=n_envs, seed=seed, wrapper_class=wrapper, wrapper_kwargs=wrapper_kwargs)
    profile = gym.spec(env_id).kwargs["profile"]
    venv = DribbleVecEnv(n_envs, profile=profile)
    venv.seed(seed)
    return WrappedDribbleVecEnv(venv, wrapper(DribbleEnv(profile=profile), **wrapper_kwargs))


def build_baseline(env_id: str, algo: str, seed: int, overrides: dict[str, Any] | None = None) -> BaseAlgorithm:
    """An untrained SB3 baseline with the hyperparameters of :data:`benchmarks.presets.BASELINES`."""
    spec = BASELINES[algo]
    # A deep copy: SB3 writes into policy_kwargs (DDPG adds n_critics=1, SAC use_sde), which would leak into the
    # next cell a worker runs.
    kwargs = copy.deepcopy({**spec["kwargs"], **(overrides or {})})
    n_envs = kwargs.pop("n_envs", spec["n_envs"])
    env = baseline_env(env_id, algo, n_envs, seed, batched=kwargs.pop("batched_env", True))
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
