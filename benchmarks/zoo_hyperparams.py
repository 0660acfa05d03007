"""The settings of ``hyperparams/<algo>.yml`` (rl-zoo3's format) as constructor arguments, so the benchmark scripts
train with exactly what ``examples/rl_zoo3_train.py`` trains with: one definition of each setting."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import yaml
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import VecEnv

HYPERPARAMS = Path(__file__).resolve().parents[1] / "hyperparams"
# rl-zoo3's own keys: how long, which policy, and how the env is wrapped (the scripts build their envs themselves).
ZOO_KEYS = ("n_timesteps", "policy", "env_wrapper")


def has_settings(algo: str, env_id: str) -> bool:
    """Whether ``hyperparams/<algo>.yml`` has an entry for ``env_id``."""
    return env_id in yaml.safe_load((HYPERPARAMS / f"{algo}.yml").read_text())


def settings(algo: str, env_id: str) -> dict[str, Any]:
    """The entry of ``env_id`` in ``hyperparams/<algo>.yml`` without rl-zoo3's own keys (``n_envs`` stays)."""
    entry = dict(yaml.safe_load((HYPERPARAMS / f"{algo}.yml").read_text())[env_id])
    for key in ZOO_KEYS:
        entry.pop(key, None)
    if "policy_kwargs" in entry:
        entry["policy_kwargs"] = eval(entry["policy_kwargs"], {"dict": dict})  # rl-zoo3's convention: a dict() string
    return entry


def env_wrapper(algo: str, env_id: str) -> Callable[[gym.Env], gym.Env]:
    """The ``env_wrapper`` chain of ``env_id``'s entry in ``hyperparams/<algo>.yml`` as one function (rl-zoo3's format:
    a list of ``module.Class`` names or ``{module.Class: kwargs}`` maps, applied in order; none: the identity)."""
    entries = yaml.safe_load((HYPERPARAMS / f"{algo}.yml").read_text())[env_id].get("env_wrapper") or []
    steps: list[tuple[Callable[..., gym.Env], dict[str, Any]]] = []
    for entry in entries if isinstance(entries, list) else [entries]:
        name, kwargs = next(iter(entry.items())) if isinstance(entry, dict) else (entry, {})
        module, _, attribute = name.rpartition(".")
        steps.append((getattr(importlib.import_module(module), attribute), dict(kwargs or {})))

    def wrap(env: gym.Env) -> gym.Env:
        for wrapper, kwargs in steps:
            env = wrapper(env, **kwargs)
        return env

    return wrap


def zoo_env(algo: str, env_id: str, n_envs: int, seed: int) -> VecEnv:
    """``n_envs`` lanes of ``env_id`` behind the ``env_wrapper`` chain of its entry in ``hyperparams/<algo>.yml``, in
    SB3's ``DummyVecEnv``: the env rl-zoo3 trains on with that file (Platform-v0 and the hybrid domains)."""
    import gym_platform  # noqa: F401  (registers Platform-v0)
    import hybrid_domains  # noqa: F401  (registers Goal-v0 and the others)

    wrap = env_wrapper(algo, env_id)
    return make_vec_env(lambda: wrap(gym.make(env_id)), n_envs=n_envs, seed=seed)
