"""Evaluating a policy during and after training: the summary every result file uses, the decision cost, and
:class:`DribbleEvalCallback` (the learning curve)."""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback

from benchmarks.presets import EVAL_SEED, FINAL_SEED
from robocup_dribble import DribbleVecEnv
from robocup_dribble.evaluation import DribbleReport, evaluate_dribbling

REACH_METRES = 20.0  # the paper's "at least around 20 meters with high reliability" (§4.1)
PREDICT_CALLS = 300  # single-observation predict calls timed per cell (the median is reported)


def distance_stats(d: np.ndarray) -> dict[str, float]:
    """Mean, median and max of per-episode metres (the keys every result file uses)."""
    return {"distance_mean": float(np.mean(d)), "distance_median": float(np.median(d)), "distance_max": float(np.max(d))}


def report_summary(report: DribbleReport) -> dict[str, float]:
    d = report.distances
    return {
        "episodes": len(d),
        **distance_stats(d),
        "reach20_share": report.share_reaching(REACH_METRES),
        "ball_loss_rate": report.loss_rate,
    }


def predict_microseconds(policy: Any, profile: str, calls: int = PREDICT_CALLS) -> float:
    """Median wall time of ``policy.predict`` on one observation (deterministic), in microseconds."""
    env = DribbleVecEnv(calls, profile=profile)
    env.seed(FINAL_SEED)
    observations = env.reset()
    policy.predict(observations[0], deterministic=True)  # warm-up (lazy setup, caches)
    times = []
    for obs in observations:
        start = time.perf_counter_ns()
        policy.predict(obs, deterministic=True)
        times.append(time.perf_counter_ns() - start)
    return statistics.median(times) / 1e3


class DribbleEvalCallback(BaseCallback):
    """Every ``eval_every`` training episodes: greedy metres on a fixed evaluation set, to the logger and a curve.

    Episodes are counted from the ``dones`` of each ``env.step`` (SarsaAAC's and SB3's on-/off-policy loops all
    expose them), so the same callback serves every algorithm. The first point is taken before training.

    :param policy: what ``evaluate_dribbling`` calls ``predict`` on (the model, or an adapter around it)
    :param profile: the env's server profile
    :param eval_every: training episodes between evaluations
    :param n_episodes: greedy episodes per evaluation
    :param seed: the evaluation seed (the same players, starts and noise at every point)
    """

    def __init__(self, policy: Any, profile: str, eval_every: int, n_episodes: int, seed: int = EVAL_SEED):
        super().__init__()
        self.policy, self.profile = policy, profile
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
        summary = report_summary(evaluate_dribbling(self.policy, self.n_episodes, self.profile, self.seed))
        self.eval_seconds += time.perf_counter() - start
        wall = time.perf_counter() - self._start
        point = {
            "episodes": self.episodes,
            "env_steps": int(self.num_timesteps),
            "wall_s": round(wall, 3),
            "train_s": round(wall - self.eval_seconds, 3),  # training time only, evaluations excluded
            **{k: v for k, v in summary.items() if k != "episodes"},
        }
        self.curve.append(point)
        for key in ("distance_mean", "distance_median", "distance_max", "reach20_share", "ball_loss_rate"):
            self.logger.record(f"eval/{key}", point[key])
        self.logger.record("eval/training_episodes", self.episodes)
        self.logger.dump(self.num_timesteps)
        return point
