"""
A tuning study: TPE samples hyperparameters, each trial trains and is scored by greedy evaluations, the median pruner
stops trials that fall behind. Trials are run ask-and-tell, so Ctrl-C ends the running trial cleanly.
"""

from __future__ import annotations

import signal
import threading
import warnings
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from typing import Any, Protocol

import numpy as np
import optuna
from optuna.pruners import MedianPruner
from optuna.samplers import TPESampler
from optuna.storages import BaseStorage
from optuna.trial import TrialState
from stable_baselines3.common.vec_env import VecEnv

from sb3_aac.tune.evaluation import RETURN, TrialEvaluation, greedy_score
from sb3_aac.tune.search_spaces import ALGORITHMS, search_space

# Trials that count towards a study's budget; a failed or interrupted trial does not.
FINISHED = (TrialState.COMPLETE, TrialState.PRUNED)
# The evaluation episodes' seed is the training seed plus this, as in ``sb3-aac train``'s final evaluation.
EVAL_SEED_OFFSET = 10_000

# ``(n_envs, seed) -> VecEnv``: how trials make their training and evaluation environments.
EnvFactory = Callable[[int, int], VecEnv]
# ``(trial, stop) -> value``: what a trial does (``stop`` is set by Ctrl-C; raise TrialInterrupted after it).
Objective = Callable[[optuna.Trial, threading.Event], float]


class StudyDefinition(Protocol):
    """What :func:`load_study` needs of a study's settings (:class:`TuneSettings`, a suite's settings)."""

    @property
    def seed(self) -> int: ...

    @property
    def startup_trials(self) -> int: ...

    @property
    def warmup_evaluations(self) -> int: ...

    def identity(self) -> dict[str, str]: ...


def fixed_names(fixed: Mapping[str, Any]) -> set[str]:
    """The names in ``fixed`` (constructor keyword arguments, ``policy_kwargs`` nested), policy arguments included."""
    return {name for name in fixed if name != "policy_kwargs"} | set(fixed.get("policy_kwargs") or {})


def trial_kwargs(algo: str, policy: str, fixed: Mapping[str, Any], params: Mapping[str, Any]) -> dict[str, Any]:
    """The algorithm's keyword arguments for a trial's ``params``: the ``fixed`` ones, then the sampled ones."""
    sampled = search_space(algo, policy).to_kwargs(params)
    policy_kwargs = {**(fixed.get("policy_kwargs") or {}), **sampled.pop("policy_kwargs", {})}
    return {**fixed, **sampled, **({"policy_kwargs": policy_kwargs} if policy_kwargs else {})}


@dataclass(frozen=True)
class TuneSettings:
    """
    What every trial of a study does; a study remembers these and refuses to resume with others.

    :param env_id: the environment's name (made by the factory given to :func:`run_study`)
    :param policy: the policy (a key of the algorithm's search spaces)
    :param algo: the algorithm (a key of :data:`~sb3_aac.tune.search_spaces.ALGORITHMS`)
    :param timesteps: training steps per seed
    :param eval_every: environment steps between greedy evaluations reported to the pruner
    :param eval_episodes: episodes of each greedy evaluation (the same episodes every time)
    :param n_envs: environments stepped side by side in training (and evaluation, at most ``eval_episodes``)
    :param seed: the training seed of a trial's first run; the sampler's seed too
    :param seeds_per_trial: runs per trial (seeds ``seed, seed + 1, ...``); the trial's value is their mean
    :param objective: ``"return"`` or the info key scored at each episode's end (e.g. ``"distance"``)
    :param fixed: constructor keyword arguments fixed for every trial (not searched), ``policy_kwargs`` nested
    :param startup_trials: trials sampled at random before TPE models the results, and before the pruner prunes
    :param warmup_evaluations: evaluations of a trial before the pruner may stop it
    """

    env_id: str
    policy: str
    algo: str = "sarsa_aac"
    timesteps: int = 100_000
    eval_every: int = 20_000
    eval_episodes: int = 100
    n_envs: int = 16
    seed: int = 0
    seeds_per_trial: int = 1
    objective: str = RETURN
    fixed: Mapping[str, Any] = field(default_factory=dict)
    startup_trials: int = 5
    warmup_evaluations: int = 1

    def __post_init__(self) -> None:
        search_space(self.algo, self.policy)  # a ValueError names the known ones
        for name in ("timesteps", "eval_every", "eval_episodes", "n_envs", "seeds_per_trial", "startup_trials"):
            if not getattr(self, name) >= 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if self.seed < 0 or self.warmup_evaluations < 0:
            raise ValueError(f"seed and warmup_evaluations must be >= 0, got {self.seed} and {self.warmup_evaluations}")

    def fixed_names(self) -> set[str]:
        """The names in :attr:`fixed`, policy arguments included (they are not searched)."""
        return fixed_names(self.fixed)

    def kwargs(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """The algorithm's keyword arguments for a trial's ``params`` (:func:`trial_kwargs`)."""
        return trial_kwargs(self.algo, self.policy, self.fixed, params)

    def identity(self) -> dict[str, str]:
        """The settings as study user attributes (strings), compared when a study is resumed."""
        return {name: repr(value) for name, value in asdict(self).items()}


@dataclass(frozen=True)
class StudyOutcome:
    """What a call of :func:`run_study` left: the study, and whether Ctrl-C ended the call."""

    study: optuna.Study
    interrupted: bool


class TrialInterrupted(Exception):
    """Ctrl-C arrived during a trial: its training stopped and it is recorded as failed."""


def load_study(storage: BaseStorage, study_name: str, settings: StudyDefinition) -> optuna.Study:
    """
    The study ``study_name`` in ``storage``, created if missing, with TPE and the median pruner.

    :raises ValueError: if the stored study was made with other settings (other env, policy, budgets...)
    """
    study = optuna.create_study(
        storage=storage,
        study_name=study_name,
        direction="maximize",
        load_if_exists=True,
        pruner=median_pruner(settings.startup_trials, settings.warmup_evaluations),
    )
    stored = study.user_attrs.get("settings")
    if stored is None:
        study.set_user_attr("settings", settings.identity())
    elif stored != settings.identity():
        differ = sorted(name for name, value in settings.identity().items() if stored.get(name) != value)
        was = ", ".join(f"{name}={stored.get(name)}" for name in differ)
        raise ValueError(f"study {study_name!r} was made with {was}; resume it with those settings or give another study name")
    # Seeded by the trials so far, so that a resumed study does not repeat its first random trials.
    study.sampler = tpe_sampler(settings.startup_trials, settings.seed + len(study.trials))
    return study


def median_pruner(startup_trials: int, warmup_evaluations: int) -> MedianPruner:
    """The pruner of every study: stop a trial whose evaluation falls below the median of the trials before it at
    the same evaluation, once ``startup_trials`` trials finished and after ``warmup_evaluations`` evaluations."""
    return MedianPruner(n_startup_trials=startup_trials, n_warmup_steps=warmup_evaluations)


def tpe_sampler(startup_trials: int, seed: int) -> TPESampler:
    """The sampler of every study: ``startup_trials`` random trials, then multivariate TPE; the constant liar keeps
    trials running side by side (processes or machines sharing the storage) from sampling the same point."""
    with warnings.catch_warnings():  # multivariate and constant_liar are "experimental" (stable since Optuna 2.2 and 2.8)
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        return TPESampler(n_startup_trials=startup_trials, seed=seed, multivariate=True, constant_liar=True)


def finished_trials(study: optuna.Study) -> int:
    """Trials that count towards the budget: complete or pruned (in every process sharing the storage)."""
    return len(study.get_trials(deepcopy=False, states=FINISHED))


def run_study(
    study: optuna.Study,
    settings: TuneSettings,
    make_env: EnvFactory,
    n_trials: int,
    on_trial: Callable[[optuna.trial.FrozenTrial], None] = lambda trial: None,
) -> StudyOutcome:
    """:func:`run_trials` with trials that train on ``make_env``'s env as ``settings`` say, scored by greedy
    evaluations."""
    return run_trials(study, lambda trial, stop: _train_and_score(trial, settings, make_env, stop), n_trials, on_trial)


def run_trials(
    study: optuna.Study,
    objective: Objective,
    n_trials: int,
    on_trial: Callable[[optuna.trial.FrozenTrial], None] = lambda trial: None,
) -> StudyOutcome:
    """
    Run trials of ``objective`` until the study holds ``n_trials`` finished ones (so the same call resumes an
    interrupted study).

    The first Ctrl-C (SIGINT) sets the objective's ``stop`` event; the objective then raises
    :class:`TrialInterrupted`, the trial is recorded as failed and this returns; a second Ctrl-C raises
    ``KeyboardInterrupt`` at once. A trial whose training diverges (``FloatingPointError``) is pruned, the error in its
    user attribute ``"diverged"``. ``on_trial`` is called with each trial this call ends.
    """
    stop = threading.Event()
    with _stop_on_sigint(stop):
        while not stop.is_set() and finished_trials(study) < n_trials:
            trial = study.ask()
            try:
                value = objective(trial, stop)
            except optuna.TrialPruned:
                study.tell(trial, state=TrialState.PRUNED)
            except FloatingPointError as error:
                trial.set_user_attr("diverged", str(error))
                study.tell(trial, state=TrialState.PRUNED)
            except TrialInterrupted:
                trial.set_user_attr("interrupted", True)
                study.tell(trial, state=TrialState.FAIL)
            except BaseException:
                study.tell(trial, state=TrialState.FAIL)
                raise
            else:
                study.tell(trial, value)
            on_trial(study.trials[trial.number])
    return StudyOutcome(study, stop.is_set())


def _train_and_score(trial: optuna.Trial, settings: TuneSettings, make_env: EnvFactory, stop: threading.Event) -> float:
    """
    Train one run per seed with the trial's hyperparameters; the mean greedy score after training (evaluated again
    even after a periodic evaluation at the last step: callbacks run before that step's update).
    """
    params = search_space(settings.algo, settings.policy).sample(trial, settings.fixed_names())
    kwargs = settings.kwargs(params)
    scores = []
    reports = 0
    for seed in range(settings.seed, settings.seed + settings.seeds_per_trial):
        env = make_env(settings.n_envs, seed)
        eval_env = make_env(min(settings.n_envs, settings.eval_episodes), seed + EVAL_SEED_OFFSET)
        try:
            model = ALGORITHMS[settings.algo](settings.policy, env, seed=seed, **kwargs)
            evaluation = TrialEvaluation(
                trial,
                eval_env,
                settings.eval_every,
                settings.eval_episodes,
                seed + EVAL_SEED_OFFSET,
                settings.objective,
                stop,
                reports,
            )
            model.learn(settings.timesteps, callback=evaluation)
            if stop.is_set():
                raise TrialInterrupted
            if evaluation.pruned:
                raise optuna.TrialPruned(f"pruned at evaluation {evaluation.reports - 1}")
            reports = evaluation.reports
            scores.append(greedy_score(model, eval_env, settings.eval_episodes, seed + EVAL_SEED_OFFSET, settings.objective))
        finally:
            env.close()
            eval_env.close()
    trial.set_user_attr("scores", scores)
    return float(np.mean(scores))


@contextmanager
def _stop_on_sigint(stop: threading.Event) -> Iterator[None]:
    """While inside: the first SIGINT sets ``stop`` and restores the previous handler (so a second one interrupts)."""
    if threading.current_thread() is not threading.main_thread():
        yield  # signal handlers can only be set from the main thread
        return
    previous = signal.getsignal(signal.SIGINT)

    def handle(signum: int, frame: Any) -> None:
        stop.set()
        signal.signal(signal.SIGINT, previous)

    signal.signal(signal.SIGINT, handle)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
