"""``sb3-aac train``: train SarsaAAC (or P-DQN / MP-DQN / HybridPPO, ``--algo``) on a registered env, save the run (model,
exported policy, settings) as one set, and print a greedy evaluation. :func:`cmd_train` runs the steps in order; each
step is its own function."""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

from sb3_aac.cli.arguments import (
    CliError,
    episode_count,
    episode_count_or_zero,
    lane_count,
    output_dir,
    require_extra,
    seed_int,
    step_count,
)
from sb3_aac.cli.envs import (
    DRIBBLE_IDS,
    add_perception_argument,
    check_env_id,
    import_gym_packages,
    make_train_env,
    max_episode_length,
)
from sb3_aac.cli.reports import print_dribble_report
from sb3_aac.common.algorithms import ALGOS, POLICIES, algo_key, algorithm, hyperparameters, key_value
from sb3_aac.common.output_files import RunFolder

DEFAULT_TIMESTEPS = 100_000
EVAL_SEED_OFFSET = 10_000  # the greedy evaluation after training plays seed + this (never the training seeds)


def add_train_command(add: Any) -> None:
    """Add ``train`` through ``add(name, help, example)`` (see :func:`sb3_aac.cli.build_parser`)."""
    train = add(
        "train",
        "train SarsaAAC, P-DQN, MP-DQN or HybridPPO (--algo), then print a greedy evaluation (metres, share >= 20 m, "
        "ball-loss rate)",
        "sb3-aac train --env RoboCupDribblePaper-v0 --policy RbfPolicy --episodes 3000 --n-envs 16 --set n_rbf=30 "
        "--out runs/rbf",
    )
    train.add_argument("--env", default="RoboCupDribblePaper-v0", help="registered env id (default: %(default)s)")
    train.add_argument(
        "--algo",
        default="sarsa_aac",
        type=algo_key,
        choices=list(ALGOS),
        help="algorithm, by key or class name (HybridPPO = hppo; default: %(default)s)",
    )
    train.add_argument(
        "--policy",
        choices=POLICIES,
        help=f"function approximators (default: {ALGOS['sarsa_aac'].default_policy}; MlpPolicy for pdqn/mpdqn/hppo)",
    )
    budget = train.add_mutually_exclusive_group()
    budget.add_argument(
        "--timesteps", type=step_count, default=DEFAULT_TIMESTEPS, help="training budget in env steps (default: %(default)s)"
    )
    budget.add_argument(
        "--episodes",
        type=episode_count,
        help="training budget in episodes (schedules span episodes x max episode length steps)",
    )
    train.add_argument("--n-envs", type=lane_count, default=16, help="envs stepped side by side (default: %(default)s)")
    train.add_argument("--seed", type=seed_int, default=0, help="random seed (default: %(default)s)")
    add_perception_argument(train)
    train.add_argument("--tensorboard", metavar="DIR", help="write TensorBoard logs here (view: tensorboard --logdir DIR)")
    train.add_argument("--progress-bar", action="store_true", help="show a progress bar (tqdm, rich)")
    train.add_argument(
        "--out",
        metavar="DIR",
        help="save DIR/model.zip, DIR/policy.aacp (exported) and DIR/run.json (DIR is created if missing; nothing else "
        "in it is touched)",
    )
    train.add_argument("--overwrite", action="store_true", help="replace those files if DIR already holds them")
    train.add_argument(
        "--set",
        metavar="KEY=VALUE",
        type=key_value,
        action="append",
        default=[],
        help="a hyperparameter of --algo's class as a Python literal, repeatable: gamma=0.95, learning_rate=0.2, "
        "type_exploration=boltzmann; policy arguments (n_rbf, hidden_units, rbf_width; for pdqn/mpdqn net_arch, "
        "actor_net_arch, param_bounding, initial_params; for hppo net_arch, ortho_init, log_std_init) go into policy_kwargs",
    )
    train.add_argument(
        "--eval-episodes", type=episode_count_or_zero, default=1000, help="greedy evaluation episodes after training (0: none)"
    )
    train.add_argument(
        "--gym-package", action="append", default=[], metavar="MODULE", help="import MODULE first (registers envs)"
    )
    train.add_argument("--verbose", type=int, default=0, choices=(0, 1, 2), help="SB3 verbosity: 1 prints the log table")
    train.set_defaults(func=cmd_train)


def cmd_train(args: argparse.Namespace) -> None:
    """Check everything the user named, then train, save and evaluate; each file of ``--out`` is the old or a whole new one."""
    if args.progress_bar:
        require_extra("progress", "--progress-bar", "tqdm", "rich")
    kwargs = model_settings(args)
    if args.tensorboard is not None:
        output_dir(args.tensorboard, "--tensorboard directory")
    folder = run_folder(args) if args.out is not None else None
    total_timesteps, budget = training_budget(args)
    model = build_model(args, kwargs)
    print(
        f"training {ALGOS[args.algo].class_name} {args.policy} on {args.env} for {budget}, "
        f"{args.n_envs} env(s), seed {args.seed}"
    )
    for note in budget_notes(args, model, total_timesteps):
        print(f"  note: {note}")
    try:
        learn(model, args, total_timesteps)
    except KeyboardInterrupt:
        if folder is None:
            print(f"interrupted after {model.num_timesteps} steps: nothing was kept (give --out DIR to keep a run)")
        else:
            print(f"interrupted after {model.num_timesteps} steps: saving the model trained so far")
            save_run(model, folder, {**run_settings(args, model, kwargs), "interrupted": True})
        raise
    if folder is not None:
        save_run(model, folder, run_settings(args, model, kwargs))
    if args.eval_episodes > 0:
        evaluate_greedy(model, args)


def model_settings(args: argparse.Namespace) -> dict[str, Any]:
    """The env and the algorithm's keyword arguments checked (``args.policy`` set to the algorithm's default if not
    given); ``build_model(args, model_settings(args))`` builds the untrained model. No file is touched."""
    import_gym_packages(args.gym_package)
    check_env_id(args.env)
    kwargs = hyperparameters(args.set, args.algo)
    args.policy = args.policy or ALGOS[args.algo].default_policy
    if args.algo != "sarsa_aac" and args.policy != "MlpPolicy":
        raise CliError(f"--algo {args.algo} has one policy, MlpPolicy, not {args.policy}")
    return kwargs


def run_folder(args: argparse.Namespace) -> RunFolder:
    """The ``--out`` folder, checked before training: writable, and not holding the run's files unless --overwrite."""
    names = ("model.zip", "policy.aacp", "run.json")
    if not args.out:
        raise CliError("cannot write --out directory '': give a folder name, e.g. runs/name")
    try:
        return RunFolder(args.out, names, "--out directory", overwrite=args.overwrite)
    except ValueError as error:
        raise CliError(str(error)) from None


def training_budget(args: argparse.Namespace) -> tuple[int, str]:
    """The step budget for ``learn`` and its description (``--episodes`` bounds steps by the max episode length)."""
    if args.episodes is not None:
        total_timesteps = args.episodes * max_episode_length(args.env)
        return total_timesteps, f"{args.episodes} episodes (at most {total_timesteps} steps)"
    return args.timesteps, f"{args.timesteps} steps"


def budget_notes(args: argparse.Namespace, model: Any, total_timesteps: int) -> list[str]:
    """What the user should know before training starts: a step budget an on-policy learner rounds up to whole
    rollouts, and a model that will not be kept (no --out)."""
    notes = []
    rollout = getattr(model, "n_steps", 0) * args.n_envs  # the steps of one rollout of an on-policy learner
    if args.episodes is None and rollout and total_timesteps % rollout:
        trained = -(-total_timesteps // rollout) * rollout
        notes.append(
            f"{ALGOS[args.algo].class_name} collects whole rollouts of n_steps x n_envs = {rollout:,} steps, so it "
            f"trains {trained:,} steps for the budget of {total_timesteps:,}"
        )
    if args.out is None:
        notes.append("no --out: the model is evaluated and then not kept (give --out DIR to keep it)")
    return notes


def build_model(args: argparse.Namespace, kwargs: dict[str, Any]) -> Any:
    env = make_train_env(args.env, args.n_envs, args.seed, args.perception)
    try:
        cls = algorithm(args.algo)
        return cls(args.policy, env, seed=args.seed, tensorboard_log=args.tensorboard, verbose=args.verbose, **kwargs)
    except (ValueError, TypeError, AssertionError) as error:
        raise CliError(f"cannot build {ALGOS[args.algo].class_name}({args.policy}) on {args.env}: {error}") from None


def learn(model: Any, args: argparse.Namespace, total_timesteps: int) -> None:
    """``model.learn`` for the budget (stopped after ``--episodes`` finished episodes, if given); prints the time."""
    from stable_baselines3.common.callbacks import BaseCallback

    class StopAfterEpisodes(BaseCallback):
        def __init__(self, episodes: int):
            super().__init__()
            self.episodes, self.finished = episodes, 0

        def _on_step(self) -> bool:
            self.finished += int(self.locals["dones"].sum())
            return self.finished < self.episodes

    callback = StopAfterEpisodes(args.episodes) if args.episodes is not None else None
    start = time.perf_counter()
    try:
        model.learn(
            total_timesteps,
            callback=callback,
            progress_bar=args.progress_bar,
            tb_log_name=f"{ALGOS[args.algo].class_name}_{args.policy}",
        )
    except FloatingPointError as error:
        raise CliError(str(error)) from None
    seconds = time.perf_counter() - start
    print(f"trained {model.num_timesteps} steps ({model.episode_num} episodes) in {seconds:.1f} s")


def run_settings(args: argparse.Namespace, model: Any, kwargs: dict[str, Any]) -> dict[str, Any]:
    """What ``run.json`` records: the command's settings and what training did."""
    return {
        "algo": args.algo,
        "env_id": args.env,
        "policy": args.policy,
        "seed": args.seed,
        "n_envs": args.n_envs,
        "perception": args.perception,
        "timesteps": model.num_timesteps,
        "episodes": model.episode_num,
        "hyperparameters": {k: repr(v) for k, v in kwargs.items()},
    }


def save_run(model: Any, folder: RunFolder, settings: dict[str, Any]) -> None:
    """Write model.zip, policy.aacp and, last, run.json into the ``--out`` folder, each in one step."""
    from sb3_aac import export_policy

    out = folder.out
    try:
        with folder.file("model.zip") as tmp:
            model.save(tmp)
        with folder.file("policy.aacp") as tmp:
            export_policy(model, tmp, metadata={"env_id": settings["env_id"]})
        with folder.file("run.json") as tmp:
            tmp.write_text(json.dumps(settings, indent=2) + "\n")
    except OSError as error:
        raise CliError(f"cannot write the run to {out}: {error.strerror or error}") from None
    print(
        f"saved {out / 'model.zip'} ({ALGOS[settings['algo']].class_name}.load), {out / 'policy.aacp'} "
        f"(RuntimePolicy.load) and {out / 'run.json'}"
    )


def evaluate_greedy(model: Any, args: argparse.Namespace) -> None:
    """Print ``--eval-episodes`` greedy episodes: dribbling metrics on the dribbling envs, the return elsewhere."""
    seed = EVAL_SEED_OFFSET + (args.seed or 0)
    if args.env in DRIBBLE_IDS:
        from robocup_dribble.evaluation import evaluate_dribbling

        report = evaluate_dribbling(
            model, args.eval_episodes, profile=DRIBBLE_IDS[args.env], seed=seed, perception=args.perception
        )
        print_dribble_report(
            report,
            f"greedy evaluation on {len(report.distances)} episodes of fresh players, seed {seed} (never a training "
            f"seed; sb3-aac evaluate MODEL --seed {seed} repeats it):",
        )
    else:
        from stable_baselines3.common.evaluation import evaluate_policy

        eval_env = make_train_env(args.env, 1, seed)
        mean, std = evaluate_policy(model, eval_env, n_eval_episodes=args.eval_episodes, deterministic=True)
        print(f"greedy evaluation over {args.eval_episodes} episodes: return {mean:.3f} +/- {std:.3f} (seed {seed})")
