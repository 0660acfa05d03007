"""
The ``sb3-aac`` command line: train SarsaAAC, measure it, watch it, export it.

Run ``sb3-aac --help`` (or ``python -m sb3_aac.cli --help``) for the subcommands and examples. Errors print one line
saying what to do and exit with status 2, without a traceback.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import inspect
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from sb3_aac.common.output_files import DirectoryPublisher, check_writable_dir, check_writable_file, replaced_atomically

DRIBBLE_IDS = {"RoboCupDribble-v0": "v19", "RoboCupDribblePaper-v0": "v11"}
PROFILE_ENV_IDS = {profile: env_id for env_id, profile in DRIBBLE_IDS.items()}
POLICIES = ("MlpPolicy", "RbfMlpPolicy", "RbfPolicy", "TilePolicy")
TOY_ENV_ID = "sb3_aac/ParameterizedTarget-v0"
# SarsaAAC constructor arguments the CLI sets itself (not through --set).
RESERVED = ("policy", "env", "tensorboard_log", "seed", "device", "verbose", "_init_setup_model")
POLICY_KEYS = ("hidden_units", "n_rbf", "rbf_width", "obs_bounds", "tile_groups", "tiles_per_input", "n_tilings")
# --algo: the class name in sb3_aac, its default policy, and the policy arguments --set may give.
ALGOS = {
    "sarsa_aac": ("SarsaAAC", "RbfPolicy", POLICY_KEYS),
    "pdqn": ("PDQN", "MlpPolicy", ("net_arch", "actor_net_arch", "param_bounding", "initial_params")),
    "mpdqn": ("MPDQN", "MlpPolicy", ("net_arch", "actor_net_arch", "param_bounding", "initial_params")),
}
MODEL_SUFFIXES = (".zip", ".aacp")
VIDEO_SUFFIXES = (".gif", ".mp4")

EPILOG = """\
examples:
  sb3-aac train --env RoboCupDribblePaper-v0 --policy RbfPolicy --episodes 3000 --n-envs 16 --seed 0 --out runs/rbf
  sb3-aac train --timesteps 200000 --set n_rbf=30 --set gamma=0.95 --tensorboard runs/tb --progress-bar
  sb3-aac evaluate runs/rbf/model.zip --episodes 1000
  sb3-aac evaluate dribbler --profile v11           # the hand-coded dribbler, for comparison
  sb3-aac reliability runs/rbf/model.zip --out runs/rbf/reliability.png
  sb3-aac render runs/rbf/model.zip --out runs/rbf/episode.gif
  sb3-aac export runs/rbf/model.zip runs/rbf/dribbler.aacp
  sb3-aac bench

MODEL is a SarsaAAC model saved by train (model.zip), a policy exported by export (.aacp), or the word
"dribbler" for the hand-coded dribbler (robocup_dribble.dribbler.HandCodedDribbler).
"""


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


# ---------------------------------------------------------------------------------------------------------------------
# argument checks
# ---------------------------------------------------------------------------------------------------------------------


def _checked(parse: Callable[[str], Any], what: str, accept: Callable[[Any], bool], requirement: str) -> Callable[[str], Any]:
    """An argparse ``type``: parse the text, then check it, with a message saying what is allowed."""

    def convert(text: str) -> Any:
        try:
            value = parse(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
        if not accept(value):
            raise argparse.ArgumentTypeError(f"must be {requirement}, got {text}")
        return value

    return convert


positive_int = _checked(lambda text: int(text.replace("_", "")), "a whole number", lambda v: v >= 1, "positive (>= 1)")
positive_float = _checked(float, "a number", lambda v: v > 0 and math.isfinite(v), "a positive number")
seed_int = _checked(int, "a whole number", lambda v: v >= 0, ">= 0")


def key_value(text: str) -> tuple[str, Any]:
    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected key=value (e.g. gamma=0.95), got {text!r}")
    try:
        value = ast.literal_eval(raw)
    except (ValueError, SyntaxError):
        value = raw  # a bare word such as type_exploration=boltzmann
    return key.strip(), value


def output_file(path: str, suffixes: tuple[str, ...], what: str) -> Path:
    """A file to write, checked before any work: the right extension, not a directory, its folder writable."""
    out = Path(path)
    if out.suffix.lower() not in suffixes:
        raise CliError(f"{what} {path!r} must end with {' or '.join(suffixes)}")
    if out.is_dir():
        raise CliError(f"{what} {path!r} is a directory; give a file name ending with {' or '.join(suffixes)}")
    try:
        return check_writable_file(out, what)
    except ValueError as error:
        raise CliError(str(error)) from None


def output_dir(path: str, what: str) -> Path:
    """A directory to write into, checked before any work (created, then probed with a temporary file)."""
    try:
        return check_writable_dir(path, what)
    except ValueError as error:
        raise CliError(str(error)) from None


@contextlib.contextmanager
def written(out: Path) -> Iterator[Path]:
    """A temporary name (same suffix) that replaces ``out`` in one step once written; a failed write is one line."""
    try:
        with replaced_atomically(out, suffix=out.suffix) as tmp:
            yield tmp
    except OSError as error:
        raise CliError(f"cannot write {out}: {error.strerror or error}") from None


def input_file(path: str, suffixes: tuple[str, ...], what: str) -> Path:
    try:
        return _input_file(Path(path), suffixes, what)
    except (OSError, ValueError) as error:  # a name the system refuses: too long, a NUL byte, a loop of links
        raise CliError(f"{what} {path!r} cannot be used: {getattr(error, 'strerror', None) or error}") from None


def _input_file(source: Path, suffixes: tuple[str, ...], what: str) -> Path:
    path = str(source)
    if source.is_dir() and (source / "model.zip").is_file() and ".zip" in suffixes:
        return source / "model.zip"  # the --out directory of train
    if not source.exists():
        raise CliError(f"{what} {path!r} does not exist (train one with: sb3-aac train --out DIR, then use DIR/model.zip)")
    if source.is_dir():
        raise CliError(f"{what} {path!r} is a directory without a model.zip; give the model file")
    if source.suffix.lower() not in suffixes:
        raise CliError(f"{what} {path!r} must be a {' or '.join(suffixes)} file (a model saved by train or an export)")
    return source


# ---------------------------------------------------------------------------------------------------------------------
# environments and models
# ---------------------------------------------------------------------------------------------------------------------


def register_toy_env() -> None:
    import gymnasium as gym

    if TOY_ENV_ID not in gym.registry:
        gym.register(TOY_ENV_ID, entry_point="sb3_aac.common.envs:ParameterizedTargetEnv")


def import_gym_packages(names: list[str]) -> None:
    import importlib

    for name in names:
        try:
            importlib.import_module(name)
        except (ImportError, TypeError, ValueError) as error:  # TypeError/ValueError: relative or empty names (".", "")
            raise CliError(f"--gym-package {name!r} cannot be imported ({error}); is it installed / on PYTHONPATH?") from None


def check_env_id(env_id: str) -> None:
    import gymnasium as gym

    import robocup_dribble  # noqa: F401  (registers the dribbling ids)

    register_toy_env()
    if env_id not in gym.registry:
        known = [*DRIBBLE_IDS, TOY_ENV_ID]
        raise CliError(
            f"unknown env id {env_id!r}; sb3-aac's ids are {known}. For another parameterized-action env, register it "
            "with gymnasium and pass the module that registers it with --gym-package MODULE"
        )


def max_episode_length(env_id: str) -> int:
    import gymnasium as gym

    if env_id in DRIBBLE_IDS:
        from robocup_dribble import DribbleTask

        return DribbleTask().max_actions
    spec = gym.spec(env_id)
    if spec.max_episode_steps is not None:
        return int(spec.max_episode_steps)
    if env_id == TOY_ENV_ID:
        return 10
    raise CliError(f"{env_id} declares no max_episode_steps, so an --episodes budget has no step bound: use --timesteps")


def make_train_env(env_id: str, n_envs: int, seed: int | None) -> Any:
    if env_id in DRIBBLE_IDS:
        from robocup_dribble import DribbleVecEnv

        env = DribbleVecEnv(n_envs, profile=DRIBBLE_IDS[env_id])
        env.seed(seed)
        return env
    from stable_baselines3.common.env_util import make_vec_env

    try:
        return make_vec_env(env_id, n_envs=n_envs, seed=seed)
    except Exception as error:  # any failure of a third-party env's constructor
        raise CliError(f"cannot make {env_id}: {type(error).__name__}: {error}") from None


def algorithm(algo: str) -> Any:
    """The class ``--algo`` names."""
    import sb3_aac

    return getattr(sb3_aac, ALGOS[algo][0])


def sarsa_keys(algo: str = "sarsa_aac") -> list[str]:
    cls = algorithm(algo)
    return [name for name in inspect.signature(cls.__init__).parameters if name not in ("self", *RESERVED)]


def hyperparameters(pairs: list[tuple[str, Any]], algo: str = "sarsa_aac") -> dict[str, Any]:
    """``--set`` pairs as keyword arguments of ``--algo``'s class; policy arguments go into ``policy_kwargs``."""
    valid = sarsa_keys(algo)
    policy_keys = ALGOS[algo][2]
    kwargs: dict[str, Any] = {}
    policy_kwargs: dict[str, Any] = {}
    for key, value in pairs:
        if key in policy_keys:
            policy_kwargs[key] = value
        elif key in valid:
            kwargs[key] = value
        else:
            hint = " (set it with its own option, e.g. --seed)" if key in RESERVED else ""
            raise CliError(f"unknown --set key {key!r}{hint}; valid keys: {', '.join(sorted([*valid, *policy_keys]))}")
    if policy_kwargs:
        given = kwargs.get("policy_kwargs") or {}
        if not isinstance(given, dict):
            raise CliError(f"policy_kwargs must be a dict literal such as {{'n_rbf': 30}}, got {given!r}")
        kwargs["policy_kwargs"] = {**given, **policy_kwargs}
    return kwargs


def load_policy(model: str, profile: str | None) -> tuple[Any, str]:
    """A policy with ``predict`` and the dribbling profile it plays (given, or inferred from its spaces)."""
    if model == "dribbler":
        from robocup_dribble.dribbler import HandCodedDribbler

        profile = profile or "v19"
        return HandCodedDribbler(profile=profile), profile
    path = input_file(model, MODEL_SUFFIXES, "MODEL")
    if path.suffix.lower() == ".aacp":
        from sb3_aac.runtime import RuntimePolicy

        try:
            policy = RuntimePolicy.load(path)
        except (ValueError, OSError) as error:
            raise CliError(f"cannot load {path}: {error}" if isinstance(error, OSError) else str(error)) from None
        matches = [p for p in PROFILE_ENV_IDS if runtime_matches_profile(policy, p)]
    else:
        policy = load_model(path)
        matches = [p for p in PROFILE_ENV_IDS if model_matches_profile(policy, p)]
    if profile is None:
        if not matches:
            raise CliError(
                f"{path} was not trained on a dribbling env (its spaces match neither {list(PROFILE_ENV_IDS)}); "
                "this command runs the dribbling env, so it needs a dribbling model"
            )
        return policy, matches[0]
    if profile not in matches:
        found = f"it matches {matches[0]}" if matches else "it was not trained on a dribbling env"
        raise CliError(f"{path} does not fit --profile {profile} ({found}); drop --profile to infer it")
    return policy, profile


def load_model(path: Path) -> Any:
    """A model.zip saved by ``train``, whichever ``--algo`` trained it, checked first
    (:func:`~sb3_aac.common.model_files.check_model_file`): any damage is one line."""
    from sb3_aac.common.model_files import check_model_file, load_checked

    errors = []
    try:
        check_model_file(path)
        for algo, (name, _, _) in ALGOS.items():
            try:
                return load_checked(algorithm(algo), path)
            except ValueError as error:
                errors.append(f"as {name}: {error}")
    except ValueError as error:
        raise CliError(str(error)) from None
    except OSError as error:
        raise CliError(f"cannot load {path}: {error}") from None
    raise CliError(f"cannot load {path}: " + "; ".join(errors))


def dribble_spaces(profile: str) -> tuple[Any, Any]:
    from robocup_dribble import DribbleEnv

    env = DribbleEnv(profile=profile)
    return env.observation_space, env.action_space


def model_matches_profile(model: Any, profile: str) -> bool:
    obs_space, action_space = dribble_spaces(profile)
    return model.observation_space == obs_space and model.action_space == action_space


def runtime_matches_profile(policy: Any, profile: str) -> bool:
    import numpy as np

    from sb3_aac.common.spaces import ParameterizedActionSpec

    obs_space, action_space = dribble_spaces(profile)
    spec = ParameterizedActionSpec.from_space(action_space)
    return (
        policy.obs_shape == obs_space.shape
        and np.array_equal(policy.obs_low, obs_space.low.astype(np.float64))
        and np.array_equal(policy.obs_high, obs_space.high.astype(np.float64))
        and policy.layout == spec.layout
        and policy.dims == spec.dims
        and np.array_equal(policy.param_low, spec.low)
        and np.array_equal(policy.param_high, spec.high)
    )


def print_dribble_report(report: Any, title: str) -> None:
    print(title)
    print(f"  mean distance      {report.mean_distance:8.2f} m")
    print(f"  median distance    {float(_median(report.distances)):8.2f} m")
    print(f"  share >= 20 m      {100 * report.share_reaching(20):8.1f} %")
    print(f"  ball-loss rate     {100 * report.loss_rate:8.1f} %   (the others kept it to the action limit)")


def _median(values: Any) -> float:
    import numpy as np

    return float(np.median(values))


# ---------------------------------------------------------------------------------------------------------------------
# subcommands
# ---------------------------------------------------------------------------------------------------------------------


def cmd_train(args: argparse.Namespace) -> None:
    import_gym_packages(args.gym_package)
    check_env_id(args.env)
    kwargs = hyperparameters(args.set, args.algo)
    args.policy = args.policy or ALGOS[args.algo][1]
    if args.algo != "sarsa_aac" and args.policy != "MlpPolicy":
        raise CliError(f"--algo {args.algo} has one policy, MlpPolicy, not {args.policy}")
    if args.tensorboard is not None:
        output_dir(args.tensorboard, "--tensorboard directory")
    publisher = run_publisher(args.out) if args.out is not None else None
    try:
        train_and_publish(args, kwargs, publisher)
    finally:
        if publisher is not None:
            publisher.discard()


def run_publisher(out: str) -> DirectoryPublisher:
    """The ``--out`` directory, checked before training; its files are staged and published as one set."""
    try:
        return DirectoryPublisher(out, "--out directory")
    except ValueError as error:
        raise CliError(str(error)) from None


def save_run(model: Any, publisher: DirectoryPublisher, settings: dict[str, Any]) -> None:
    """Write model.zip, policy.aacp (SarsaAAC only) and run.json into the staging directory, then publish them together."""
    from sb3_aac import export_policy

    staging = publisher.staging
    exported = settings["algo"] == "sarsa_aac"  # the .aacp format carries SarsaAAC's approximators only (docs/pdqn.md)
    try:
        model.save(staging / "model.zip")
        if exported:
            export_policy(model, staging / "policy.aacp", metadata={"env_id": settings["env_id"]})
        (staging / "run.json").write_text(json.dumps(settings, indent=2) + "\n")
        out = publisher.publish()
    except OSError as error:
        raise CliError(f"cannot write the run to {publisher.out}: {error.strerror or error}") from None
    runtime = f", {out / 'policy.aacp'} (RuntimePolicy.load)" if exported else ""
    print(f"saved {out / 'model.zip'} ({ALGOS[settings['algo']][0]}.load){runtime} and {out / 'run.json'}")


def train_and_publish(args: argparse.Namespace, kwargs: dict[str, Any], publisher: DirectoryPublisher | None) -> None:
    name = ALGOS[args.algo][0]
    if args.episodes is not None:
        total_timesteps = args.episodes * max_episode_length(args.env)
        budget = f"{args.episodes} episodes (at most {total_timesteps} steps)"
    else:
        total_timesteps = args.timesteps
        budget = f"{total_timesteps} steps"

    from stable_baselines3.common.callbacks import BaseCallback

    class StopAfterEpisodes(BaseCallback):
        def __init__(self, episodes: int):
            super().__init__()
            self.episodes, self.finished = episodes, 0

        def _on_step(self) -> bool:
            self.finished += int(self.locals["dones"].sum())
            return self.finished < self.episodes

    env = make_train_env(args.env, args.n_envs, args.seed)
    try:
        cls = algorithm(args.algo)
        model = cls(args.policy, env, seed=args.seed, tensorboard_log=args.tensorboard, verbose=args.verbose, **kwargs)
    except (ValueError, TypeError, AssertionError) as error:
        raise CliError(f"cannot build {name}({args.policy}) on {args.env}: {error}") from None
    callback = StopAfterEpisodes(args.episodes) if args.episodes is not None else None
    print(f"training {name} {args.policy} on {args.env} for {budget}, {args.n_envs} env(s), seed {args.seed}")
    start = time.perf_counter()
    try:
        model.learn(total_timesteps, callback=callback, progress_bar=args.progress_bar, tb_log_name=f"{name}_{args.policy}")
    except FloatingPointError as error:
        raise CliError(str(error)) from None
    seconds = time.perf_counter() - start
    episodes = model._episode_num
    print(f"trained {model.num_timesteps} steps ({episodes} episodes) in {seconds:.1f} s")
    if publisher is not None:
        settings = {
            "algo": args.algo,
            "env_id": args.env,
            "policy": args.policy,
            "seed": args.seed,
            "n_envs": args.n_envs,
            "timesteps": model.num_timesteps,
            "episodes": episodes,
            "hyperparameters": {k: repr(v) for k, v in kwargs.items()},
        }
        save_run(model, publisher, settings)
    if args.eval_episodes == 0:
        return
    if args.env in DRIBBLE_IDS:
        from robocup_dribble.evaluation import evaluate_dribbling

        report = evaluate_dribbling(model, args.eval_episodes, profile=DRIBBLE_IDS[args.env], seed=10_000 + (args.seed or 0))
        print_dribble_report(report, f"greedy evaluation on {len(report.distances)} episodes of fresh players:")
    else:
        from stable_baselines3.common.evaluation import evaluate_policy

        eval_env = make_train_env(args.env, 1, 10_000 + (args.seed or 0))
        mean, std = evaluate_policy(model, eval_env, n_eval_episodes=args.eval_episodes, deterministic=True)
        print(f"greedy evaluation over {args.eval_episodes} episodes: return {mean:.3f} +/- {std:.3f}")


def cmd_evaluate(args: argparse.Namespace) -> None:
    from robocup_dribble.evaluation import evaluate_dribbling

    policy, profile = load_policy(args.model, args.profile)
    start = time.perf_counter()
    report = evaluate_dribbling(policy, args.episodes, profile=profile, seed=args.seed)
    print_dribble_report(
        report,
        f"{args.model} on {PROFILE_ENV_IDS[profile]}: {len(report.distances)} greedy episodes of fresh heterogeneous players "
        f"({time.perf_counter() - start:.1f} s)",
    )


def cmd_reliability(args: argparse.Namespace) -> None:
    import numpy as np

    from robocup_dribble.evaluation import reliability_test

    out = output_file(args.out, (".png",), "--out")
    policy, profile = load_policy(args.model, args.profile)
    report = reliability_test(policy, args.players, profile=profile, seed=args.seed)
    print(f"reliability test of {args.model} on {PROFILE_ENV_IDS[profile]}: {args.players} fresh players, one episode each")
    print(f"  {report.summary()}")
    for metres in (5, 10, 15, 20, 25):
        print(f"  reached {metres:2d} m: {100 * report.share_reaching(metres):5.1f} %")
    lost = report.distances[report.ball_lost]
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    top = max(1.0, float(np.ceil(report.distances.max())))
    bins = np.arange(0.0, top + 1.0, 1.0)
    left.hist(lost, bins=bins, color="tab:red", edgecolor="black", linewidth=0.4)
    left.set(
        xlabel="metres dribbled before losing the ball",
        ylabel="players",
        title=f"Ball lost: {len(lost)} of {len(report.distances)} players",
    )
    metres = np.linspace(0.0, top, 400)
    share = (report.distances[None, :] >= metres[:, None]).mean(1) * 100
    right.plot(metres, share, color="tab:blue")
    right.set(xlabel="metres", ylabel="% of players reaching it", title="Cumulative share reaching each distance", ylim=(0, 101))
    right.grid(alpha=0.3)
    fig.suptitle(f"{Path(args.model).name} on {PROFILE_ENV_IDS[profile]} (as Uc-Cetina 2013, Figs. 9-10)")
    fig.tight_layout()
    with written(out) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    print(f"wrote {out}")


def cmd_render(args: argparse.Namespace) -> None:
    from robocup_dribble import DribbleEnv

    out = None if args.window else output_file(args.out, VIDEO_SUFFIXES, "--out")
    if out is not None and out.suffix.lower() == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise CliError("writing .mp4 needs imageio-ffmpeg (pip install imageio-ffmpeg); or write a .gif") from None
    policy, profile = load_policy(args.model, args.profile)
    try:
        env = DribbleEnv(profile=profile, render_mode="human" if args.window else "rgb_array")
        obs, info = env.reset(seed=args.seed)
        frames = [] if args.window else [env.render()]
    except Exception as error:  # pygame missing or no display
        raise CliError(f"cannot render: {error}") from None
    done, steps = False, 0
    while not done:
        action, _ = policy.predict(obs, deterministic=True)
        obs, _, terminated, truncated, info = env.step(action)
        done, steps = terminated or truncated, steps + 1
        if not args.window:
            frames.append(env.render())
    env.close()
    outcome = "lost the ball" if info["ball_lost"] else "kept the ball to the action limit"
    print(f"one episode of {args.model} on {PROFILE_ENV_IDS[profile]}: {steps} actions, {info['distance']:.2f} m, {outcome}")
    if out is None:
        return
    import imageio.v2 as imageio

    with written(out) as tmp:
        if out.suffix.lower() == ".gif":
            imageio.mimsave(tmp, frames, duration=1000 / args.fps, loop=0)
        else:
            imageio.mimsave(tmp, frames, fps=args.fps)
    print(f"wrote {out} ({len(frames)} frames)")


def cmd_export(args: argparse.Namespace) -> None:
    from sb3_aac import RuntimePolicy, export_policy

    source = input_file(args.model, (".zip",), "MODEL")
    out = output_file(args.out, (".aacp",), "OUT")
    model = load_model(source)
    matches = [p for p in PROFILE_ENV_IDS if model_matches_profile(model, p)]
    metadata = {"env_id": PROFILE_ENV_IDS[matches[0]]} if matches else {}
    try:
        path = export_policy(model, out, metadata=metadata)
    except OSError as error:
        raise CliError(f"cannot write {out}: {error.strerror or error}") from None
    policy = RuntimePolicy.load(path)
    print(f"wrote {path} ({path.stat().st_size} bytes): {policy!r}")
    print("load it with: from sb3_aac.runtime import RuntimePolicy; RuntimePolicy.load(path).act(obs)  (numpy only)")


def cmd_bench(args: argparse.Namespace) -> None:
    root = Path(__file__).resolve().parents[1]
    scripts = [root / "benchmarks" / "env_speed.py", root / "benchmarks" / "runtime_speed.py"]
    missing = [str(s) for s in scripts if not s.is_file()]
    if missing:
        raise CliError(f"bench runs the scripts of a source checkout, missing: {missing}; clone the repository")
    runs = [
        [str(scripts[0]), "--seconds", str(args.seconds)],
        [str(scripts[1]), *([] if args.full else ["--quick"])],
    ]
    if args.only is not None:
        runs = [runs[("env", "runtime").index(args.only)]]
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(root), str(root / "envs"), env.get("PYTHONPATH")]))
    for run in runs:
        print(f"$ python {' '.join(Path(run[0]).relative_to(root).parts)} {' '.join(run[1:])}", flush=True)
        result = subprocess.run([sys.executable, *run], env=env, check=False)
        if result.returncode != 0:
            raise CliError(f"{Path(run[0]).name} failed with exit status {result.returncode}")


# ---------------------------------------------------------------------------------------------------------------------
# parser
# ---------------------------------------------------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="sb3-aac",
        description="Train, evaluate, watch and export SARSA Actor-Actor-Critic (SarsaAAC) agents, e.g. RoboCup dribblers.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    from sb3_aac import __version__

    parser.add_argument("--version", action="version", version=f"sb3-aac {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    def add(name: str, help_text: str, epilog: str, parents: tuple[argparse.ArgumentParser, ...] = ()) -> argparse.ArgumentParser:
        return sub.add_parser(
            name, help=help_text, description=help_text, epilog="example:\n  " + epilog,
            formatter_class=argparse.RawDescriptionHelpFormatter, parents=list(parents),
        )

    # MODEL, --profile and --seed mean the same for every command that plays a trained policy
    played = argparse.ArgumentParser(add_help=False)
    played.add_argument("model", metavar="MODEL", help="model.zip, an exported .aacp, or 'dribbler'")
    played.add_argument("--profile", choices=list(PROFILE_ENV_IDS), help="server profile (default: inferred from MODEL's spaces)")
    played.add_argument("--seed", type=seed_int, default=0, help="seed of the players, starts and noise (default: %(default)s)")

    train = add(
        "train",
        "train SarsaAAC, then print a greedy evaluation (metres, share >= 20 m, ball-loss rate)",
        "sb3-aac train --env RoboCupDribblePaper-v0 --episodes 3000 --n-envs 16 --set n_rbf=30 --out runs/rbf",
    )
    train.add_argument("--env", default="RoboCupDribblePaper-v0", help="registered env id (default: %(default)s)")
    train.add_argument("--algo", default="sarsa_aac", choices=list(ALGOS), help="algorithm (default: %(default)s)")
    train.add_argument(
        "--policy", choices=POLICIES, help="function approximators (default: RbfPolicy; MlpPolicy for pdqn/mpdqn)"
    )
    budget = train.add_mutually_exclusive_group()
    budget.add_argument("--timesteps", type=positive_int, help="training budget in env steps (default: 100000)")
    budget.add_argument(
        "--episodes", type=positive_int, help="training budget in episodes (schedules span episodes x max episode length steps)"
    )
    train.add_argument("--n-envs", type=positive_int, default=16, help="envs stepped side by side (default: %(default)s)")
    train.add_argument("--seed", type=seed_int, default=0, help="random seed (default: %(default)s)")
    train.add_argument("--tensorboard", metavar="DIR", help="write TensorBoard logs here (view: tensorboard --logdir DIR)")
    train.add_argument("--progress-bar", action="store_true", help="show a progress bar (tqdm, rich)")
    train.add_argument("--out", metavar="DIR", help="save DIR/model.zip, DIR/policy.aacp (exported) and DIR/run.json")
    train.add_argument(
        "--set",
        metavar="KEY=VALUE",
        type=key_value,
        action="append",
        default=[],
        help="a hyperparameter of --algo's class as a Python literal, repeatable: gamma=0.95, learning_rate=0.2, "
        "type_exploration=boltzmann; policy arguments (n_rbf, hidden_units, rbf_width; for pdqn/mpdqn net_arch, "
        "actor_net_arch, param_bounding, initial_params) go into policy_kwargs",
    )
    train.add_argument("--eval-episodes", type=int, default=1000, help="greedy evaluation episodes after training (0: none)")
    train.add_argument("--gym-package", action="append", default=[], metavar="MODULE", help="import MODULE first (registers envs)")
    train.add_argument("--verbose", type=int, default=0, choices=(0, 1, 2), help="SB3 verbosity: 1 prints the log table")
    train.set_defaults(func=cmd_train)

    evaluate = add(
        "evaluate",
        "greedy metrics of MODEL on fresh heterogeneous players",
        "sb3-aac evaluate runs/rbf/model.zip --episodes 1000   |   sb3-aac evaluate dribbler --profile v11",
        (played,),
    )
    evaluate.add_argument("--episodes", type=positive_int, default=1000, help="episodes (default: %(default)s)")
    evaluate.set_defaults(func=cmd_evaluate)

    reliability = add(
        "reliability",
        "the paper's reliability test: fresh players dribble once each; prints a summary, plots Figs. 9-10 to a PNG",
        "sb3-aac reliability runs/rbf/model.zip --out runs/rbf/reliability.png",
        (played,),
    )
    reliability.add_argument("--players", type=positive_int, default=10_000, help="players (default: %(default)s, as the paper)")
    reliability.add_argument("--out", default="reliability.png", help="PNG to write (default: %(default)s)")
    reliability.set_defaults(func=cmd_reliability)

    render = add(
        "render", "play one greedy episode to a GIF/MP4 or a window", "sb3-aac render runs/rbf/model.zip --out episode.gif", (played,)
    )
    render.add_argument("--out", default="episode.gif", help="video file, .gif or .mp4 (default: %(default)s)")
    render.add_argument("--window", action="store_true", help="show the episode in a pygame window instead of writing a file")
    render.add_argument("--fps", type=positive_float, default=10.0, help="frames per second (default: %(default)s, server cycles)")
    render.set_defaults(func=cmd_render)

    export = add(
        "export",
        "write MODEL's policy as plain arrays + JSON for a runtime without torch (sb3_aac.runtime.RuntimePolicy, C++)",
        "sb3-aac export runs/rbf/model.zip dribbler.aacp",
    )
    export.add_argument("model", metavar="MODEL", help="a SarsaAAC model.zip")
    export.add_argument("out", metavar="OUT", help="the policy file to write (.aacp); format: docs/export-format.md")
    export.set_defaults(func=cmd_export)

    bench = add("bench", "quick speed benchmarks: env steps/s and us per decision of an exported policy", "sb3-aac bench")
    bench.add_argument("--seconds", type=positive_float, default=0.3, help="env benchmark budget per figure (default: %(default)s)")
    bench.add_argument("--only", choices=("env", "runtime"), help="run one of the two benchmarks")
    bench.add_argument("--full", action="store_true", help="the full runtime benchmark (all policies and sizes; a minute)")
    bench.set_defaults(func=cmd_bench)

    from sb3_aac.cli_tune import add_tune_command

    add_tune_command(add)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``sb3-aac``. Returns 0; errors exit with status 2 and one line on stderr."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command == "train" and args.timesteps is None and args.episodes is None:
        args.timesteps = 100_000
    if args.command == "train" and args.eval_episodes < 0:
        parser.error("--eval-episodes must be >= 0")
    try:
        with terminate_as_interrupt():
            args.func(args)
    except (CliError, OSError) as error:  # OSError: a file the user named failed in a way no check foresaw
        message = " ".join(str(error).split())  # one line, whatever the error's text holds
        print(f"sb3-aac {args.command}: error: {message}", file=sys.stderr)
        raise SystemExit(2) from None
    except KeyboardInterrupt:
        print(f"sb3-aac {args.command}: interrupted", file=sys.stderr)
        raise SystemExit(130) from None
    return 0


@contextlib.contextmanager
def terminate_as_interrupt() -> Iterator[None]:
    """SIGTERM (``kill``) raises KeyboardInterrupt while a command runs, so its cleanup (temporaries) runs as for
    Ctrl-C. Only in the main thread, where Python allows signal handlers; the previous handler is restored."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    # Run the imported sb3_aac.cli, not this __main__ copy, so that CliError raised by sb3_aac.cli_tune is the one caught.
    from sb3_aac.cli import main as package_main

    sys.exit(package_main())
