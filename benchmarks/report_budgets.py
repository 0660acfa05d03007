"""The report's sections on budgets and settings beyond the headline pairs: each tuned learner against its defaults
(with its tuning budget), SarsaAAC's two candidate default policies against each other on every env, the views at each
env-step budget of an env, and the equal wall-clock budget.

Verdicts are Welch's tests on the difference (:func:`benchmarks.significance.compare`), with
:data:`SHORT_VIEW_SEEDS` seeds a side at an env's main (shortest) budget and :data:`LONG_VIEW_SEEDS` at the long and
wall-clock budgets, whose runs cost up to 10x more.
"""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from benchmarks import domains
from benchmarks.groups import KINDS, Group, find_group
from benchmarks.presets import base_config, is_tuned
from benchmarks.report_text import comparison_text, fmt_ci, fmt_int, headline_pair, headline_verdicts, md_table
from benchmarks.significance import MIN_SEEDS, compare, iqm

SHORT_VIEW_SEEDS = MIN_SEEDS
LONG_VIEW_SEEDS = 5


def split_views(groups: dict[str, list[Group]]) -> tuple[dict[str, list[Group]], dict[str, list[Group]]]:
    """Per env: the env-step groups, and the wall-clock groups."""
    steps = {env: [g for g in gs if not g.seconds] for env, gs in groups.items()}
    clock = {env: [g for g in gs if g.seconds] for env, gs in groups.items()}
    return steps, {env: gs for env, gs in clock.items() if gs}


def budget_verdicts(groups: dict[str, list[Group]], references: dict[str, Any]) -> list[str]:
    """The headline verdicts at every env-step budget of each env (the shortest with :data:`SHORT_VIEW_SEEDS`
    seeds a side, longer ones with :data:`LONG_VIEW_SEEDS`)."""
    lines = []
    for env_id, gs in groups.items():
        budgets = sorted({g.budget for g in gs})
        for rank, budget in enumerate(budgets):
            seeds = SHORT_VIEW_SEEDS if rank == 0 else LONG_VIEW_SEEDS
            lines += headline_verdicts({env_id: [g for g in gs if g.budget == budget]}, references, seeds)
    return lines


def _digits(env_id: str) -> tuple[str, int]:
    return (" m", 1) if domains.is_dribbling(env_id) else ("", 3)


def tuning_budget_text(group: Group) -> str:
    """The tuning budget of a tuned group's settings, from its cells (``algo_config["tuning"]``)."""
    record = (group.runs[0].get("algo_config") or {}).get("tuning") or {}
    budget, best = record.get("budget") or {}, record.get("best") or {}
    if not budget:
        return "unknown"
    value = best.get("value")
    best_text = f"; best trial {best.get('trial')}: {value:.3g} on the tuning episodes" if value is not None else ""
    return (
        f"{budget.get('trials')} trials x {budget.get('env_steps', 0):,} env steps x {budget.get('seeds')} seed(s), "
        f"seeds {budget.get('tuning_seeds')}, evaluation set {budget.get('eval_seed')}{best_text}"
    )


def tuned_section(groups: dict[str, list[Group]]) -> list[str]:
    """Each tuned learner beside its default settings at the same budget, with the difference's verdict."""
    rows = []
    for env_id, gs in groups.items():
        unit, digits = _digits(env_id)
        for tuned in (g for g in gs if is_tuned(g.config)):
            default = find_group(gs, tuned.algo, base_config(tuned.config), tuned.budget)
            if default is None:
                verdict, default_text = "no default runs", "-"
            else:
                c = compare(tuned.final(), default.final(), min_seeds=LONG_VIEW_SEEDS)
                verdict = comparison_text(c, "tuned", "default", unit, digits)
                default_text = f"{fmt_ci(default.final(), digits)} ({len(default.runs)} seeds)"
            rows.append(
                [
                    env_id,
                    default.label if default else tuned.label,
                    f"{tuned.budget:,}",
                    default_text,
                    f"{fmt_ci(tuned.final(), digits)} ({len(tuned.runs)} seeds)",
                    verdict,
                    tuning_budget_text(tuned),
                ]
            )
    if not rows:
        return []
    return [
        "## Tuned and default settings",
        "",
        "Every tuned learner's study had the same size (trials x env steps x tuning seeds, TPE with median pruning on "
        "greedy evaluations; `benchmarks/tuning.py`); its tuning seeds and evaluation episodes are none of the grid's. "
        "Final score IQM [95% CI] at the env-step budget:",
        "",
        md_table(["env", "learner", "env steps", "default", "tuned", "tuned - default", "tuning budget"], rows, "llrrrll"),
        "",
    ]


POLICY_CANDIDATES = (("tile", "TilePolicy"), ("deep", "DeepPolicy"))  # SarsaAAC configs a user is pointed to first


def relative_score(group: Group, rivals: list[Group]) -> float:
    """``group``'s final IQM placed between the worst (0) and the best (1) final IQM of ``rivals`` (every learner of
    the env at the same budget, ``group`` among them); 1 where all score the same."""
    scores = [float(iqm(g.final())) for g in rivals]
    best, worst = max(scores), min(scores)
    return 1.0 if best == worst else (float(iqm(group.final())) - worst) / (best - worst)


def candidate_groups(groups: dict[str, list[Group]]) -> dict[str, tuple[int, list[Group], Group, Group]]:
    """Per env where both :data:`POLICY_CANDIDATES` ran with their defaults at its main (shortest) budget: that
    budget, every group at it, and the two candidates' groups."""
    (first, _), (second, _) = POLICY_CANDIDATES
    found = {}
    for env_id, gs in groups.items():
        if not gs:  # an env with only wall-clock cells, or none readable
            continue
        budget = min(g.budget for g in gs)
        a, b = find_group(gs, "SarsaAAC", first, budget), find_group(gs, "SarsaAAC", second, budget)
        if a is not None and b is not None:
            found[env_id] = (budget, [g for g in gs if g.budget == budget], a, b)
    return found


def relative_scores(found: dict[str, tuple[int, list[Group], Group, Group]]) -> dict[str, tuple[float, float]]:
    """Per env of :func:`candidate_groups`, the two candidates' :func:`relative_score` among that env's learners."""
    return {env_id: (relative_score(a, rivals), relative_score(b, rivals)) for env_id, (_, rivals, a, b) in found.items()}


def pick(scores: dict[str, tuple[float, float]]) -> str:
    """The candidate with the higher mean relative score over the envs (the first candidate on a tie)."""
    means = np.mean(list(scores.values()), axis=0)
    return POLICY_CANDIDATES[int(means[1] > means[0])][1]


def recommended_policy(groups: dict[str, list[Group]]) -> str | None:
    """The candidate policy with the higher mean :func:`relative_score` over the envs where both ran (the first
    candidate on a tie); None where there is no such env. The rule behind the "(recommended)" label."""
    found = candidate_groups(groups)
    return pick(relative_scores(found)) if found else None


def policies_section(groups: dict[str, list[Group]]) -> list[str]:
    """SarsaAAC's candidate policies (:data:`POLICY_CANDIDATES`) with their defaults at each env's main budget, the
    second against the first by Welch's test, and each one's score relative to the env's best learner, whose mean
    over the envs picks the recommended policy (:func:`recommended_policy`)."""
    (_, first_name), (_, second_name) = POLICY_CANDIDATES
    found = candidate_groups(groups)
    if not found:
        return []
    scores = relative_scores(found)
    rows, tally = [], Counter[str]()
    for env_id, (budget, _, a, b) in found.items():
        unit, digits = _digits(env_id)
        c = compare(b.final(), a.final(), min_seeds=SHORT_VIEW_SEEDS)
        tally[c.outcome] += 1
        rows.append(
            [
                env_id,
                f"{budget:,}",
                f"{fmt_ci(a.final(), digits)} ({len(a.runs)} seeds)",
                f"{fmt_ci(b.final(), digits)} ({len(b.runs)} seeds)",
                f"{scores[env_id][0]:.2f} / {scores[env_id][1]:.2f}",
                comparison_text(c, second_name, first_name, unit, digits),
            ]
        )
    means = np.mean(list(scores.values()), axis=0)
    return [
        "## SarsaAAC's policies across the domains",
        "",
        f"{first_name} and {second_name} with their shipped defaults at each env's main budget, final score IQM [95% CI]; "
        f"{second_name} against {first_name} by Welch's test ({SHORT_VIEW_SEEDS} seeds a side for a verdict). "
        f"{second_name} better on {tally['A better']} env(s), {first_name} better on {tally['B better']}, no significant "
        f"difference on {tally['no significant difference']}, no verdict on {tally['too few seeds']}.",
        "",
        "Relative score: the policy's final IQM placed between the worst (0) and the best (1) final IQM of every learner "
        "of the env at that budget (tuned twins included). Mean over the envs: "
        f"{first_name} {means[0]:.2f}, {second_name} {means[1]:.2f}; the recommended policy, the one with the higher "
        f"mean, is **{pick(scores)}**.",
        "",
        md_table(
            ["env", "env steps", first_name, second_name, "relative score", f"{second_name} - {first_name}"],
            rows,
            "lrrrrl",
        ),
        "",
    ]


def wall_clock_section(groups: dict[str, list[Group]]) -> list[str]:
    """The equal wall-clock budget: per env a table of the groups and the best SarsaAAC config against the best of
    each other kind of learner, at the same seconds of training."""
    if not groups:
        return []
    lines = [
        "## Equal wall-clock budget",
        "",
        "Every learner trains for the same seconds on one core (evaluations excluded); its env-step horizon, over "
        "which its schedules run, is twice what its algorithm usually steps in that time, so the clock ends training "
        "(the column 'stopped by time' counts the runs it ended). The final evaluation is the same as at the env-step "
        "budget.",
        "",
    ]
    for env_id, gs in groups.items():
        unit, digits = _digits(env_id)
        rows = [
            [
                g.label,
                str(len(g.runs)),
                f"{g.seconds}",
                fmt_int(np.mean(g.values("env_steps"))),
                fmt_int(np.mean(g.values("episodes"))),
                fmt_ci(g.final(), digits),
                f"{sum(r.get('stopped_by') == 'time' for r in g.runs)}/{len(g.runs)}",
            ]
            for g in gs
        ]
        header = ["learner", "seeds", "seconds", "env steps", "episodes", "final score, IQM [95% CI]", "stopped by time"]
        lines += [f"### {env_id}", "", md_table(header, rows), ""]
        sarsa = headline_pair(gs, "SarsaAAC", LONG_VIEW_SEEDS)
        for kind in KINDS:
            other = headline_pair(gs, kind, LONG_VIEW_SEEDS) if kind != "SarsaAAC" else None
            if sarsa is None or other is None:
                continue
            c = compare(sarsa.final(), other.final(), min_seeds=LONG_VIEW_SEEDS)
            lines.append(
                f"- {sarsa.label} vs the best {kind}, {other.label}, at {sarsa.seconds} s: "
                f"{comparison_text(c, 'SarsaAAC', other.label, unit, digits)}."
            )
        lines.append("")
    return lines
