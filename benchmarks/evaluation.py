"""Evaluating a policy during and after training: the decision cost, and :class:`EvalCallback` (the learning curve
of any domain of :mod:`benchmarks.domains`)."""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from benchmarks import domains
from benchmarks.presets import EVAL_SEED, FINAL_SEED

PREDICT_CALLS = 300  # single-observation predict calls timed per cell (the median is reported)


def evaluation_observations(env_id: str, count: int) -> list[np.ndarray]:
    """``count`` first observations of the final evaluation set's episodes."""
    if domains.is_dribbling(env_id):
        from robocup_dribble import ENV_PROFILES, DribbleVecEnv

        env = DribbleVecEnv(count, profile=ENV_PROFILES[env_id])
        env.seed(FINAL_SEED)
        return list(env.reset())
    env = domains.episodic_env(env_id)
    observations = [env.reset(seed=FINAL_SEED * domains.SLOT_STRIDE + j)[0] for j in range(count)]
    env.close()
    return observations


def predict_microseconds(policy: Any, env_id: str, calls: int = PREDICT_CALLS) -> float:
    """Median wall time of ``policy.predict`` on one observation (deterministic), in microseconds."""
    observations = evaluation_observations(env_id, calls)
    policy.predict(observations[0], deterministic=True)  # warm-up (lazy setup, caches)
    times = []
    for obs in observations:
        start = time.perf_counter_ns()
        policy.predict(obs, deterministic=True)
        times.append(time.perf_counter_ns() - start)
    return statistics.median(times) / 1e3


class EvalCallback(BaseCallback):
    """Every ``eval_every`` training episodes: the greedy score on a fixed evaluation set, to the logger and a curve.

    Episodes are counted from the ``dones`` of each ``env.step`` (SarsaAAC's, P-DQN's and SB3's loops all expose
    them), so the same callback serves every algorithm. The first point is taken before training. Curve points carry
    the summary of :func:`benchmarks.domains.summarize` without the per-episode scores.

    :param policy: what :func:`benchmarks.domains.evaluate` calls ``predict`` on (the model, or an adapter around it)
    :param env_id: the env the policy is scored on
    :param eval_every: training episodes between evaluations
    :param n_episodes: greedy episodes per evaluation
    :param seed: the evaluation set (the same episodes at every point and for every policy)
    """

    def __init__(self, policy: Any, env_id: str, eval_every: int, n_episodes: int, seed: int = EVAL_SEED):
        super().__init__()
        self.policy, self.env_id = policy, env_id
        self.eval_every, self.n_episodes, self.seed = eval_every, n_episodes, seed
        self.episodes = 0
        self.next_eval = eval_every
        self.curve: list[dict[str, Any]] = []
        self.eval_seconds = 0.0
        self._start = 0.0

    def _on_training_start(self) -> None:
        self._start = time.perf_counter()
        self.evaluate()

    def _on_step(self) -> bool:
        self.episodes += int(np.sum(self.locals["dones"]))
        if self.episodes >= self.next_eval:
            self.evaluate()
            self.next_eval = (self.episodes // self.eval_every + 1) * self.eval_every
        return True

    def evaluate(self) -> dict[str, Any]:
        start = time.perf_counter()
        summary = domains.evaluate(self.env_id, self.policy, self.n_episodes, self.seed)
        self.eval_seconds += time.perf_counter() - start
        wall = time.perf_counter() - self._start
        scores = {k: v for k, v in summary.items() if k not in ("episodes", "episode_scores")}
        point = {
            "episodes": self.episodes,
            "env_steps": int(self.num_timesteps),
            "wall_s": round(wall, 3),
            "train_s": round(wall - self.eval_seconds, 3),  # training time only, evaluations excluded
            **scores,
        }
        self.curve.append(point)
        for key, value in scores.items():
            self.logger.record(f"eval/{key}", value)
        self.logger.record("eval/training_episodes", self.episodes)
        self.logger.dump(self.num_timesteps)
        return point
