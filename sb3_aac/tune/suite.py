"""
A multi-task study: every trial trains the algorithm with the trial's settings on each task of a suite in turn, and
is scored by the mean over the tasks of the greedy score normalised between the task's floor and reference.

A task's normalised score is ``(score - floor) / (reference - floor)`` clipped to [0, 1]: 0 at (or below) the floor,
1 at (or above) the reference. After task ``i`` the mean normalised score of tasks ``0..i`` is reported to the median
pruner as intermediate value ``i``, so a trial that falls behind the others' mean over the same tasks stops there.
A trial keeps the raw and the normalised scores of the tasks it trained on as its user attributes ``"scores"`` and
``"normalised"`` (``{task name: value}``). The sampler, the pruner, the storage, Ctrl-C and divergence are the
single-env study's (:mod:`sb3_aac.tune.study`). The tasks' envs and scores are given as functions, so this module
imports no env package (the repository's suite is ``benchmarks/suite.py``).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import optuna
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback

from sb3_aac.tune.search_spaces import ALGORITHMS, search_space
from sb3_aac.tune.study import EnvFactory, Objective, TrialInterrupted, fixed_names, trial_kwargs


def normalised_score(score: float, floor: float, reference: float) -> float:
    """``(score - floor) / (reference - floor)`` clipped to [0, 1]: 0 at or below ``floor``, 1 at or above
    ``reference``."""
    return float(np.clip((score - floor) / (reference - floor), 0.0, 1.0))


@dataclass(frozen=True)
class SuiteTask:
    """
    One task of a suite: an env, a training budget and a greedy score with its floor and reference.

    :param name: the task's name (the key of its scores)
    :param make_env: ``(n_envs, seed) -> VecEnv`` of the training env
    :param n_envs: lanes trained on
    :param timesteps: training env steps (summed over lanes)
    :param score: the greedy score of a trained model on the task's tuning episodes
    :param floor: the score normalised to 0
    :param reference: the score normalised to 1 (above ``floor``)
    :param fixed: constructor keyword arguments of this task (e.g. ``info_keywords=()``), before the trial's
    """

    name: str
    make_env: EnvFactory = field(compare=False, repr=False)
    n_envs: int
    timesteps: int
    score: Callable[[BaseAlgorithm], float] = field(compare=False, repr=False)
    floor: float
    reference: float
    fixed: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not (self.n_envs >= 1 and self.timesteps >= 1):
            raise ValueError(f"task {self.name!r}: n_envs and timesteps must be >= 1, got {self.n_envs}, {self.timesteps}")
        if not (np.isfinite(self.floor) and np.isfinite(self.reference) and self.reference > self.floor):
            raise ValueError(
                f"task {self.name!r}: the reference must be finite and above the floor, got floor {self.floor}, "
                f"reference {self.reference}"
            )

    def normalised(self, score: float) -> float:
        """``score`` mapped to [0, 1] (:func:`normalised_score`)."""
        return normalised_score(score, self.floor, self.reference)


@dataclass(frozen=True)
class SuiteSettings:
    """
    What every trial of a multi-task study does; a study remembers these and refuses to resume with others.

    :param suite: the suite's name
    :param tasks: the tasks, trained in this order (put the ones that tell trials apart first: pruning acts after each)
    :param policy: the policy (a key of the algorithm's search spaces)
    :param algo: the algorithm (a key of :data:`~sb3_aac.tune.search_spaces.ALGORITHMS`)
    :param seed: the training seed of every task of every trial; the sampler's seed too
    :param fixed: constructor keyword arguments fixed for every trial and task (not searched), ``policy_kwargs`` nested
    :param startup_trials: trials sampled at random before TPE models the results, and before the pruner prunes
    :param warmup_evaluations: tasks of a trial before the pruner may stop it
    """

    suite: str
    tasks: tuple[SuiteTask, ...]
    policy: str
    algo: str = "sarsa_aac"
    seed: int = 0
    fixed: Mapping[str, Any] = field(default_factory=dict)
    startup_trials: int = 5
    warmup_evaluations: int = 1

    def __post_init__(self) -> None:
        search_space(self.algo, self.policy)  # a ValueError names the known ones
        names = [task.name for task in self.tasks]
        if not names or len(set(names)) != len(names):
            raise ValueError(f"a suite needs at least one task and distinct task names, got {names}")
        if self.startup_trials < 1 or self.seed < 0 or self.warmup_evaluations < 0:
            raise ValueError(
                f"startup_trials must be >= 1, seed and warmup_evaluations >= 0, got {self.startup_trials}, "
                f"{self.seed}, {self.warmup_evaluations}"
            )

    def fixed_names(self) -> set[str]:
        """The names in :attr:`fixed`, policy arguments included (they are not searched)."""
        return fixed_names(self.fixed)

    def kwargs(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """The algorithm's keyword arguments for a trial's ``params`` (:func:`~sb3_aac.tune.study.trial_kwargs`)."""
        return trial_kwargs(self.algo, self.policy, self.fixed, params)

    def identity(self) -> dict[str, str]:
        """The settings as study user attributes (strings), compared when a study is resumed; a task is its name,
        lanes, budget, floor, reference and fixed arguments."""
        return {
            "suite": self.suite,
            "tasks": repr(self.tasks),
            "policy": self.policy,
            "algo": self.algo,
            "seed": repr(self.seed),
            "fixed": repr(dict(self.fixed)),
            "startup_trials": repr(self.startup_trials),
            "warmup_evaluations": repr(self.warmup_evaluations),
        }


class StopOnEvent(BaseCallback):
    """Stops training (``learn`` returns) at the next step once ``stop`` is set."""

    def __init__(self, stop: threading.Event):
        super().__init__()
        self.stop = stop

    def _on_step(self) -> bool:
        return not self.stop.is_set()


def suite_objective(settings: SuiteSettings) -> Objective:
    """The objective of :func:`~sb3_aac.tune.study.run_trials` for a multi-task study (module docstring): the trial's
    mean normalised score over the suite's tasks."""

    def objective(trial: optuna.Trial, stop: threading.Event) -> float:
        kwargs = settings.kwargs(search_space(settings.algo, settings.policy).sample(trial, settings.fixed_names()))
        scores: dict[str, float] = {}
        normalised: dict[str, float] = {}
        for step, task in enumerate(settings.tasks):
            env = task.make_env(task.n_envs, settings.seed)
            try:
                model = ALGORITHMS[settings.algo](settings.policy, env, seed=settings.seed, **{**task.fixed, **kwargs})
                model.learn(task.timesteps, callback=StopOnEvent(stop))
                if stop.is_set():
                    raise TrialInterrupted
                scores[task.name] = task.score(model)
            finally:
                env.close()
            normalised[task.name] = task.normalised(scores[task.name])
            trial.set_user_attr("scores", scores)
            trial.set_user_attr("normalised", normalised)
            trial.report(float(np.mean(list(normalised.values()))), step)
            if trial.should_prune():
                raise optuna.TrialPruned(f"pruned after task {task.name!r}")
        return float(np.mean(list(normalised.values())))

    return objective
