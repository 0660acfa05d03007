"""
Two results folders cell for cell: the same cells (env, learner, seed, budget) run with other settings, such as a
candidate default run with ``benchmarks.run --set`` against the grid's own cells::

    python -m benchmarks.run --preset full --only '*__SarsaAAC-deep__s[0-4]__*k' --set replay_ratio=3 --out DIR
    python -m benchmarks.compare benchmarks/results DIR [--min-seeds 5]

For each group of cells (env, learner, budget; a wall-clock cell's budget is its seconds, its env-step horizon
follows the learner's training rate and may differ between the folders) with seeds in both folders, on the seeds
both hold: each side's settings (the cells' overrides), mean and IQM of the final score (the env's metric), and the verdict of
:func:`benchmarks.significance.compare` on B against A (Welch's two-sided test on the difference of the means;
"too few seeds" below ``--min-seeds``, by default the report's :data:`~benchmarks.significance.MIN_SEEDS`).
Groups only one folder holds are left out, and so are the references.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.cells import load_cells
from benchmarks.groups import Group, group_results
from benchmarks.presets import budget_label
from benchmarks.significance import MIN_SEEDS, compare, iqm
from benchmarks.tuned import TUNED_PARAMS, TUNING_RECORD

SWAPPED = {"A better": "B better", "B better": "A better"}  # compare(B's scores, A's) names B "A"


def _by_group(folder: Path) -> dict[tuple[str, str, str, int, int], Group]:
    """The report's groups of a folder (:func:`benchmarks.groups.group_results`) by env, algo, config, budget (0 for a
    wall-clock group: its horizon is not its budget), seconds."""
    groups, _ = group_results(load_cells(folder))
    return {(g.env_id, g.algo, g.config, 0 if g.seconds else g.budget, g.seconds): g for env in groups.values() for g in env}


def _settings(runs: list[dict[str, Any]]) -> str:
    """The overrides the runs share, as text (``defaults`` when none; a tuned cell's: its study)."""
    texts = {json.dumps(r["cell"].get("overrides", {}), sort_keys=True) for r in runs}
    if len(texts) > 1:
        return "mixed overrides"
    overrides = json.loads(texts.pop())
    if TUNED_PARAMS in overrides:
        return f"tuned ({overrides.get(TUNING_RECORD, {}).get('study', 'study not recorded')})"
    return ", ".join(f"{k}={v!r}" for k, v in overrides.items()) or "defaults"


def compare_folders(a: Path, b: Path, min_seeds: int = MIN_SEEDS) -> list[str]:
    """Markdown lines: one table row per group both folders hold (see the module docstring)."""
    groups_a, groups_b = _by_group(a), _by_group(b)
    header = [
        f"A: {a}; B: {b}; verdict of B against A (Welch, two-sided, at least {min_seeds} seeds a side)",
        "",
        "| env | learner | budget | seeds | A settings | B settings | A mean (IQM) | B mean (IQM) | B - A | Welch p "
        "| verdict |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    rows = []
    for key in sorted(set(groups_a) & set(groups_b)):
        group_a, group_b = groups_a[key], groups_b[key]
        by_seed_a = {r["cell"]["seed"]: r for r in group_a.runs}
        by_seed_b = {r["cell"]["seed"]: r for r in group_b.runs}
        seeds = sorted(set(by_seed_a) & set(by_seed_b))
        if not seeds:
            continue
        runs_a, runs_b = [by_seed_a[s] for s in seeds], [by_seed_b[s] for s in seeds]
        sa = np.array([r["final"][group_a.metric] for r in runs_a], dtype=float)
        sb = np.array([r["final"][group_b.metric] for r in runs_b], dtype=float)
        result = compare(sb, sa, min_seeds=min_seeds) if len(seeds) >= 2 else None  # its "A" is folder B
        outcome = "too few seeds" if result is None else SWAPPED.get(result.outcome, result.outcome)
        p = f"{result.welch_p:.3g}" if result is not None else "-"
        budget = f"{group_a.seconds} s" if group_a.seconds else budget_label(group_a.budget)
        rows.append(
            f"| {group_a.env_id} | {group_a.label} | {budget} | {len(seeds)} | {_settings(runs_a)} | "
            f"{_settings(runs_b)} | {sa.mean():.3f} ({iqm(sa):.3f}) | {sb.mean():.3f} ({iqm(sb):.3f}) | "
            f"{sb.mean() - sa.mean():+.3f} | {p} | {outcome} |"
        )
    return header + (rows or ["(no group with seeds in both folders)"])


def _folder(text: str) -> Path:
    path = Path(text)
    if not (path / "cells").is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is not a results folder (it has no cells/ folder)")
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.compare", description=__doc__.split("\n\n")[0])
    parser.add_argument("a", type=_folder, help="results folder A (e.g. benchmarks/results)")
    parser.add_argument("b", type=_folder, help="results folder B (the same cells, other settings)")
    parser.add_argument("--min-seeds", type=int, default=MIN_SEEDS, help="seeds a side below which no verdict is given")
    args = parser.parse_args(argv)
    if args.min_seeds < 2:
        parser.error(f"--min-seeds must be at least 2 (a t-test needs a variance), got {args.min_seeds}")
    print("\n".join(compare_folders(args.a, args.b, args.min_seeds)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
