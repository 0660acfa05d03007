"""The greedy evaluation a tuning trial is scored by: the same fixed episodes every time, reported to the trial."""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
import optuna
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.vec_env import VecEnv

from sb3_aac.common.checkpoints import GreedyCheckpoints

RETURN = "return"  # the objective name meaning the episode return rather than an info key


def greedy_score(model: BaseAlgorithm, env: VecEnv, n_episodes: int, seed: int, objective: str = RETURN) -> float:
    """
    Mean over ``n_episodes`` greedy episodes of the return (``objective="return"``) or of ``info[objective]`` at
    each episode's last step. ``env`` is reseeded with ``seed`` first, so every call plays the same episodes.
    """
    values: list[float] = []

    def record(local: dict[str, Any], _globals: dict[str, Any]) -> None:
        if objective != RETURN and local["done"]:
            info = local["info"]
            if objective not in info:
                raise ValueError(
                    f"objective {objective!r} is not a key of the info at an episode's end; its keys: {sorted(info)}"
                )
            values.append(float(info[objective]))

    env.seed(seed)
    returns, _ = evaluate_policy(
        model, env, n_eval_episodes=n_episodes, deterministic=True, return_episode_rewards=True, warn=False, callback=record
    )
    return float(np.mean(returns if objective == RETURN else values))


class TrialEvaluation(GreedyCheckpoints):
    """
    Every ``eval_every`` environment steps (:class:`~sb3_aac.common.checkpoints.GreedyCheckpoints`): the greedy score
    on the fixed evaluation episodes, reported to ``trial`` as intermediate value number ``first_report``,
    ``first_report + 1``, ... Training stops (``learn`` returns) when
    the trial's pruner says so (then :attr:`pruned` is True) or when ``stop`` is set (Ctrl-C).

    :param trial: the Optuna trial reported to
    :param eval_env: the environment evaluated on
    :param eval_every: environment steps (summed over lanes) between evaluations
    :param n_episodes: evaluation episodes
    :param seed: the evaluation episodes' seed
    :param objective: ``"return"`` or an info key (see :func:`greedy_score`)
    :param stop: training stops at the next step once this is set
    :param first_report: the step number of the first report (a trial training several seeds continues the count)
    """

    def __init__(
        self,
        trial: optuna.Trial,
        eval_env: VecEnv,
        eval_every: int,
        n_episodes: int,
        seed: int,
        objective: str,
        stop: threading.Event,
        first_report: int = 0,
    ):
        super().__init__(eval_every, lambda model: greedy_score(model, eval_env, n_episodes, seed, objective))
        self.trial, self.eval_env, self.eval_every = trial, eval_env, eval_every
        self.n_episodes, self.seed, self.objective, self.stop = n_episodes, seed, objective, stop
        self.reports = first_report
        self.pruned = False

    def _on_step(self) -> bool:
        if self.stop.is_set():
            return False
        return super()._on_step()

    def on_checkpoint(self, score: float) -> bool:
        self.trial.report(score, self.reports)
        self.reports += 1
        self.pruned = self.trial.should_prune()
        return not self.pruned
