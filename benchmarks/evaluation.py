"""Evaluating a policy during and after training: the decision cost, :class:`EvalCallback` (the learning curve of any
domain of :mod:`benchmarks.domains`), and :class:`TrainingTimeLimit`, which stops training at the equal wall-clock
budget.

The equal wall-clock budget: a cell with ``seconds > 0`` trains until that many seconds of training have passed
(its greedy evaluations excluded, so every learner gets the same training time whatever its evaluation costs), or
until its env-step horizon, whichever comes first; :class:`TrainingTimeLimit` ends ``learn`` at the limit.

The horizon (``Cell.budget``) is :data:`benchmarks.presets.WALL_CLOCK_HEADROOM` (2) times what the learner steps in
those seconds at its usual rate (:data:`benchmarks.presets.STEPS_PER_SECOND`), so that the clock ends training even
where the learner runs faster than usual; schedules (exploration, learning rates) run over the horizon, so at the
stop they are at least half done. The cell file records which limit ended training (``stopped_by``).
"""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np
from robocup_dribble import ENV_PROFILES, DribbleVecEnv
from stable_baselines3.common.callbacks import BaseCallback

from benchmarks import domains
from benchmarks.presets import EVAL_SEED, FINAL_SEED

PREDICT_CALLS = 300  # single-observation predict calls timed per cell (the median is reported)


def evaluation_observations(env_id: str, count: int) -> list[np.ndarray]:
    """``count`` first observations of the final evaluation set's episodes."""
    if domains.is_dribbling(env_id):
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


class TrainingTimeLimit(BaseCallback):
    """Stop training (``learn`` returns) once ``seconds`` of training have passed since training started, the time
    ``evaluation`` spent on its greedy evaluations excluded.

    :param seconds: the training-time budget (> 0)
    :param evaluation: the cell's learning-curve callback (its ``eval_seconds`` are not training time); place this
        callback after it in the ``CallbackList``
    """

    def __init__(self, seconds: float, evaluation: EvalCallback):
        super().__init__()
        if not seconds > 0:
            raise ValueError(f"a wall-clock budget must be > 0 seconds, got {seconds}")
        self.seconds, self.evaluation = float(seconds), evaluation
        self.reached = False  # whether the time limit (not the env-step horizon) ended training
        self._start = 0.0
        self._eval_before = 0.0  # evaluation seconds spent before training started (the curve's first point)

    def _on_training_start(self) -> None:
        self._start = time.perf_counter()
        self._eval_before = self.evaluation.eval_seconds

    def training_seconds(self) -> float:
        """Seconds of training so far (evaluations excluded)."""
        return time.perf_counter() - self._start - (self.evaluation.eval_seconds - self._eval_before)

    def _on_step(self) -> bool:
        self.reached = self.training_seconds() >= self.seconds
        return not self.reached
