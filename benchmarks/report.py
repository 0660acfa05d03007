"""Turn a benchmark directory's cell files into ``report.md`` and figures.

Usage: ``python -m benchmarks.report DIR`` (after ``python -m benchmarks.run --preset ... --out DIR``, and optionally
``python -m benchmarks.run --reliability --out DIR`` for the reliability figures).

Statistics over seeds: the interquartile mean (IQM, ``scipy.stats.trim_mean`` cutting 25% at each end) with a 95%
percentile bootstrap confidence interval (``scipy.stats.bootstrap``, 2,000 resamples of the runs). This is
rliable's recommended aggregate and interval; rliable's own bootstrap module is not used because it imports
``arch``, which fails to import next to pandas 3 on the development machine. With 5 seeds the IQM is the mean of
the middle 3; with 3 or fewer it is the plain mean. Verdicts (which config is better, whether a paper's figure is
met) come from tests on the difference in :mod:`benchmarks.significance`, never from overlapping intervals.

Learning curves: every run's evaluation points are interpolated linearly onto a common grid of training episodes
(or env steps) that every run of the config reached, then aggregated point by point.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from benchmarks import cells
from benchmarks.figures import FAMILY_FIGURES, FAMILY_TITLES, best_figure, family_figure, final_figure, reliability_figure
from benchmarks.groups import group_results
from benchmarks.presets import PAPER_FAMILIES
from benchmarks.report_budgets import budget_verdicts, policies_section, split_views, tuned_section, wall_clock_section
from benchmarks.report_text import (
    cost_table,
    env_title,
    method_section,
    paper_claims,
    performance_table,
    reliability_table,
    setup_section,
    training_cost_line,
)


def read_inputs(out: Path) -> tuple[list[dict[str, Any]], dict[str, Any] | None, list[str]]:
    """The sound cell results, the reliability results (None if absent or damaged) and a message per damaged file."""
    results, damaged = cells.read_cells(out)
    for message in damaged:
        print(f"warning: {message}; left out of the report", file=sys.stderr)
    if not results:
        damage = f" ({len(damaged)} damaged: {'; '.join(damaged)})" if damaged else ""
        raise SystemExit(f"No sound cell files in {out / 'cells'}{damage}: run python -m benchmarks.run --out {out} first")
    reliability_path = out / "reliability.json"
    reliability = None
    if reliability_path.exists():
        try:
            reliability = cells.read_json_object(reliability_path)
        except ValueError as error:
            damaged.append(str(error))
            print(f"warning: {error}; rerun python -m benchmarks.run --reliability --out {out}", file=sys.stderr)
    return results, reliability, damaged


def build_report(out: str | Path, figures: bool = True) -> Path:
    """Write ``DIR/report.md`` and the figures from ``DIR/cells/*.json`` (and ``DIR/reliability.json`` if present).

    :param figures: False skips drawing the PNGs (the markdown still links them)
    """
    out = Path(out)
    results, reliability, damaged = read_inputs(out)
    every_group, references = group_results(results)
    groups, clock_groups = split_views(every_group)  # env-step budgets; equal wall-clock budgets
    if figures:
        family_figs = {f: family_figure(out, f, groups, references) for f in PAPER_FAMILIES}
        best = best_figure(out, groups, references)
        final = final_figure(out, groups, references)
        rel_fig = reliability_figure(out, reliability) if reliability else None
    else:
        family_figs = {
            f: FAMILY_FIGURES[f][0] if any(g.family == f for gs in groups.values() for g in gs) else None
            for f in PAPER_FAMILIES
        }
        best = "fig_best.png" if any(groups.values()) else None
        final = "fig_final.png" if best else None
        rel_fig = "fig_reliability.png" if reliability else None

    shown_dir = out.name if out.is_absolute() else out  # no path of the machine that made it
    lines = [
        "# Benchmark: SarsaAAC against P-DQN, MP-DQN, HybridPPO and SB3 baselines on RoboCup dribbling, Platform, the "
        "hybrid-action domains and Half Field Offense",
        "",
        f"Generated {time.strftime('%Y-%m-%d %H:%M')} from {len(results)} cell files in `{shown_dir}`.",
        "",
        "## Summary",
        "",
        *(budget_verdicts(groups, references) or ["- No env has SarsaAAC cells."]),
        *training_cost_line(groups),
        "",
        "### The paper's figures against ours",
        "",
        paper_claims(groups, reliability),
        "",
        "The paper's runs were on a real rcssserver 11 with reward constants, parameter meanings and exploration we had "
        "to choose ourselves (see `docs/robocup_dribble.md` and `docs/sarsa_aac.md`); its episode counts are for "
        "one learner, ours come from 16 lanes learning together.",
        "",
    ]
    lines += tuned_section(groups)
    lines += policies_section(groups)
    lines += wall_clock_section(clock_groups)
    lines += setup_section(out, results, groups, reliability)
    lines += method_section(results)
    lines += ["## Results per env (Table 1 of the paper, extended)", ""]
    for env_id, gs in groups.items():
        ref = references.get(env_id)
        lines += [
            f"### {env_title(env_id)}",
            "",
            "Greedy performance at the end of training:",
            "",
            performance_table(env_id, gs, ref),
            "",
        ]
        lines += ["Learning speed and cost:", "", cost_table(env_id, gs, ref), ""]
    missing = [e for e in references if e not in groups]
    for env_id in missing:
        lines += [f"### {env_title(env_id)}", "", performance_table(env_id, [], references[env_id]), ""]
    lines += ["## Figures", ""]
    for family in PAPER_FAMILIES:
        if family_figs[family]:
            lines += [
                f"### {FAMILY_TITLES[family]} (paper {FAMILY_FIGURES[family][1]})",
                "",
                f"![{family}]({family_figs[family]})",
                "",
            ]
    if best:
        lines += [
            "### Best of each family, the peers and the baselines (paper Fig. 8)",
            "",
            "Left: against training episodes (the paper's axis); middle: against env steps (the budget all algorithms "
            "share); right: against training seconds on this machine (log scale; evaluations excluded).",
            "",
            f"![best]({best})",
            "",
        ]
    if final:
        lines += ["### Final score of every config", "", f"![final]({final})", ""]
    lines += ["## Reliability test (paper Figs. 9-10)", ""]
    if reliability:
        lines += [
            f"10,000 fresh players (a new player-type set for every episode, seed {reliability['seed']}), "
            "one episode each, greedy. "
            "The policies are the best SarsaAAC cell, the best parameterized-peer cell and the best SB3 baseline cell of each "
            "dribbling env (best config by mean final distance, "
            "then its best seed, both chosen on the final evaluation set, not on these players), and the hand-coded dribbler.",
            "",
            reliability_table(reliability),
            "",
        ]
        if rel_fig:
            lines += [f"![reliability]({rel_fig})", ""]
    else:
        lines += ["Not run yet: `python -m benchmarks.run --reliability --out DIR`, then regenerate this report.", ""]
    if damaged:
        lines += ["## Damaged result files (left out; rerun the runner to recompute them)", ""]
        lines += [f"- {message}" for message in damaged]
        lines.append("")
    errors = sorted((out / "errors").glob("*.txt")) if (out / "errors").exists() else []
    if errors:
        lines += ["## Failed cells", ""]
        for path in errors:
            last = path.read_text().strip().splitlines()[-1] if path.read_text().strip() else "(empty)"
            lines.append(f"- `{path.stem}`: {last}")
        lines.append("")
    report = out / "report.md"
    report.write_text("\n".join(lines))
    return report


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.report", description=__doc__.split("\n\n")[0])
    parser.add_argument("dir", help="benchmark directory (the --out of benchmarks.run)")
    args = parser.parse_args(argv)
    path = build_report(args.dir)
    print(f"wrote {path} and its figures")
    return 0


if __name__ == "__main__":
    sys.exit(main())
