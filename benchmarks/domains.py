"""The benchmark's domains: how each env id is built for training and how a policy is scored on it.

* Dribbling (``RoboCupDribblePaper-v0``, ``RoboCupDribble-v0``): batched :class:`~robocup_dribble.DribbleVecEnv`
  lanes; scored by :func:`robocup_dribble.evaluation.evaluate_dribbling` (metres along +x), whose episode slots each
  have their own seeded player, start state and noise (common random numbers).
* Platform (``Platform-v0``, PyPI ``hybrid-platform``): ``SelectObservation(gym.make("Platform-v0"), 0)`` in SB3's
  ``DummyVecEnv``; scored by the undiscounted return of greedy episodes, episode slot ``j`` of a set with seed ``s``
  starting from ``reset(seed=s * 1_000_003 + j)``, so every policy meets the same episodes too.

Each score comes as the summary every result file uses (:func:`summarize`) plus the per-episode scores in slot
order, so two policies' episodes can be paired.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import VecEnv

from benchmarks.presets import PLATFORM_ID
from robocup_dribble import ENV_PROFILES
from sb3_aac import SelectObservation

REACH_METRES = 20.0  # the paper's "at least around 20 meters with high reliability" (section 4.1)
PLATFORM_SLOT_STRIDE = 1_000_003  # a prime: the reset seeds of two evaluation sets never meet
PLATFORM_SUCCESS_RETURN = 1.0  # Platform's return is the share of the level covered: 1 reaches the goal

# Published Platform-v0 figures (mean return of the trained greedy policy), drawn as reference lines:
# (label, mean return, citation).
PLATFORM_REFERENCES: tuple[tuple[str, float, str], ...] = (
    ("MP-DQN", 0.987, "Bester, James, Konidaris 2019, arXiv:1905.04388"),
    ("HyAR-TD3", 0.98, "Li et al., ICLR 2022 (HyAR), Table 2"),
    ("P-DQN", 0.93, "as reported by Li et al., ICLR 2022, Table 2"),
    ("H-PPO", 0.80, "as reported by Li et al., ICLR 2022, Table 2"),
)


def is_dribbling(env_id: str) -> bool:
    return env_id in ENV_PROFILES


def metric(env_id: str) -> str:
    """The key of the summary that ranks policies on ``env_id``."""
    return "distance_mean" if is_dribbling(env_id) else "return_mean"


def metric_label(env_id: str) -> str:
    return "metres dribbled" if is_dribbling(env_id) else "mean return"


def platform_env(wrapper: Callable[[gym.Env], gym.Env] | None = None) -> gym.Env:
    """One Platform-v0 env with a Box observation (and ``wrapper`` around it, e.g. an action wrapper)."""
    import gym_platform  # noqa: F401  (registers Platform-v0)

    env: gym.Env = SelectObservation(gym.make(PLATFORM_ID), 0)
    return wrapper(env) if wrapper is not None else env


def train_env(env_id: str, n_envs: int, seed: int, wrapper: Callable[[gym.Env], gym.Env] | None = None) -> VecEnv:
    """The training VecEnv of a cell that acts in the env's own parameterized action space (``wrapper`` None) or
    through an action wrapper. Dribbling: ``DribbleVecEnv`` lanes (wrapped ones: :mod:`benchmarks.adapters`)."""
    if is_dribbling(env_id):
        from robocup_dribble import DribbleVecEnv

        if wrapper is not None:
            raise ValueError("dribbling baselines train on benchmarks.adapters.baseline_env (batched wrappers)")
        env = DribbleVecEnv(n_envs, profile=ENV_PROFILES[env_id])
        env.seed(seed)
        return env
    if env_id != PLATFORM_ID:
        raise ValueError(f"unknown env id {env_id!r}; the benchmark knows {[*ENV_PROFILES, PLATFORM_ID]}")
    return make_vec_env(lambda: platform_env(wrapper), n_envs=n_envs, seed=seed)


def distance_stats(d: np.ndarray) -> dict[str, float]:
    """Mean, median and max of per-episode metres (the keys every dribbling result uses)."""
    return {"distance_mean": float(np.mean(d)), "distance_median": float(np.median(d)), "distance_max": float(np.max(d))}


def summarize(env_id: str, scores: np.ndarray, ball_lost: np.ndarray | None = None) -> dict[str, Any]:
    """The summary every result file uses, from per-episode scores in slot order (kept under ``"episode_scores"``)."""
    d = np.asarray(scores, dtype=float)
    episode_scores = [round(float(x), 4) for x in d]
    if is_dribbling(env_id):
        if ball_lost is None:
            raise ValueError(f"a dribbling summary needs the per-episode ball_lost flags ({env_id})")
        return {
            "episodes": len(d),
            **distance_stats(d),
            "reach20_share": float(np.mean(d >= REACH_METRES)),
            "ball_loss_rate": float(np.mean(ball_lost)),
            "episode_scores": episode_scores,
        }
    return {
        "episodes": len(d),
        "return_mean": float(np.mean(d)),
        "return_median": float(np.median(d)),
        "success_share": float(np.mean(d >= PLATFORM_SUCCESS_RETURN - 1e-6)),
        "episode_scores": episode_scores,
    }


def evaluate(env_id: str, policy: Any, n_episodes: int, seed: int) -> dict[str, Any]:
    """Greedy score of ``policy`` (anything with SB3's ``predict``) on episode slots ``0..n_episodes-1`` of set
    ``seed`` of ``env_id``: :func:`summarize`'s summary."""
    if is_dribbling(env_id):
        from robocup_dribble.evaluation import evaluate_dribbling

        report = evaluate_dribbling(policy, n_episodes, ENV_PROFILES[env_id], seed)
        return summarize(env_id, report.distances, report.ball_lost)
    return summarize(env_id, platform_returns(policy, n_episodes, seed))


def platform_returns(policy: Any, n_episodes: int, seed: int) -> np.ndarray:
    """Undiscounted returns of greedy Platform episodes, slot ``j`` reset with seed ``seed * PLATFORM_SLOT_STRIDE + j``."""
    if n_episodes < 1:
        raise ValueError(f"n_episodes must be >= 1, got {n_episodes}")
    env = platform_env()
    returns = np.zeros(n_episodes)
    try:
        for slot in range(n_episodes):
            obs, _ = env.reset(seed=seed * PLATFORM_SLOT_STRIDE + slot)
            done = False
            while not done:
                action, _ = policy.predict(obs, deterministic=True)
                obs, reward, terminated, truncated, _ = env.step(action)
                returns[slot] += float(reward)
                done = terminated or truncated
    finally:
        env.close()
    return returns
