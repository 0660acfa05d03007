"""
The task suite that chooses SarsaAAC's shipped defaults: a multi-task Optuna study (:mod:`sb3_aac.tune.suite`) whose
every trial trains on each task, and the check of its best settings against the defaults on fresh seeds.

    python -m benchmarks.suite tune --suite defaults --policy TilePolicy --trials 35 \\
        --storage hyperparams/tuned/suite-defaults/TilePolicy.journal
    python -m benchmarks.suite evaluate --suite defaults --policy TilePolicy --seeds 5 --out runs/defaults
    python -m benchmarks.suite evaluate --suite defaults --policy TilePolicy --seeds 5 --out runs/tuned \\
        --from-study hyperparams/tuned/suite-defaults/TilePolicy.journal [--tasks paper,v19]
    python -m benchmarks.suite compare runs/defaults runs/tuned
    python -m benchmarks.suite trials --suite defaults --policy TilePolicy   # every trial's per-task scores

Suites (:data:`SUITES`): ``defaults``, the budgets users spend on each task, 16 lanes each: the paper's env and v19
for 150k env steps (``DribbleVecEnv(16)``), ``NavigationEnv`` and CatchPoint-v0 for 300k, Platform-v0
(``SelectObservation``) for 20k; a full trial takes about 100 s on one idle core. Moving-v0 is left out: TilePolicy's
defaults make -1.18 after 300k steps (23 s), hardly above the random policy's -1.30, so at a budget of seconds it
tells trials apart by noise only. ``smoke``: the toy env for 2,000 steps, to try the commands in seconds.

Scores: each env's greedy metric (:func:`greedy_score`): metres dribbled, success share (NavigationEnv,
CatchPoint-v0), mean return (Platform-v0, the toy env). Normalisation (one definition of each end,
:func:`floor_policy` and :func:`reference_score`, both measured on the same episodes as the score): 0 is the uniform
random policy; 1 is the hand-coded dribbler on the dribbling envs (30.7 m and 25.4 m on the final episodes), the
scripted controller of ``hybrid_domains.baselines`` on Moving-v0 and CatchPoint-v0, and the metric's maximum on the
others (Platform-v0's return 1 reaches the goal; success share 1; the toy env's optimum return 10). A trial's value
is the mean normalised score over the tasks.

Seeds: trials train with seed :data:`benchmarks.tuning.TUNE_SEED` and are scored on 200 episodes of set
:data:`benchmarks.tuning.TUNE_EVAL_SEED`; ``evaluate`` trains with seeds 0, 1, ... and scores on 1,000 episodes of
the benchmark's final set (:data:`benchmarks.presets.FINAL_SEED`), so no seed or episode of the verdict was tuned on.
``compare`` prints per task the two means, Welch's test on the difference and the verdict: the second settings win
across the suite if their mean normalised score is higher and no task is significantly worse (p < 0.05).

The suite lives here and not behind ``sb3-aac tune``: its tasks are the benchmark's envs and references
(``robocup_dribble``, ``hybrid_domains``, Platform-v0, the hand-coded dribbler), which ``sb3_aac`` must not import.
"""

from __future__ import annotations

import argparse
import ast
import inspect
import json
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import optuna
import torch as th
from hybrid_domains.baselines import scripted_policy
from optuna.trial import FrozenTrial, TrialState
from robocup_dribble import ENV_PROFILES, DribbleEnv
from robocup_dribble.dribbler import HandCodedDribbler
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import VecEnv

from benchmarks import domains
from benchmarks.presets import FINAL_SEED
from benchmarks.tuning import TUNE_EVAL_SEED, TUNE_SEED
from sb3_aac import SarsaAAC
from sb3_aac.common.algorithms import hyperparameters, key_value
from sb3_aac.common.envs import NavigationEnv, ParameterizedTargetEnv
from sb3_aac.common.statistics import welch_test
from sb3_aac.tune.report import flat_settings, literal, print_trial
from sb3_aac.tune.search_spaces import policies, search_space
from sb3_aac.tune.storage import open_storage
from sb3_aac.tune.study import finished_trials, load_study, run_trials, trial_kwargs
from sb3_aac.tune.suite import SuiteSettings, SuiteTask, normalised_score, suite_objective

NAVIGATION = "NavigationEnv"  # sb3_aac.common.envs.NavigationEnv (no registered id)
TOY = "ParameterizedTargetEnv"  # sb3_aac.common.envs.ParameterizedTargetEnv, optimum return 10
TOY_OPTIMUM = 10.0
TUNE_EPISODES = 200  # greedy episodes scoring a trial's task
FINAL_EPISODES = 1000  # greedy episodes scoring an evaluation run (the benchmark's final evaluation)
SIGNIFICANCE = 0.05  # a task is significantly worse below this p-value of Welch's test
NO_INFO_KEYWORDS = {"info_keywords": ()}  # SarsaAAC's default logs the dribbling envs' info keys


@dataclass(frozen=True)
class Task:
    """A task of a suite: ``env_id`` trained on ``n_envs`` lanes for ``timesteps`` env steps."""

    name: str
    env_id: str
    n_envs: int
    timesteps: int
    fixed: dict[str, Any] = field(default_factory=dict)


SUITES: dict[str, tuple[Task, ...]] = {
    # Ordered so that pruning (from the third task on) has seen both dribbling profiles and the navigation task, and
    # the slowest task (Platform-v0, about 45 s a run) comes last.
    "defaults": (
        Task("paper", "RoboCupDribblePaper-v0", 16, 150_000),
        Task("nav", NAVIGATION, 16, 300_000, NO_INFO_KEYWORDS),
        Task("v19", "RoboCupDribble-v0", 16, 150_000),
        Task("catch", "CatchPoint-v0", 16, 300_000, NO_INFO_KEYWORDS),
        Task("platform", domains.PLATFORM_ID, 16, 20_000, NO_INFO_KEYWORDS),
    ),
    "smoke": (Task("toy", TOY, 4, 2_000),),
}
WARMUP_TASKS = {"defaults": 2, "smoke": 0}  # tasks of a trial before the pruner may stop it


def suite(name: str) -> tuple[Task, ...]:
    """The tasks of suite ``name``; a ValueError names the known suites otherwise."""
    if name not in SUITES:
        raise ValueError(f"unknown suite {name!r}; the suites are {sorted(SUITES)}")
    return SUITES[name]


_LOCAL_ENVS: dict[str, tuple[type[gym.Env], str | None]] = {
    NAVIGATION: (NavigationEnv, "is_success"),
    TOY: (ParameterizedTargetEnv, None),
}


def train_env(env_id: str, n_envs: int, seed: int) -> VecEnv:
    """The training VecEnv of a task's env (:func:`benchmarks.domains.train_env` for the benchmark's ids)."""
    if env_id in _LOCAL_ENVS:
        return make_vec_env(_LOCAL_ENVS[env_id][0], n_envs=n_envs, seed=seed)
    return domains.train_env(env_id, n_envs, seed)


def greedy_score(env_id: str, policy: Any, n_episodes: int, seed: int) -> float:
    """The mean greedy score of ``policy`` on episode slots ``0..n_episodes-1`` of set ``seed``: the benchmark's
    metric (:func:`benchmarks.domains.metric`), success share on NavigationEnv, mean return on the toy env."""
    if env_id in _LOCAL_ENVS:
        make, success_key = _LOCAL_ENVS[env_id]
        returns, success = domains.play_episodes(make(), policy, n_episodes, seed, success_key)
        return float(np.mean(success if success_key is not None else returns))
    return float(domains.evaluate(env_id, policy, n_episodes, seed)[domains.metric(env_id)])


class RandomActions:
    """Uniformly random actions of ``action_space`` (seeded once), one per observation of a batch."""

    def __init__(self, action_space: gym.spaces.Space[Any], seed: int):
        self.action_space = action_space
        self.action_space.seed(seed)

    def predict(self, obs: Any, deterministic: bool = True) -> tuple[Any, None]:
        if np.ndim(obs) < 2:
            return self.action_space.sample(), None
        actions = np.empty(len(obs), dtype=object)
        for i in range(len(obs)):
            actions[i] = self.action_space.sample()
        return actions, None


class ScriptedActions:
    """A function from one observation to an action (``hybrid_domains.baselines``) as a policy with ``predict``."""

    def __init__(self, act: Callable[[Any], Any]):
        self.act = act

    def predict(self, obs: Any, deterministic: bool = True) -> tuple[Any, None]:
        return self.act(obs), None


def floor_policy(env_id: str, seed: int) -> RandomActions:
    """The policy normalised to 0: uniformly random actions of the env's action space."""
    if env_id in _LOCAL_ENVS:
        space = _LOCAL_ENVS[env_id][0]().action_space
    elif domains.is_dribbling(env_id):
        space = DribbleEnv(profile=ENV_PROFILES[env_id]).action_space
    else:
        space = domains.episodic_env(env_id).action_space
    return RandomActions(space, seed)


@cache
def floor_score(env_id: str, n_episodes: int, seed: int) -> float:
    return greedy_score(env_id, floor_policy(env_id, seed), n_episodes, seed)


@cache
def reference_score(env_id: str, n_episodes: int, seed: int) -> float:
    """The score normalised to 1 on these episodes: the hand-coded dribbler (dribbling), the scripted controller
    (Moving-v0, CatchPoint-v0), else the metric's maximum (Platform-v0's return 1 reaches the goal, a success share of
    1, the toy env's optimum return)."""
    if domains.is_dribbling(env_id):
        return greedy_score(env_id, HandCodedDribbler(profile=ENV_PROFILES[env_id]), n_episodes, seed)
    if env_id in ("Moving-v0", "CatchPoint-v0"):
        return greedy_score(env_id, ScriptedActions(scripted_policy(env_id)), n_episodes, seed)
    if env_id == domains.PLATFORM_ID:
        return domains.PLATFORM_SUCCESS_RETURN
    if env_id == TOY:
        return TOY_OPTIMUM
    if env_id == NAVIGATION:
        return 1.0
    raise ValueError(f"no reference score for {env_id!r}")


def suite_tasks(
    name: str, n_episodes: int = TUNE_EPISODES, seed: int = TUNE_EVAL_SEED, only: set[str] | None = None
) -> tuple[SuiteTask, ...]:
    """Suite ``name`` as the study's tasks (those named in ``only``, if given), scored on ``n_episodes`` episodes of
    set ``seed``."""

    def score(env_id: str) -> Callable[[Any], float]:
        return lambda model: greedy_score(env_id, model, n_episodes, seed)

    return tuple(
        SuiteTask(
            name=task.name,
            make_env=lambda n_envs, train_seed, env_id=task.env_id: train_env(env_id, n_envs, train_seed),
            n_envs=task.n_envs,
            timesteps=task.timesteps,
            score=score(task.env_id),
            floor=floor_score(task.env_id, n_episodes, seed),
            reference=reference_score(task.env_id, n_episodes, seed),
            fixed=task.fixed,
        )
        for task in suite(name)
        if only is None or task.name in only
    )


def suite_settings(
    name: str, policy: str, fixed: dict[str, Any], seed: int = TUNE_SEED, startup_trials: int = 5
) -> SuiteSettings:
    return SuiteSettings(
        suite=name,
        tasks=suite_tasks(name),
        policy=policy,
        seed=seed,
        fixed=fixed,
        startup_trials=startup_trials,
        warmup_evaluations=WARMUP_TASKS[name],
    )


def default_params(policy: str) -> dict[str, Any]:
    """SarsaAAC's defaults with ``policy`` as a trial's parameters of its search space (rates: the policy's
    ``default_learning_rate``)."""
    policy_class = SarsaAAC.policy_aliases[policy]
    rate = policy_class.default_learning_rate  # type: ignore[attr-defined]
    defaults = {
        name: parameter.default
        for cls in (SarsaAAC, policy_class)
        for name, parameter in inspect.signature(cls.__init__).parameters.items()
    }
    defaults.update(learning_rate=rate, q_learning_rate=rate, param_learning_rate=rate)
    space = search_space("sarsa_aac", policy)
    return {name: defaults[name] for name in {**space.hyperparameters, **space.policy_kwargs}}


STORAGE_HELP = "journal file or database URL (default: hyperparams/tuned/suite-SUITE/POLICY.journal)"


def default_storage(name: str, policy: str) -> str:
    return f"hyperparams/tuned/suite-{name}/{policy}.journal"


def study_name(name: str, policy: str) -> str:
    return f"suite-{name}-sarsa_aac-{policy}"


def print_suite_trial(trial: FrozenTrial) -> None:
    print_trial(trial)
    normalised = trial.user_attrs.get("normalised", {})
    scores = trial.user_attrs.get("scores", {})
    if normalised:
        print("   " + ", ".join(f"{task} {scores[task]:.4g} ({value:.3f})" for task, value in normalised.items()), flush=True)


def trial_settings(storage: str, name: str, policy: str, number: int | None = None) -> tuple[FrozenTrial, dict[str, Any]]:
    """Trial ``number`` (None: the best complete one) of the study of suite ``name`` in ``storage`` and its
    constructor keyword arguments."""
    study = optuna.load_study(study_name=study_name(name, policy), storage=open_storage(storage))
    complete = study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
    if not complete:
        raise SystemExit(f"study {study_name(name, policy)!r} in {storage} has no complete trial yet")
    if number is not None and number not in {trial.number for trial in complete}:
        raise SystemExit(f"trial {number} is not a complete trial of the study; complete: {[t.number for t in complete]}")
    trial = study.best_trial if number is None else study.trials[number]
    fixed = ast.literal_eval(study.user_attrs["settings"]["fixed"])  # the --set values the study was run with
    return trial, trial_kwargs("sarsa_aac", policy, fixed, trial.params)


def cmd_tune(args: argparse.Namespace) -> None:
    fixed = hyperparameters(args.set)
    settings = suite_settings(args.suite, args.policy, fixed, args.seed, args.startup_trials)
    storage = args.storage or default_storage(args.suite, args.policy)
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        study = load_study(open_storage(storage), study_name(args.suite, args.policy), settings)
    except ValueError as error:  # a storage that cannot be opened, a study made with other settings
        raise SystemExit(str(error)) from None
    described = ", ".join(
        f"{t.name} {t.timesteps} steps x {t.n_envs} lanes [{t.floor:.4g}, {t.reference:.4g}]" for t in settings.tasks
    )
    print(
        f"tuning SarsaAAC {args.policy} on suite {args.suite!r}: {described}; objective: the mean normalised greedy "
        f"score ({TUNE_EPISODES} episodes of set {TUNE_EVAL_SEED}), training seed {args.seed}; {args.trials} trials, "
        f"{finished_trials(study)} finished so far, in {storage}",
        flush=True,
    )
    if args.enqueue_defaults:  # the defaults as the next trial, so that the study scores them on its tasks too
        study.enqueue_trial(default_params(args.policy), skip_if_exists=True)
    outcome = run_trials(study, suite_objective(settings), args.trials, print_suite_trial)
    best, kwargs = trial_settings(storage, args.suite, args.policy)
    print(f"best: trial {best.number}, mean normalised score {best.value:.4f}; per task {best.user_attrs['normalised']}")
    print("evaluate it: --set " + " ".join(f"{key}={literal(value)}" for key, value in flat_settings(kwargs).items()))
    if outcome.interrupted:
        raise KeyboardInterrupt


def cmd_trials(args: argparse.Namespace) -> None:
    storage = args.storage or default_storage(args.suite, args.policy)
    study = optuna.load_study(study_name=study_name(args.suite, args.policy), storage=open_storage(storage))
    ended = study.get_trials(deepcopy=False, states=(TrialState.COMPLETE, TrialState.PRUNED, TrialState.FAIL))
    print(f"study {study.study_name!r} in {storage}: {len(ended)} ended trials ({finished_trials(study)} finished)")
    for trial in ended:
        print_suite_trial(trial)


def cmd_evaluate(args: argparse.Namespace) -> None:
    if args.from_study:
        trial, kwargs = trial_settings(args.from_study, args.suite, args.policy, args.trial)
        label = f"trial {trial.number} of {args.from_study}"
    else:
        kwargs, label = hyperparameters(args.set), "defaults" if not args.set else "--set"
    header: dict[str, Any] = {
        "suite": args.suite,
        "policy": args.policy,
        "settings": label,
        "kwargs": {key: literal(value) for key, value in flat_settings(kwargs).items()},
        "episodes": FINAL_EPISODES,
        "episode_set": FINAL_SEED,
    }
    names = [task.name for task in suite(args.suite)]
    only = set(args.tasks.split(",")) if args.tasks else set(names)
    if not only <= set(names):
        raise SystemExit(f"unknown tasks {sorted(only - set(names))}; suite {args.suite!r} has {names}")
    out = Path(args.out)
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    to_run: dict[str, list[int]] = {}
    for name in names:
        for seed in seeds if name in only else ():
            path = out / f"{name}-s{seed}.json"
            if path.exists():  # resume: a run finished with the same settings is kept
                stored = json.loads(path.read_text())
                if {key: stored.get(key) for key in header} != header:
                    raise SystemExit(f"{path} holds another evaluation ({stored['settings']}); give another --out")
            else:
                to_run.setdefault(name, []).append(seed)
    tasks = [task for task in suite(args.suite) if task.name in to_run]
    for task, suite_task in zip(tasks, suite_tasks(args.suite, FINAL_EPISODES, FINAL_SEED, set(to_run)), strict=True):
        for seed in to_run[task.name]:
            env = train_env(task.env_id, task.n_envs, seed)
            start = time.perf_counter()
            model = SarsaAAC(args.policy, env, seed=seed, **{**task.fixed, **kwargs})
            model.learn(task.timesteps)
            seconds = round(time.perf_counter() - start, 1)
            env.close()
            score = suite_task.score(model)
            run = {"task": task.name, "seed": seed, "score": score, "floor": suite_task.floor}
            run.update(reference=suite_task.reference, env_id=task.env_id, timesteps=task.timesteps, n_envs=task.n_envs)
            print(f"{task.name} seed {seed}: {score:.4f} ({seconds:.0f} s of training)", flush=True)
            out.mkdir(parents=True, exist_ok=True)
            (out / f"{task.name}-s{seed}.json").write_text(json.dumps({**header, **run, "train_seconds": seconds}) + "\n")


RUN_KEYS = ("task", "seed", "score", "floor", "reference", "env_id", "timesteps", "n_envs", "train_seconds")


def load_evaluation(folder: str) -> dict[str, Any]:
    """The run files ``evaluate`` wrote into ``folder`` (one per task and seed) as one evaluation: their shared header
    and, per task, the scores in seed order with the seeds, floor and reference."""
    files = sorted(Path(folder).glob("*.json"))
    if not files:
        raise SystemExit(f"no evaluation files (*.json) in {folder}")
    runs = [json.loads(path.read_text()) for path in files]
    header = {key: value for key, value in runs[0].items() if key not in RUN_KEYS}
    tasks: dict[str, dict[str, Any]] = {}
    for path, run in sorted(zip(files, runs, strict=True), key=lambda pair: (pair[1]["task"], pair[1]["seed"])):
        if {key: value for key, value in run.items() if key not in RUN_KEYS} != header:
            raise SystemExit(f"{path} is another evaluation than {files[0]}")
        task = tasks.setdefault(run["task"], {"scores": [], "seeds": [], "floor": run["floor"], "reference": run["reference"]})
        task["scores"].append(run["score"])
        task["seeds"].append(run["seed"])
    order = [task.name for task in suite(header["suite"]) if task.name in tasks]
    return {**header, "tasks": {name: tasks[name] for name in order}}


def normalised_mean(task: dict[str, Any]) -> float:
    return float(np.mean([normalised_score(score, task["floor"], task["reference"]) for score in task["scores"]]))


def compare_text(first: dict[str, Any], second: dict[str, Any]) -> str:
    """Per task the two evaluations' means, Welch's test on the difference, and whether the second wins across the
    suite (higher mean normalised score, no task significantly worse)."""
    shared = [name for name in first["tasks"] if name in second["tasks"]]
    names = [name for name in shared if min(len(first["tasks"][name]["scores"]), len(second["tasks"][name]["scores"])) >= 2]
    if not names:
        raise SystemExit("the two evaluations share no task with at least 2 runs on each side")
    lines = [
        f"A: {first['settings']} {first['kwargs']}",
        f"B: {second['settings']} {second['kwargs']}",
        f"training seeds per task as listed; {first['episodes']} greedy episodes of set {first['episode_set']} each",
        f"{'task':9s} {'A mean':>9s} {'B mean':>9s} {'B - A':>9s} {'t':>7s} {'p':>7s}  A norm  B norm  A seeds | B seeds",
    ]
    worse = []
    for name in names:
        a, b = first["tasks"][name], second["tasks"][name]
        t, p = welch_test(b["scores"], a["scores"])
        diff = float(np.mean(b["scores"]) - np.mean(a["scores"]))
        if p < SIGNIFICANCE and diff < 0:
            worse.append(name)
        lines.append(
            f"{name:9s} {np.mean(a['scores']):9.4f} {np.mean(b['scores']):9.4f} {diff:+9.4f} {t:7.2f} {p:7.3g}  "
            f"{normalised_mean(a):.3f}   {normalised_mean(b):.3f}   {a['seeds']} | {b['seeds']}"
        )
    mean_a = float(np.mean([normalised_mean(first["tasks"][n]) for n in names]))
    mean_b = float(np.mean([normalised_mean(second["tasks"][n]) for n in names]))
    wins = mean_b > mean_a and not worse

    def runs(evaluation: dict[str, Any], name: str) -> int:
        return len(evaluation["tasks"].get(name, {}).get("scores", []))

    every = [*first["tasks"], *(name for name in second["tasks"] if name not in first["tasks"])]
    missing = [f"{name} ({runs(first, name)} | {runs(second, name)} runs)" for name in every if name not in names]
    if missing:
        lines.append(f"not compared (fewer than 2 runs on a side): {', '.join(missing)}")
    lines.append(f"mean normalised score over the compared tasks: A {mean_a:.4f}, B {mean_b:.4f}")
    why = f"significantly worse on {', '.join(worse)}" if worse else "a lower mean normalised score"
    lines.append("verdict: B wins across the suite" if wins else f"verdict: B does not win across the suite ({why})")
    return "\n".join(lines)


def cmd_compare(args: argparse.Namespace) -> None:
    first, second = (load_evaluation(folder) for folder in args.evaluations)
    print(compare_text(first, second))


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)

    def with_suite(command: argparse.ArgumentParser) -> None:
        command.add_argument("--suite", default="defaults", type=_suite_name, help="suite (default: %(default)s)")
        command.add_argument("--policy", default="TilePolicy", choices=policies("sarsa_aac"))
        command.add_argument("--set", metavar="KEY=VALUE", type=key_value, action="append", default=[])

    tune = commands.add_parser("tune", help="run (or resume) the suite's study")
    with_suite(tune)
    tune.add_argument("--trials", type=int, default=30, help="finished trials the study should hold")
    tune.add_argument("--storage", help=STORAGE_HELP)
    tune.add_argument("--seed", type=int, default=TUNE_SEED, help="training seed of every trial (default: %(default)s)")
    tune.add_argument("--startup-trials", type=int, default=5)
    tune.add_argument("--enqueue-defaults", action="store_true", help="make SarsaAAC's defaults the next trial")
    tune.set_defaults(func=cmd_tune)

    trials = commands.add_parser("trials", help="print every ended trial of the suite's study")
    with_suite(trials)
    trials.add_argument("--storage", help=STORAGE_HELP)
    trials.set_defaults(func=cmd_trials)

    evaluate = commands.add_parser("evaluate", help="train the suite on seeds 0..N-1, score on the final episodes")
    with_suite(evaluate)
    evaluate.add_argument("--seeds", type=int, default=5, help="runs per task, seeds FIRST_SEED, FIRST_SEED + 1, ...")
    evaluate.add_argument("--first-seed", type=int, default=0, help="(processes side by side take different seeds)")
    evaluate.add_argument("--from-study", metavar="STORAGE", help="evaluate the best trial of the suite's study there")
    evaluate.add_argument("--trial", type=int, help="with --from-study: this trial instead of the best")
    evaluate.add_argument("--tasks", metavar="A,B", help="only these tasks (processes side by side take different ones)")
    evaluate.add_argument(
        "--out", required=True, help="folder of the scores, a TASK-sSEED.json per run (finished runs are kept)"
    )
    evaluate.set_defaults(func=cmd_evaluate)

    compare = commands.add_parser("compare", help="Welch's test per task between two evaluations (A, then B)")
    compare.add_argument("evaluations", nargs=2, metavar="FOLDER")
    compare.set_defaults(func=cmd_compare)
    return parser


def _suite_name(text: str) -> str:
    try:
        suite(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return text


def main(argv: Sequence[str] | None = None) -> None:
    args = build_parser().parse_args(argv)
    th.set_num_threads(1)
    try:
        args.func(args)
    except KeyboardInterrupt:  # a study stopped by Ctrl-C has said so and kept its finished trials
        raise SystemExit(130) from None


if __name__ == "__main__":
    main()
