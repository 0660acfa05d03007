"""``sb3-aac tune``: search the hyperparameters of SarsaAAC (or HybridPPO, ``--algo hppo``) with Optuna
(:mod:`sb3_aac.tune`) from the command line."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import TYPE_CHECKING

from sb3_aac.cli.arguments import CliError, episode_count, lane_count, positive_int, seed_int, step_count
from sb3_aac.cli.envs import DRIBBLE_IDS, check_env_id, import_gym_packages, make_train_env
from sb3_aac.common.algorithms import ALGOS, POLICIES, algo_key, hyperparameters, key_value

if TYPE_CHECKING:  # Optuna is an optional dependency: imported when the command runs
    from optuna import Study

    from sb3_aac.tune import TuneSettings

DEFAULT_STORAGE = "sqlite:///study.db"
EVALUATIONS_PER_TRIAL = 5  # the default --eval-every is --timesteps divided by this
TUNABLE_ALGOS = ("sarsa_aac", "hppo")  # the algorithms of sb3_aac.tune.search_spaces (not imported: it needs Optuna)


def add_tune_command(add: Callable[..., argparse.ArgumentParser]) -> None:
    """Add the ``tune`` subcommand through ``add(name, help, example)``, the helper of :func:`sb3_aac.cli.build_parser`."""
    tune = add(
        "tune",
        "search hyperparameters with Optuna (TPE, median pruning on greedy evaluations); resumable; prints the best as "
        "a train command and a hyperparams/sarsa_aac.yml entry",
        "sb3-aac tune --env RoboCupDribblePaper-v0 --policy RbfPolicy --trials 30 --timesteps 50000 --storage sqlite:///study.db",
    )
    tune.add_argument("--env", default="RoboCupDribblePaper-v0", help="registered env id (default: %(default)s)")
    tune.add_argument(
        "--algo",
        default="sarsa_aac",
        type=algo_key,
        choices=TUNABLE_ALGOS,
        help="algorithm, by key or class name (HybridPPO = hppo, with --policy MlpPolicy; default: %(default)s)",
    )
    tune.add_argument(
        "--policy", default="RbfPolicy", choices=POLICIES, help="the policy whose space is searched (default: %(default)s)"
    )
    tune.add_argument(
        "--trials", type=positive_int, default=20, help="finished trials the study should hold (default: %(default)s)"
    )
    tune.add_argument(
        "--timesteps", type=step_count, default=100_000, help="training steps per trial and seed (default: %(default)s)"
    )
    tune.add_argument(
        "--eval-every",
        type=step_count,
        help=f"steps between pruning evaluations (default: timesteps / {EVALUATIONS_PER_TRIAL})",
    )
    tune.add_argument(
        "--eval-episodes",
        type=episode_count,
        default=100,
        help="episodes per greedy evaluation, the same each time (default: %(default)s)",
    )
    tune.add_argument(
        "--objective",
        metavar="KEY",
        help="'return', or an info key read at each episode's end (default: distance on the dribbling envs, else return)",
    )
    tune.add_argument(
        "--storage",
        default=DEFAULT_STORAGE,
        help="database URL, or a journal file (e.g. study.log) that processes on several machines can share "
        "(default: %(default)s)",
    )
    tune.add_argument("--study-name", help="default: ALGO-POLICY-ENV; the same name and storage resume a study")
    tune.add_argument("--n-envs", type=lane_count, default=16, help="envs stepped side by side (default: %(default)s)")
    tune.add_argument(
        "--seed", type=seed_int, default=0, help="training seed of every trial; sampler seed (default: %(default)s)"
    )
    tune.add_argument(
        "--seeds-per-trial",
        type=positive_int,
        default=1,
        help="runs per trial, seeds SEED, SEED+1, ...; the trial scores their mean",
    )
    tune.add_argument(
        "--startup-trials",
        type=positive_int,
        default=5,
        help="random trials before TPE and pruning start (default: %(default)s)",
    )
    tune.add_argument(
        "--set",
        metavar="KEY=VALUE",
        type=key_value,
        action="append",
        default=[],
        help="fix a hyperparameter (not searched), as train's --set",
    )
    tune.add_argument(
        "--gym-package", action="append", default=[], metavar="MODULE", help="import MODULE first (registers envs)"
    )
    tune.set_defaults(func=cmd_tune)


def cmd_tune(args: argparse.Namespace) -> None:
    try:
        import optuna

        from sb3_aac.tune import finished_trials, load_study, open_storage, run_study
        from sb3_aac.tune.report import print_trial
    except ImportError as error:
        raise CliError(f"tune needs Optuna ({error}): pip install 'sb3-aac[tune]'") from None
    import_gym_packages(args.gym_package)
    check_env_id(args.env)
    settings = tune_settings(args)
    study_name = args.study_name or f"{settings.algo}-{settings.policy}-{settings.env_id}"
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        study = load_study(open_storage(args.storage), study_name, settings)
    except ValueError as error:
        raise CliError(str(error)) from None
    print(
        f"tuning {ALGOS[settings.algo].class_name} {settings.policy} on {settings.env_id}: {args.trials} trials of "
        f"{settings.timesteps} steps x "
        f"{settings.seeds_per_trial} seed(s), {settings.n_envs} env(s); objective {settings.objective!r} on "
        f"{settings.eval_episodes} greedy episodes every {settings.eval_every} steps; study {study_name!r} in {args.storage} "
        f"({finished_trials(study)} finished trials so far)",
        flush=True,
    )
    try:
        outcome = run_study(
            study, settings, lambda n_envs, seed: make_train_env(settings.env_id, n_envs, seed), args.trials, print_trial
        )
    except (ValueError, TypeError) as error:  # hyperparameters the algorithm rejects, an objective the env lacks
        raise CliError(f"trial failed: {error}") from None
    print_best(outcome.study, settings)
    if outcome.interrupted:
        print(
            f"stopped by Ctrl-C; the study keeps its {finished_trials(study)} finished trials: run the same command to resume"
        )
        raise KeyboardInterrupt


def tune_settings(args: argparse.Namespace) -> TuneSettings:
    from sb3_aac.tune import TuneSettings

    objective = args.objective or ("distance" if args.env in DRIBBLE_IDS else "return")
    try:
        return TuneSettings(
            env_id=args.env,
            policy=args.policy,
            algo=args.algo,
            timesteps=args.timesteps,
            eval_every=args.eval_every or max(1, args.timesteps // EVALUATIONS_PER_TRIAL),
            eval_episodes=args.eval_episodes,
            n_envs=args.n_envs,
            seed=args.seed,
            seeds_per_trial=args.seeds_per_trial,
            objective=objective,
            fixed=hyperparameters(args.set, args.algo),
            startup_trials=args.startup_trials,
        )
    except ValueError as error:
        raise CliError(str(error)) from None


def print_best(study: Study, settings: TuneSettings) -> None:
    from optuna.trial import TrialState

    from sb3_aac.tune.report import train_command, zoo_entry

    complete = study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
    if not complete:
        print("no trial has completed yet, so there is no best setting")
        return
    best = study.best_trial
    kwargs = settings.kwargs(best.params)
    print(f"best of {len(complete)} completed trials: trial {best.number}, {settings.objective} {best.value:.4g}")
    print("train with it:")
    print(f"  {train_command(settings, kwargs)}")
    print(f"or add to hyperparams/{settings.algo}.yml:")
    print(zoo_entry(settings, kwargs))
