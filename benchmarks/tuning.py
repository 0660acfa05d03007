"""The runner's tuning stage (``python -m benchmarks.run --tune --preset P``): one Optuna study per tuned learner
and env of the preset, every study of the same size, and the best settings written as
``hyperparams/tuned/<env id>/<learner>.yml`` with the study's journal file beside it.

Size (:func:`benchmarks.presets.tuning_spec`): ``trials`` finished trials (complete or pruned) x ``env_steps`` env
steps of training x ``seeds`` tuning seeds per trial, the trial's value the mean over its seeds of the greedy score
(:func:`benchmarks.domains.evaluate`, the env's metric) after training. Sampler and pruner are ``sb3-aac tune``'s
(:func:`sb3_aac.tune.study.tpe_sampler`, :func:`~sb3_aac.tune.study.median_pruner`: multivariate TPE after
:data:`STARTUP_TRIALS` random trials; the median rule on ``evaluations`` greedy evaluations during training, spaced
``env_steps / evaluations`` apart). The spaces are :mod:`benchmarks.tuned`'s: rl-zoo3's samplers for SB3's
algorithms through the grid's action wrappers, sb3-aac's for SarsaAAC, P-DQN, MP-DQN and HybridPPO.

Cost: ``python -m benchmarks.run --preset P --estimate`` prints the stage's core-hours beside the grid's
(:func:`benchmarks.cost.trial_seconds`: every trial counted unpruned, an upper bound).

Seeds: a trial trains with seeds :data:`TUNE_SEED`, ``TUNE_SEED + 1``, ... and is scored on the episodes of set
:data:`TUNE_EVAL_SEED`; the grid trains with seeds 0-9 and is scored on sets 10,000 (curves) and 20,000 (final), so
no episode or seed of the tuning is one the benchmark's verdicts are computed on.

Storage: ``--storage`` names one Optuna storage all studies share (an Optuna journal file, for processes on one
machine, or a database URL such as ``postgresql://user@host/db``, for machines sharing the studies); without it each
study is its own journal file beside its tuned file. A finished study is copied into that journal file either way, so
the repository carries every trial. Trials run one per task: in a local process pool (``--workers``) or as Ray tasks
(``--engine ray``), each task asking the shared storage for its trial, so the same command on several machines
(with one database URL) works on the same studies. A trial records its host and process id; a rerun marks the
trials of processes that died on this host as failed and runs trials until every study holds its ``trials``
finished ones, so an interrupted stage resumes with the same command and keeps every finished trial.
"""

from __future__ import annotations

import contextlib
import fnmatch
import os
import socket
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import optuna
import torch as th
import yaml
from optuna.storages import BaseStorage, JournalStorage
from optuna.storages.journal import JournalFileBackend
from optuna.trial import TrialState
from stable_baselines3.common.callbacks import BaseCallback

from benchmarks import domains
from benchmarks.models import build_model
from benchmarks.presets import ENV_SHORT, Cell, tuning_spec
from benchmarks.tuned import learner_name, sample_kwargs, tunable, tuned_dir
from benchmarks.workers import run_in_pool, worker_env
from sb3_aac.common.output_files import pid_alive, replaced_atomically
from sb3_aac.tune.storage import open_storage
from sb3_aac.tune.study import FINISHED, median_pruner, tpe_sampler

TUNE_SEED = 1_000  # a trial's training seeds: TUNE_SEED, TUNE_SEED + 1, ... (the grid's are 0-9)
TUNE_EVAL_SEED = 40_000  # the trials' evaluation episodes (the grid's sets are 10,000, 20,000 and 30,000)
STARTUP_TRIALS = 5  # random trials before TPE, and finished trials before the pruner prunes
WARMUP_EVALUATIONS = 1  # a trial's first evaluation never prunes it
STUDY_ATTR = "benchmark_study"  # the study's user attribute holding its definition (checked when resumed)
JOURNAL_SUFFIX = ".journal"


@dataclass(frozen=True)
class StudySpec:
    """One study of the tuning stage: a learner (algorithm and grid config) on an env, and its size."""

    env_id: str
    algo: str
    config: str
    trials: int
    env_steps: int
    seeds: int
    evaluations: int
    eval_episodes: int

    @property
    def name(self) -> str:
        return f"{ENV_SHORT.get(self.env_id, self.env_id)}__{learner_name(self.algo, self.config)}"

    @property
    def eval_every(self) -> int:
        """Env steps between the pruning evaluations."""
        return max(1, self.env_steps // self.evaluations)

    def identity(self) -> dict[str, str]:
        """What a resumed study must match (all but ``trials``: a study may be given more trials later)."""
        return {k: repr(v) for k, v in asdict(self).items() if k != "trials"} | {
            "tune_seed": repr(TUNE_SEED),
            "tune_eval_seed": repr(TUNE_EVAL_SEED),
        }

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def plan_studies(preset: str | dict[str, Any], trials: int | None = None, only: str | None = None) -> list[StudySpec]:
    """The studies of a preset's tuning stage (``trials`` replaces the preset's), those whose name matches one of the
    comma-separated glob patterns ``only`` (a plain word matches as a substring).

    :raises ValueError: for a budget below 1, a learner without a search space, or ``only`` matching no study
    """
    spec = tuning_spec(preset)
    trials = spec["trials"] if trials is None else trials
    for key, value in (
        ("trials", trials),
        ("seeds", spec["seeds"]),
        ("evaluations", spec["evaluations"]),
        ("eval_episodes", spec["eval_episodes"]),
        *(("env_steps", v) for v in spec["env_steps"].values()),
    ):
        if not (isinstance(value, int) and value >= 1):
            raise ValueError(f"the tuning budget's {key} must be a whole number >= 1, got {value!r}")
    studies = []
    for env_id, learners in spec["learners"].items():
        for algo, config in learners:
            if not tunable(algo, config):
                raise ValueError(f"{algo} ({config}) has no search space (benchmarks.tuned) and cannot be tuned")
            studies.append(
                StudySpec(
                    env_id,
                    algo,
                    config,
                    trials,
                    spec["env_steps"][env_id],
                    spec["seeds"],
                    spec["evaluations"],
                    spec["eval_episodes"],
                )
            )
    if not only:
        return studies
    globs = [p if any(c in p for c in "*?[") else f"*{p}*" for p in (s.strip() for s in only.split(",")) if p]
    chosen = [s for s in studies if any(fnmatch.fnmatchcase(s.name, g) for g in globs)]
    if not chosen:
        raise ValueError(f"--only {only!r} matches none of the studies {[s.name for s in studies]}")
    return chosen


def storage_spec(study: StudySpec, storage: str | None, folder: Path) -> str:
    """Where ``study`` lives: ``storage`` (a journal file made absolute, for tasks elsewhere, or a URL), or its own
    journal file beside its tuned file."""
    if storage is None:
        return str((folder / study.env_id / f"{learner_name(study.algo, study.config)}{JOURNAL_SUFFIX}").resolve())
    return storage if "://" in storage else str(Path(storage).resolve())


def open_study(storage: BaseStorage, study: StudySpec, create: bool = False) -> optuna.Study:
    """The study in ``storage`` with the stage's sampler and pruner (created if ``create`` and missing).

    :raises ValueError: if the stored study was made with another definition (env steps, seeds, evaluations...)
    """
    pruner = median_pruner(STARTUP_TRIALS, WARMUP_EVALUATIONS)
    if create:
        loaded = optuna.create_study(
            storage=storage, study_name=study.name, direction="maximize", load_if_exists=True, pruner=pruner
        )
    else:
        loaded = optuna.load_study(study_name=study.name, storage=storage, pruner=pruner)
    stored = loaded.user_attrs.get(STUDY_ATTR)
    if stored is None:
        loaded.set_user_attr(STUDY_ATTR, study.identity())
    elif stored != study.identity():
        differ = ", ".join(f"{k}={stored.get(k)} (now {v})" for k, v in study.identity().items() if stored.get(k) != v)
        raise ValueError(f"study {study.name!r} was made with {differ}; give another --storage or remove the old study")
    # Seeded by the trials so far and the process: a resumed study samples anew, and two processes asking at the same
    # moment do not draw the same random trial (the constant liar keeps them apart once TPE models the results).
    loaded.sampler = tpe_sampler(STARTUP_TRIALS, (TUNE_SEED + len(loaded.trials) + 7919 * os.getpid()) % 2**32)
    return loaded


def fail_abandoned_trials(study: optuna.Study) -> list[int]:
    """Mark as failed the running trials of processes of this host that no longer exist (a killed run's); their
    numbers. Trials of live processes, and of other hosts, stay running."""
    host = socket.gethostname()
    abandoned = []
    for trial in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        attrs = trial.user_attrs
        if attrs.get("host") == host and isinstance(attrs.get("pid"), int) and not pid_alive(attrs["pid"]):
            with contextlib.suppress(RuntimeError, ValueError):  # another process marked it first
                study._storage.set_trial_user_attr(trial._trial_id, "abandoned", True)
                study._storage.set_trial_state_values(trial._trial_id, TrialState.FAIL)
                abandoned.append(trial.number)
    return abandoned


def finished_count(study: optuna.Study) -> int:
    return len(study.get_trials(deepcopy=False, states=FINISHED))


class TrialReport(BaseCallback):
    """Every ``eval_every`` env steps: the greedy score on the tuning evaluation set, reported to ``trial`` as
    intermediate value ``first_report``, ``first_report + 1``, ...; training stops when the pruner says so."""

    def __init__(self, trial: optuna.Trial, policy: Any, study: StudySpec, first_report: int):
        super().__init__()
        self.trial, self.policy, self.study = trial, policy, study
        self.reports = first_report
        self.pruned = False
        self._next = study.eval_every

    def _on_step(self) -> bool:
        if self.num_timesteps < self._next:
            return True
        self._next += self.study.eval_every
        self.trial.report(score(self.study, self.policy), self.reports)
        self.reports += 1
        self.pruned = self.trial.should_prune()
        return not self.pruned


def score(study: StudySpec, policy: Any) -> float:
    """The greedy score of ``policy`` on the tuning evaluation set (the env's metric)."""
    summary = domains.evaluate(study.env_id, policy, study.eval_episodes, TUNE_EVAL_SEED)
    return float(summary[domains.metric(study.env_id)])


def _train_trial(trial: optuna.Trial, study: StudySpec) -> float:
    """Train the trial's settings once per tuning seed; the mean final greedy score. Raises ``TrialPruned``."""
    kwargs = sample_kwargs(trial, study.env_id, study.algo, study.config)
    scores, reports = [], 0
    for seed in range(TUNE_SEED, TUNE_SEED + study.seeds):
        model, policy, _ = build_model(Cell(study.env_id, study.algo, study.config, seed, study.env_steps, overrides=kwargs))
        report = TrialReport(trial, policy, study, reports)
        try:
            model.learn(study.env_steps, callback=report)
        except FloatingPointError as error:
            trial.set_user_attr("diverged", str(error))
            raise optuna.TrialPruned(f"training diverged: {error}") from None
        if report.pruned:
            raise optuna.TrialPruned(f"pruned at evaluation {report.reports - 1}")
        reports = report.reports
        scores.append(score(study, policy))
    trial.set_user_attr("scores", scores)
    return float(np.mean(scores))


def run_trial(study_data: dict[str, Any], storage: str) -> tuple[str, str, str]:
    """Ask the study for one trial, train and score it, tell the result; runs in a worker process or Ray task.

    :return: the study's name, the outcome (``"complete"``, ``"pruned"``, ``"failed"`` or ``"skipped"``: the study
        already held its trials) and a line saying what happened (the traceback for a failure)
    """
    th.set_num_threads(1)
    study = StudySpec(**study_data)
    loaded = open_study(open_storage(storage), study)
    if finished_count(loaded) >= study.trials:
        return study.name, "skipped", "the study holds its trials"
    trial = loaded.ask()
    trial.set_user_attr("host", socket.gethostname())
    trial.set_user_attr("pid", os.getpid())
    start = time.perf_counter()
    try:
        value = _train_trial(trial, study)
    except optuna.TrialPruned as pruned:
        loaded.tell(trial, state=TrialState.PRUNED)
        return study.name, "pruned", f"trial {trial.number}: {pruned} ({time.perf_counter() - start:.0f} s)"
    except Exception:
        text = traceback.format_exc()
        trial.set_user_attr("error", text.strip().splitlines()[-1])
        loaded.tell(trial, state=TrialState.FAIL)
        return study.name, "failed", f"trial {trial.number}: {text}"
    loaded.tell(trial, value)
    return study.name, "complete", f"trial {trial.number}: {value:.4g} ({time.perf_counter() - start:.0f} s)"


Task = tuple[dict[str, Any], str]  # run_trial's arguments
Report = Callable[[str, str, str], None]


def _run_local(tasks: Sequence[Task], workers: int, report: Report) -> None:
    run_in_pool(run_trial, tasks, workers, report)


def _run_ray(tasks: Sequence[Task], engine: Any, report: Report) -> None:
    """One Ray task (one CPU) per trial, on the engine's cluster (:class:`benchmarks.engines.RayEngine`)."""
    import ray  # optional (sb3-aac[distributed]): imported only when trials run on Ray

    with engine.connected():
        remote = ray.remote(run_trial).options(
            num_cpus=1,
            max_retries=engine.max_retries,
            retry_exceptions=False,
            runtime_env={"env_vars": worker_env()},
        )
        pending = {remote.remote(*task): task for task in tasks}
        try:
            while pending:
                finished, _ = ray.wait(list(pending), num_returns=1)
                task = pending.pop(finished[0])
                try:
                    report(*ray.get(finished[0]))
                except ray.exceptions.RayError as error:
                    report(StudySpec(**task[0]).name, "failed", f"Ray could not run the trial: {error}")
        finally:
            for ref in pending:
                with contextlib.suppress(Exception):
                    ray.cancel(ref, force=True)


def prepare(studies: Sequence[StudySpec], storage: str | None, folder: Path) -> dict[str, str]:
    """Open every study's storage and create or check its study, before any trial runs; the storage of each study.

    :raises ValueError: one line per problem (an unwritable or damaged storage, an unreachable database, a stored
        study of another definition)
    """
    specs, problems, opened = {}, [], {}
    for study in studies:
        spec = storage_spec(study, storage, folder)
        try:
            if spec not in opened:
                opened[spec] = open_storage(spec)
            loaded = open_study(opened[spec], study, create=True)
            fail_abandoned_trials(loaded)
        except ValueError as error:
            problems.append(str(error))
            continue
        specs[study.name] = spec
    if problems:
        raise ValueError("; ".join(dict.fromkeys(problems)))
    return specs


def run_tuning(
    studies: Sequence[StudySpec],
    storage: str | None = None,
    folder: Path | None = None,
    workers: int = 2,
    engine: Any = None,
    progress: bool = True,
) -> dict[str, list[str]]:
    """Run trials until every study holds its ``trials`` finished ones, then write each study's tuned file and
    journal; returns the study names ``done`` (tuned file written) and ``failed`` (trials kept failing).

    ``engine``: a :class:`benchmarks.engines.RayEngine` (one Ray task per trial), or None for a local process pool
    of ``workers`` (1: in this process). Rounds of trials are run until the studies are full; a round in which no
    trial of a study finishes ends that study's attempts (its last error is printed).
    """
    folder = Path(folder or tuned_dir())
    specs = prepare(studies, storage, folder)
    status: dict[str, list[str]] = {"done": [], "failed": []}
    last_error: dict[str, str] = {}
    todo = list(studies)

    def report(name: str, outcome: str, text: str) -> None:
        if outcome == "failed":
            last_error[name] = text
        if progress and outcome != "skipped":
            print(f"{name}: {outcome} {text.strip().splitlines()[-1] if outcome == 'failed' else text}", flush=True)

    while todo:
        tasks: list[Task] = []
        before = {}
        for study in todo:
            loaded = open_study(open_storage(specs[study.name]), study)
            running = len(loaded.get_trials(deepcopy=False, states=(TrialState.RUNNING,)))
            before[study.name] = finished_count(loaded)
            tasks += [(study.to_dict(), specs[study.name])] * max(0, study.trials - before[study.name] - running)
        if tasks:
            (_run_ray(tasks, engine, report) if engine is not None else _run_local(tasks, workers, report))
        remaining = []
        for study in todo:
            loaded = open_study(open_storage(specs[study.name]), study)
            finished = finished_count(loaded)
            if finished >= study.trials and not loaded.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)):
                status["failed"].append(study.name)  # every trial pruned: no best settings
                if progress:
                    print(f"{study.name}: all {finished} trials were pruned; no tuned settings written")
            elif finished >= study.trials:
                write_tuned(loaded, study, specs[study.name], folder)
                status["done"].append(study.name)
            elif finished > before[study.name] or not tasks:
                remaining.append(study)  # progress (or trials of other processes still running): another round
            else:
                status["failed"].append(study.name)
                if progress:
                    print(f"{study.name}: no trial finished in a round; last error:\n{last_error.get(study.name, '?')}")
        if remaining and not tasks:
            time.sleep(5.0)  # every missing trial runs in another process: wait for them
        todo = remaining
    return status


def write_tuned(study: optuna.Study, spec: StudySpec, storage: str, folder: Path) -> Path:
    """The study's best settings as ``<folder>/<env id>/<learner>.yml``, and its trials in the journal file beside
    it (copied there when the study lives in another storage)."""
    path = folder / spec.env_id / f"{learner_name(spec.algo, spec.config)}.yml"
    journal = path.with_suffix(JOURNAL_SUFFIX)
    if storage != str(journal.resolve()):
        with replaced_atomically(journal) as tmp:
            tmp.unlink(missing_ok=True)
            optuna.copy_study(
                from_study_name=spec.name,
                from_storage=open_storage(storage),
                to_storage=JournalStorage(JournalFileBackend(str(tmp))),
                to_study_name=spec.name,
            )
    best = study.best_trial
    states = [t.state for t in study.get_trials(deepcopy=False)]
    record = {
        "env_id": spec.env_id,
        "algo": spec.algo,
        "config": spec.config,
        "study": spec.name,
        "journal": journal.name,
        "budget": {
            "trials": spec.trials,
            "env_steps": spec.env_steps,
            "seeds": spec.seeds,
            "evaluations": spec.evaluations,
            "eval_episodes": spec.eval_episodes,
            "tuning_seeds": list(range(TUNE_SEED, TUNE_SEED + spec.seeds)),
            "eval_seed": TUNE_EVAL_SEED,
        },
        "trials": {
            "complete": states.count(TrialState.COMPLETE),
            "pruned": states.count(TrialState.PRUNED),
            "failed": states.count(TrialState.FAIL),
        },
        "best": {"trial": best.number, "value": float(best.value) if best.value is not None else None},
        "params": dict(best.params),
    }
    header = (
        f"# The best of {spec.trials} trials of study {spec.name} ({spec.env_steps:,} env steps x {spec.seeds} tuning "
        f"seed(s) a trial); written by python -m benchmarks.run --tune. The grid's '{spec.config}-tuned' config reads "
        "'params' (Optuna's parameter names, turned into keyword arguments by benchmarks.tuned).\n"
    )
    with replaced_atomically(path) as tmp:
        tmp.write_text(header + yaml.safe_dump(record, sort_keys=False))
    return path
