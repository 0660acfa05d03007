"""What every command checks in its arguments: argparse types that say what is allowed, and input and output paths
checked before any work. A user error is a :class:`CliError`: one line, exit status 2."""

from __future__ import annotations

import argparse
import contextlib
import importlib
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from sb3_aac.common.output_files import check_writable_dir, check_writable_file, replaced_atomically


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


def require_extra(extra: str, what: str, *modules: str) -> None:
    """Check, before any work, that the optional ``modules`` of ``what`` import; one line naming the extra otherwise."""
    for module in modules:
        try:
            importlib.import_module(module)
        except ImportError as error:
            raise CliError(f"{what} needs {module} ({error}): pip install 'sb3-aac[{extra}]'") from None


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


def _whole(text: str) -> int:
    return int(text.replace("_", ""))


positive_int = _checked(_whole, "a whole number", lambda v: v >= 1, "positive (>= 1)")
positive_float = _checked(float, "a number", lambda v: v > 0 and math.isfinite(v), "a positive number")

# Limits of sizes and numbers a command accepts, so that a typo is a one-line refusal rather than an allocation
# that fails after minutes (or a traceback from deep inside numpy or torch).
MAX_SEED = 2**32 - 1  # numpy's legacy seeding, which SB3's set_random_seed calls, takes 0 .. 2**32 - 1
MAX_LANES = 65_536  # envs stepped side by side: 4,096 lanes already saturate a core
MAX_EPISODES = 10_000_000
MAX_TIMESTEPS = 10**11  # env steps: days of training at millions of steps a second
MIN_FPS, MAX_FPS = 0.1, 1000.0
seed_int = _checked(_whole, "a whole number", lambda v: 0 <= v <= MAX_SEED, f"in 0 .. {MAX_SEED} (2**32 - 1)")
lane_count = _checked(_whole, "a whole number", lambda v: 1 <= v <= MAX_LANES, f"in 1 .. {MAX_LANES:,}")
episode_count = _checked(_whole, "a whole number", lambda v: 1 <= v <= MAX_EPISODES, f"in 1 .. {MAX_EPISODES:,}")
episode_count_or_zero = _checked(_whole, "a whole number", lambda v: 0 <= v <= MAX_EPISODES, f"in 0 .. {MAX_EPISODES:,}")
step_count = _checked(_whole, "a whole number", lambda v: 1 <= v <= MAX_TIMESTEPS, f"in 1 .. {MAX_TIMESTEPS:.0e}")
frame_rate = _checked(float, "a number", lambda v: MIN_FPS <= v <= MAX_FPS, f"in {MIN_FPS} .. {MAX_FPS:g} frames per second")


def add_trust_argument(parser: argparse.ArgumentParser) -> None:
    """``--trust``: load a model.zip with its pickled entries (which runs code from the file), as SB3's ``load`` does."""
    parser.add_argument(
        "--trust",
        action="store_true",
        help="load a model.zip whose pickled entries this command cannot stand in for (runs code from the file: only "
        "for files you or someone you trust made; by default nothing of a model.zip is unpickled)",
    )


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
