"""Run the benchmark grid: SarsaAAC's approximators and SB3 baselines on the dribbling envs, resumable and parallel.

Usage::

    python -m benchmarks.run --preset quick|full [--out DIR] [--workers 2] [--only PATTERN[,PATTERN...]]
                             [--engine local|ray [--address ADDR]] [--allow-dirty] [--shard I/N]
    python -m benchmarks.run --preset full --estimate [--only ...] [--cores N[,N...]]  # core-hours, run nothing
    python -m benchmarks.run --reliability [--out DIR]      # the reliability test of the best policies
    python -m benchmarks.run --tune --preset P [--trials N] [--storage JOURNAL_OR_URL] [--only ...] [--engine ...]
    python -m benchmarks.run --preset full --only 'goal__SarsaAAC-deep__s[0-4]__*' --set replay_ratio=3 --out DIR
    python -m benchmarks.report DIR                         # report.md and figures from the cell files

Each cell (env id x algorithm x config x seed x budget, see :mod:`benchmarks.presets`) trains through SB3's
``learn`` with a TensorBoard logger (``DIR/tb/<cell_id>``) and :class:`DribbleEvalCallback`, which every
``eval_every`` training episodes plays the same ``eval_episodes`` greedy episodes (``evaluate_dribbling`` with a fixed
seed) and logs ``eval/distance_mean``, ``eval/reach20_share`` and ``eval/ball_loss_rate``. A finished cell saves its
model (``DIR/models/<cell_id>.zip``) and then its results (``DIR/cells/<cell_id>.json``), each written to a temporary
file and moved into place with ``os.replace``, so a cell file exists only if the cell finished. A rerun skips the
cells that have one: an interrupted sweep loses only the cells that were running. A cell that raises leaves
``DIR/errors/<cell_id>.txt`` (the traceback) and is tried again by the next run.

Cells run in worker processes (``ProcessPoolExecutor``, spawn); each pins torch and BLAS to one thread, so two
workers use two cores. ``--workers 1`` runs the cells in this process. ``--engine ray`` runs each cell as a Ray task
instead, on a Ray cluster (``--address``) or a Ray instance started here with ``--workers`` CPUs; the driver writes
every cell's files (:mod:`benchmarks.engines`).

A sweep refuses to start when tracked files have uncommitted changes, unless ``--allow-dirty`` (recorded in every
cell with the commit, :mod:`benchmarks.provenance`); ``DIR/runs.jsonl`` logs every invocation when it starts and
when it ends, interrupted ones too.

``--shard I/N`` runs shard I of the grid split N ways (:mod:`benchmarks.shards`), for N machines each with its
own results folder; ``python -m benchmarks.merge`` puts the folders together for one report.

``--estimate`` prints what the preset (or its ``--only`` cells and studies) costs, per stage (the grid's main
budgets, the long budgets, the equal wall-clock budget, the tuning stage) and env, in core-hours
(:mod:`benchmarks.cost`), and with ``--cores`` its wall time on that many cores; it runs nothing.

``--set KEY=VALUE`` (repeatable; the value a Python literal) runs the selected cells with that SarsaAAC keyword
argument (a policy argument goes into ``policy_kwargs``), e.g. to try a candidate default on the grid's seeds and
budgets; it takes untuned SarsaAAC cells only and belongs in a folder of its own (each cell records its overrides,
and the committed results' test refuses cells that are not the preset's).

``--tune`` runs the tuning stage instead of the grid (:mod:`benchmarks.tuning`): one Optuna study per tuned learner
and env of the preset, their best settings written to ``hyperparams/tuned/<env id>/<learner>.yml`` (``--tuned-dir``
another folder), which the grid's ``<config>-tuned`` cells read.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import signal
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from benchmarks import cells
from benchmarks.cost import estimate_text, wall_text
from benchmarks.execution import run_grid
from benchmarks.engines import RayEngine
from benchmarks.presets import PRESETS, Cell, build_cells, is_tuned, select
from benchmarks.provenance import (
    ENV_VAR,
    REPO,
    RUN_LOG,
    DirtyTreeError,
    invocation_provenance,
    logged_invocation,
    new_invocation_id,
    require_clean_tree,
)
from benchmarks.reliability import RELIABILITY_PLAYERS, run_reliability
from benchmarks.shards import Shard
from benchmarks.tuned import TUNED_DIR_VAR, resolve_tuned, tuned_dir
from benchmarks.tuning import plan_studies, run_tuning
from sb3_aac.common.algorithms import SettingsError, hyperparameters, key_value
from sb3_aac.common.output_files import check_writable_dir


def _exit_on_sigterm(signum: int, frame: Any) -> None:
    raise SystemExit(128 + signum)


def _positive_int(text: str) -> int:
    """An argparse type: a whole number >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def _positive_ints(text: str) -> list[int]:
    """An argparse type: comma-separated whole numbers >= 1, at least one."""
    return [_positive_int(part) for part in text.split(",")]


def _shard(text: str) -> Shard:
    """An argparse type: shard I of N (:meth:`benchmarks.shards.Shard.parse`)."""
    try:
        return Shard.parse(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _patterns(text: str) -> str:
    """An argparse type: comma-separated cell-id patterns, at least one (an empty --only, e.g. an unset shell
    variable, would otherwise select every cell)."""
    if not any(p.strip() for p in text.split(",")):
        raise argparse.ArgumentTypeError(f"expected at least one pattern (e.g. sarsa_aac or 'hppo-*'), got {text!r}")
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.run", description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", choices=sorted(PRESETS), help="the grid to run")
    parser.add_argument("--out", default=None, help="results directory (default: runs/bench-<preset>)")
    parser.add_argument("--workers", type=_positive_int, default=2, help="worker processes (1: run in this process)")
    parser.add_argument(
        "--only",
        type=_patterns,
        default=None,
        help="comma-separated glob patterns of cell ids (a plain word matches as a substring)",
    )
    parser.add_argument(
        "--shard",
        type=_shard,
        default=None,
        help="run shard I of the grid split N ways (one per machine, each its own --out; then benchmarks.merge)",
    )
    parser.add_argument("--list", action="store_true", help="list the cells (and whether they are finished), run nothing")
    parser.add_argument(
        "--estimate", action="store_true", help="print the core-hours per stage (grid, long, wall-clock, tuning), run nothing"
    )
    parser.add_argument(
        "--cores", type=_positive_ints, default=None, help="with --estimate: also the wall time on N[,N...] cores"
    )
    parser.add_argument("--reliability", action="store_true", help="run the reliability test of the best policies in --out")
    parser.add_argument("--players", type=_positive_int, default=RELIABILITY_PLAYERS, help="players of the reliability test")
    parser.add_argument(
        "--engine", choices=("local", "ray"), default="local", help="local process pool, or one Ray task per cell"
    )
    parser.add_argument(
        "--address", default=None, help="the Ray cluster to join (default: start Ray here with --workers CPUs)"
    )
    parser.add_argument(
        "--allow-dirty",
        action="store_true",
        help="run although tracked files have uncommitted changes (recorded in each cell)",
    )
    parser.add_argument("--tune", action="store_true", help="run the preset's tuning stage (not the grid)")
    parser.add_argument("--trials", type=_positive_int, default=None, help="finished trials per study (default: the preset's)")
    parser.add_argument(
        "--storage",
        default=None,
        help="one Optuna journal file or database URL for all studies (default: a journal per study)",
    )
    parser.add_argument("--tuned-dir", default=None, help="folder of the tuned settings (default: hyperparams/tuned)")
    parser.add_argument(
        "--set",
        metavar="KEY=VALUE",
        type=key_value,
        action="append",
        default=[],
        help="a SarsaAAC keyword argument for every selected cell (repeatable; untuned SarsaAAC cells only)",
    )
    args = parser.parse_args(argv)
    signal.signal(signal.SIGTERM, _exit_on_sigterm)  # `kill` runs the cleanup of run_grid (workers end with us)
    _check_combinations(parser, args)
    tuning = _tuning_arguments(parser, args)
    if args.estimate or tuning:
        return (estimate if args.estimate else tune)(parser, args)
    out = Path(args.out or f"runs/bench-{args.preset or 'full'}")
    if not args.list:
        try:
            check_writable_dir(out, "--out")
            cells.check_results_folder(out, (RUN_LOG,))
        except ValueError as error:
            parser.error(str(error))
    os.environ["SB3_AAC_BENCH_COMMAND"] = "python -m benchmarks.run " + " ".join(
        shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv)
    )
    if args.preset:
        grid = _with_settings(parser, _with_tuned_settings(_grid(parser, args)), args.set)
        if args.list:
            for cell in grid:
                print(f"{'done' if cells.is_finished(out, cell) else 'todo'}  {cell.cell_id}")
            return 0
        start = time.time()
        invocation = new_invocation_id()
        fields = {
            "command": os.environ["SB3_AAC_BENCH_COMMAND"],
            "workers": args.workers,
            "engine": args.engine,
            "allow_dirty": args.allow_dirty,
            **({"shard": str(args.shard)} if args.shard else {}),
        }
        try:
            with logged_invocation(out, invocation=invocation, **fields) as log:
                state = require_clean_tree(REPO, args.allow_dirty, ignore=(out,))
                os.environ[ENV_VAR] = json.dumps(invocation_provenance(invocation, state, args.allow_dirty))
                engine = RayEngine(args.address, num_cpus=args.workers) if args.engine == "ray" else None
                if engine is not None:
                    engine.check_address()
                try:
                    status = run_grid(grid, out, args.workers, engine=engine)
                finally:
                    del os.environ[ENV_VAR]  # later run_grid calls of this process are not this invocation's
                log.update({k: len(v) for k, v in status.items()})
        except (DirtyTreeError, ConnectionError) as error:
            print(f"refused: {error}", file=sys.stderr)
            return 2
        print(
            f"{len(status['done'])} cells done, {len(status['skipped'])} skipped, {len(status['failed'])} failed "
            f"in {time.time() - start:.0f} s; results in {out}"
        )
        if status["failed"]:
            print("failed (tracebacks in errors/): " + ", ".join(status["failed"]))
        if status["busy"]:
            print("running in another process (not started here): " + ", ".join(status["busy"]))
    if args.reliability:
        run_reliability(out, args.players)
        print(f"reliability test written to {out / 'reliability.json'}")
    return 1 if args.preset and status["failed"] else 0


def _check_combinations(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Exit (2) naming the problem if the options given do not go together."""
    if not args.preset and not args.reliability:
        parser.error("give --preset (run the grid) and/or --reliability")
    if args.address and args.engine != "ray":
        parser.error("--address needs --engine ray")
    if args.cores and not args.estimate:
        parser.error("--cores belongs to --estimate")
    if args.set and (args.estimate or args.tune or not args.preset):
        parser.error("--set belongs to a grid run (--preset, without --estimate or --tune)")
    if args.shard and (args.estimate or args.tune or args.reliability):
        parser.error(
            "--shard splits the grid run only (not --estimate, --tune or --reliability; the reliability test runs on "
            "the merged folder, see benchmarks.merge)"
        )


def _grid(parser: argparse.ArgumentParser, args: argparse.Namespace) -> list[Cell]:
    """The preset's cells matching ``--only``, of ``--shard`` if given; exits (2) if there are none."""
    every = build_cells(args.preset)
    grid = select(every, args.only)
    if not grid:
        parser.error(f"--only {args.only!r} matches none of the {len(every)} cells of preset {args.preset!r} (see --list)")
    if args.shard:
        if len(grid) < args.shard.count:
            parser.error(f"--shard {args.shard}: the grid has {len(grid)} cells, too few for {args.shard.count} shards")
        grid = args.shard.cells(grid)
    return grid


def estimate(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """``--estimate``: the preset's core-hours per stage and env (:func:`benchmarks.cost.estimate_text`)."""
    if not args.preset or args.reliability or args.list or args.tune:
        parser.error("--estimate needs --preset and runs nothing else (no --reliability, --list or --tune)")
    if not select(build_cells(args.preset), args.only) and args.only:
        parser.error(f"--only {args.only!r} matches none of the cells of preset {args.preset!r} (see --list)")
    print(f"Estimated cost of preset {args.preset!r}{f' (--only {args.only})' if args.only else ''}, core-hours:")
    print(estimate_text(args.preset, args.only))
    if args.cores:
        print("\nEstimated wall time on N cores (each core takes the longest cell or trial still waiting; the tuning "
              "stage first):")  # fmt: skip
        print(wall_text(args.preset, args.cores, args.only))
    return 0


def _with_tuned_settings(grid: list[Cell]) -> list[Cell]:
    """The grid's tuned cells with their settings (:func:`benchmarks.tuned.resolve_tuned`); exits (2) if some lack them."""
    try:
        return resolve_tuned(grid)
    except ValueError as error:
        print(f"refused: {error}; or leave the tuned cells out with --only", file=sys.stderr)
        raise SystemExit(2) from None


def _with_settings(parser: argparse.ArgumentParser, grid: list[Cell], pairs: list[tuple[str, Any]]) -> list[Cell]:
    """The cells with ``--set``'s keyword arguments added to their overrides; exits (2) naming the problem if a cell
    is not an untuned SarsaAAC cell or a key is not SarsaAAC's."""
    if not pairs:
        return grid
    others = [cell.cell_id for cell in grid if cell.algo != "SarsaAAC" or is_tuned(cell.config)]
    if others:
        shown = ", ".join(others[:3]) + (f" and {len(others) - 3} more" if len(others) > 3 else "")
        parser.error(f"--set applies to untuned SarsaAAC cells only, and --only selects {shown}")
    try:
        settings = hyperparameters(pairs)
    except SettingsError as error:
        parser.error(str(error))
    return [replace(cell, overrides={**cell.overrides, **settings}) for cell in grid]


def _tuning_arguments(parser: argparse.ArgumentParser, args: argparse.Namespace) -> bool:
    """Check the tuning options and make ``--tuned-dir`` the cells' folder of tuned settings; whether to tune."""
    if (args.trials or args.storage) and not args.tune:
        parser.error("--trials and --storage belong to --tune")
    if args.tuned_dir:
        os.environ[TUNED_DIR_VAR] = str(Path(args.tuned_dir).resolve())  # read by the cells, here and in Ray tasks
    return bool(args.tune)


def tune(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """The tuning stage: every argument, the tuned folder and every study's storage checked before any trial runs."""
    if args.reliability or args.list:
        parser.error("--tune runs only the tuning stage (no --reliability or --list)")
    try:
        studies = plan_studies(args.preset, args.trials, args.only)
        folder = check_writable_dir(tuned_dir(), "--tuned-dir")
    except ValueError as error:
        parser.error(str(error))
    engine = RayEngine(args.address, num_cpus=args.workers) if args.engine == "ray" else None
    start = time.time()
    try:
        if engine is not None:
            engine.check_address()
        status = run_tuning(studies, args.storage, folder, args.workers, engine)
    except (ValueError, ConnectionError) as error:
        print(f"refused: {error}", file=sys.stderr)
        return 2
    print(f"{len(status['done'])} studies tuned, {len(status['failed'])} failed in {time.time() - start:.0f} s; "
          f"tuned settings in {folder}")  # fmt: skip
    if status["failed"]:
        print("failed (no trial finished in a round): " + ", ".join(status["failed"]))
    return 1 if status["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
