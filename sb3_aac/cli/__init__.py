"""
The ``sb3-aac`` command line: train SarsaAAC, P-DQN, MP-DQN or HybridPPO, measure, watch and export the result.

Run ``sb3-aac --help`` (or ``python -m sb3_aac.cli --help``) for the subcommands and examples. Errors print one line
saying what to do and exit with status 2, without a traceback. Each command is a module of this package with its
parser (``add_*_command``) and its ``cmd_*``; :func:`build_parser` assembles them and :func:`main` runs one.
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import threading
from collections.abc import Iterator
from typing import Any

from sb3_aac.cli.arguments import CliError, add_trust_argument, seed_int
from sb3_aac.cli.bench import add_bench_command
from sb3_aac.cli.envs import PROFILE_ENV_IDS
from sb3_aac.common.algorithms import SettingsError
from sb3_aac.version import __version__
from sb3_aac.cli.evaluate import add_evaluate_commands
from sb3_aac.cli.export import add_c_header_command, add_export_command
from sb3_aac.cli.pitch import add_pitch_command
from sb3_aac.cli.push import add_push_command
from sb3_aac.cli.render import add_render_command
from sb3_aac.cli.train import add_train_command
from sb3_aac.cli.tune import add_tune_command

__all__ = ["CliError", "build_parser", "main"]

EPILOG = """\
examples:
  sb3-aac train --env RoboCupDribblePaper-v0 --policy RbfPolicy --episodes 3000 --n-envs 16 --seed 0 --out runs/rbf
  sb3-aac train --timesteps 200000 --set gamma=0.95 --tensorboard runs/tb --progress-bar   # DeepPolicy, the default
  sb3-aac train --algo mpdqn --env RoboCupDribblePaper-v0 --timesteps 200000 --out runs/mpdqn
  sb3-aac evaluate runs/rbf/model.zip --episodes 1000
  sb3-aac evaluate dribbler --profile v11           # the hand-coded dribbler, for comparison
  sb3-aac reliability runs/rbf/model.zip --out runs/rbf/reliability.png
  sb3-aac render runs/rbf/model.zip --out runs/rbf/episode.gif
  sb3-aac export runs/rbf/model.zip runs/rbf/dribbler.aacp
  sb3-aac c-header                                  # aacp.h: the .aacp reader for C/C++ agents
  sb3-aac push runs/rbf/model.zip --repo-id you/sarsa-aac-dribble
  sb3-aac pitch runs/tile/model.zip --server PATH/rcssserver --episodes 1000   # a real rcssserver 19 against the env
  sb3-aac bench

MODEL is a model saved by train (model.zip: SarsaAAC, P-DQN, MP-DQN or HybridPPO), a policy exported by export
(.aacp), or the word "dribbler" for the hand-coded dribbler (robocup_dribble.dribbler.HandCodedDribbler).
"""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="sb3-aac",
        description="Train, evaluate, watch and export parameterized-action agents (SarsaAAC, P-DQN, MP-DQN, HybridPPO), "
        "e.g. RoboCup dribblers.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"sb3-aac {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    def add(
        name: str, help_text: str, epilog: str, parents: tuple[argparse.ArgumentParser, ...] = ()
    ) -> argparse.ArgumentParser:
        return sub.add_parser(
            name,
            help=help_text,
            description=help_text,
            epilog="example:\n  " + epilog,
            formatter_class=argparse.RawDescriptionHelpFormatter,
            parents=list(parents),
        )

    # MODEL, --profile and --seed mean the same for every command that plays a trained policy
    played = argparse.ArgumentParser(add_help=False)
    played.add_argument("model", metavar="MODEL", help="model.zip, an exported .aacp, or 'dribbler'")
    played.add_argument(
        "--profile", choices=list(PROFILE_ENV_IDS), help="server profile (default: inferred from MODEL's spaces)"
    )
    played.add_argument(
        "--seed", type=seed_int, default=0, help="seed of the players, starts and noise (default: %(default)s)"
    )
    add_trust_argument(played)

    add_train_command(add)
    add_evaluate_commands(add, played)
    add_render_command(add, played)
    add_export_command(add)
    add_c_header_command(add)
    add_pitch_command(add, played)
    add_push_command(add)
    add_bench_command(add)
    add_tune_command(add)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``sb3-aac``. Returns 0; errors exit with status 2 and one line on stderr."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with terminate_as_interrupt():
            args.func(args)
    except (CliError, SettingsError, OSError) as error:  # OSError: a file the user named failed in a way no check foresaw
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
