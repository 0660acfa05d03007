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
import json
import sys
import time
import warnings
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from benchmarks import cells
from benchmarks.presets import BASELINES, ENV_IDS, FAMILIES, SARSA_CONFIGS, config_label
from benchmarks.provenance import invocations
from benchmarks.significance import MIN_SEEDS, compare, target_verdict
from benchmarks.significance import verdict as difference_verdict

BOOTSTRAP_RESAMPLES = 2000
GRID_POINTS = 80
THRESHOLDS = (16.0, 20.0, 25.0)

COLORS = {
    "mlp2": "#9ecae1",
    "mlp10": "#4292c6",
    "mlp20": "#08306b",
    "rbfmlp2": "#a1d99b",
    "rbfmlp10": "#41ab5d",
    "rbfmlp20": "#00441b",
    "rbf10": "#fdae6b",
    "rbf30": "#f16913",
    "rbf50": "#7f2704",
    "ppo": "#7b3294",
    "a2c": "#e7298a",
    "sac": "#8c564b",
    "td3": "#17becf",
    "ddpg": "#bcbd22",
    "dqn": "#666666",
}
FAMILY_FIGURES = {"MLP": ("fig_mlp.png", "Fig. 5"), "MLP+RBF": ("fig_rbfmlp.png", "Fig. 6"), "RBF": ("fig_rbf.png", "Fig. 7")}
FAMILY_TITLES = {
    "MLP": "SarsaAAC with MLP approximators",
    "MLP+RBF": "SarsaAAC with MLP approximators behind an RBF filter layer (10 per input)",
    "RBF": "SarsaAAC with arrays of Gaussian RBFs (linear approximators)",
}


# ---------------------------------------------------------------------------------------------------------------------
# Loading and grouping
# ---------------------------------------------------------------------------------------------------------------------


def load_results(out: Path) -> list[dict[str, Any]]:
    """The sound cell results (a damaged file is named in a warning and left out; :func:`build_report` lists it)."""
    return cells.load_cells(out)


class Group:
    """The runs (seeds) of one env x algorithm x config x budget."""

    def __init__(self, env_id: str, algo: str, config: str, budget: int, runs: list[dict[str, Any]]):
        self.env_id, self.algo, self.config, self.budget = env_id, algo, config, budget
        self.runs = sorted(runs, key=lambda r: r["cell"]["seed"])

    @property
    def label(self) -> str:
        return config_label(self.algo, self.config)

    @property
    def family(self) -> str:
        return self.runs[0]["family"]

    @property
    def color(self) -> str:
        return COLORS.get(self.config, "#333333")

    def final(self, key: str = "distance_mean") -> np.ndarray:
        return np.array([r["final"][key] for r in self.runs], dtype=float)

    def values(self, key: str) -> np.ndarray:
        return np.array([r[key] for r in self.runs], dtype=float)

    def curve(self, x: str = "episodes", y: str = "distance_mean") -> tuple[np.ndarray, np.ndarray]:
        """Grid ``(G,)`` over the x range every run reached, and the runs' interpolated values ``(runs, G)``."""
        end = min(r["curve"][-1][x] for r in self.runs)
        grid = np.linspace(0.0, end, GRID_POINTS) if end > 0 else np.zeros(1)
        values = np.stack([np.interp(grid, [p[x] for p in r["curve"]], [p[y] for p in r["curve"]]) for r in self.runs])
        return grid, values

    def first_reaching(self, metres: float) -> list[dict[str, Any] | None]:
        """Per run: the first curve point whose greedy mean distance is at least ``metres`` (None if never)."""
        return [next((p for p in r["curve"] if p["distance_mean"] >= metres), None) for r in self.runs]


def group_results(results: list[dict[str, Any]]) -> tuple[dict[str, list[Group]], dict[str, dict[str, Any]]]:
    """Training groups per env (SarsaAAC configs in the paper's order, then baselines) and references per env."""
    buckets: dict[tuple[str, str, str, int], list[dict[str, Any]]] = defaultdict(list)
    references = {}
    for r in results:
        c = r["cell"]
        if c["algo"] == "Reference":
            references[c["env_id"]] = r
        elif "final" in r:
            buckets[(c["env_id"], c["algo"], c["config"], c["budget"])].append(r)
    order = {name: i for i, name in enumerate([*SARSA_CONFIGS, *(a.lower() for a in BASELINES)])}
    groups: dict[str, list[Group]] = defaultdict(list)
    for key in sorted(buckets, key=lambda k: (k[0], order.get(k[2], 99), k[3])):
        groups[key[0]].append(Group(*key, buckets[key]))
    env_order = [e for e in ENV_IDS if e in groups or e in references] + sorted(set(groups) - set(ENV_IDS))
    return {e: groups.get(e, []) for e in env_order}, references


# ---------------------------------------------------------------------------------------------------------------------
# Statistics
# ---------------------------------------------------------------------------------------------------------------------


def iqm(values: np.ndarray, axis: int = 0) -> np.ndarray:
    return stats.trim_mean(values, 0.25, axis=axis)


def iqm_ci(values: np.ndarray, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """IQM over runs (axis 0) and its 95% percentile bootstrap interval; the interval is the point itself for 1 run
    or runs that all agree."""
    values = np.asarray(values, dtype=float)
    point = iqm(values)
    if values.shape[0] < 2:
        return point, point.copy(), point.copy()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # degenerate resamples (all runs equal) warn
        result = stats.bootstrap(
            (values,),
            lambda sample, axis: stats.trim_mean(sample, 0.25, axis=axis),
            n_resamples=BOOTSTRAP_RESAMPLES,
            confidence_level=0.95,
            method="percentile",
            axis=0,
            vectorized=True,
            random_state=seed,
        )
    low = np.where(np.isfinite(result.confidence_interval.low), result.confidence_interval.low, point)
    high = np.where(np.isfinite(result.confidence_interval.high), result.confidence_interval.high, point)
    return point, np.minimum(low, point), np.maximum(high, point)


def scalar_ci(values: np.ndarray) -> tuple[float, float, float]:
    point, low, high = iqm_ci(np.asarray(values, dtype=float)[:, None])
    return float(point[0]), float(low[0]), float(high[0])


def best_group(groups: list[Group], algos: tuple[str, ...], family: str | None = None) -> Group | None:
    """The group with the highest IQM final distance among ``algos`` (and ``family``)."""
    pool = [g for g in groups if g.algo in algos and (family is None or g.family == family)]
    return max(pool, key=lambda g: float(iqm(g.final()))) if pool else None


# ---------------------------------------------------------------------------------------------------------------------
# Formatting
# ---------------------------------------------------------------------------------------------------------------------


def fmt_ci(values: np.ndarray, digits: int = 1) -> str:
    point, low, high = scalar_ci(values)
    if len(values) < 2:
        return f"{point:.{digits}f}"
    return f"{point:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]"


def fmt_int(x: float) -> str:
    return f"{x:,.0f}"


def fmt_reach(group: Group, metres: float, key: str) -> str:
    """Mean over the runs that reached ``metres`` of their episodes (or training seconds) at that point."""
    hits = [p for p in group.first_reaching(metres) if p is not None]
    n = len(group.runs)
    if not hits:
        return "not reached"
    mean = np.mean([p[key] for p in hits])
    text = fmt_int(mean) if key == "episodes" else f"{mean:.1f} s"
    return text if len(hits) == n else f"{text} ({len(hits)}/{n} seeds)"


def env_title(env_id: str) -> str:
    return {"RoboCupDribblePaper-v0": "RoboCupDribblePaper-v0 (rcssserver 11 physics, the paper's)", "RoboCupDribble-v0": "RoboCupDribble-v0 (rcssserver 19 physics)"}.get(env_id, env_id)


def env_short(env_id: str) -> str:
    return {"RoboCupDribblePaper-v0": "RoboCupDribblePaper-v0 (v11 physics)", "RoboCupDribble-v0": "RoboCupDribble-v0 (v19 physics)"}.get(env_id, env_id)


def md_table(header: list[str], rows: list[list[str]], align: str | None = None) -> str:
    align = align or "l" + "r" * (len(header) - 1)
    sep = ["---:" if a == "r" else "---" for a in align]
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join(sep) + " |"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------------------------------------------------


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update(
        {
            "figure.dpi": 110,
            "savefig.dpi": 130,
            "font.size": 10.5,
            "axes.titlesize": 11.5,
            "axes.labelsize": 10.5,
            "legend.fontsize": 9,
            "axes.spines.top": False,
            "axes.spines.right": False,
            "axes.grid": True,
            "grid.alpha": 0.3,
        }
    )
    return plt


def _plot_group(ax, group: Group, x: str, label: str | None = None) -> None:
    grid, values = group.curve(x)
    point, low, high = iqm_ci(values)
    n = len(group.runs)
    ax.plot(grid, point, color=group.color, lw=2, label=f"{label or group.label} (n={n})")
    if n > 1:
        ax.fill_between(grid, low, high, color=group.color, alpha=0.2, lw=0)


def _references(ax, reference: dict[str, Any] | None, legend: bool = True) -> None:
    if reference is None:
        return
    ref = reference["references"]
    hand = ref["handcoded"]["final"]["distance_mean"]
    ceiling = ref["ceiling"]["mean"]
    ax.axhline(hand, color="black", ls="--", lw=1.2, label=f"hand-coded dribbler ({hand:.1f} m)" if legend else None)
    ax.axhline(ceiling, color="0.45", ls=":", lw=1.5, label=f"running ceiling, no ball ({ceiling:.1f} m)" if legend else None)


def _budget_note(groups: list[Group]) -> str:
    parts = sorted({(g.algo == "SarsaAAC", g.budget, len(g.runs)) for g in groups}, reverse=True)
    return "; ".join(f"{'SarsaAAC' if s else 'baselines'} {b:,} env steps x {n} seeds" for s, b, n in parts)


def _axes_style(ax, xlabel: str, ymax: float) -> None:
    ax.set_xlabel(xlabel)
    ax.set_ylabel("greedy dribble distance (m)")
    ax.set_ylim(0, ymax)
    ax.xaxis.set_major_formatter(_thousands())


def _thousands():
    from matplotlib.ticker import FuncFormatter

    return FuncFormatter(lambda v, _: f"{v / 1000:g}k" if abs(v) >= 1000 else f"{v:g}")


def _ymax(references: dict[str, Any], env_ids: list[str], groups: list[Group]) -> float:
    top = [r["references"]["ceiling"]["mean"] for e, r in references.items() if e in env_ids]
    top += [float(np.max(g.curve()[1])) for g in groups]
    return max([25.0, *top]) * 1.08


def family_figure(out: Path, family: str, groups: dict[str, list[Group]], references: dict[str, Any]) -> str | None:
    plt = _plt()
    env_ids = [e for e, gs in groups.items() if any(g.family == family for g in gs)]
    if not env_ids:
        return None
    name, paper_fig = FAMILY_FIGURES[family]
    fig, axes = plt.subplots(1, len(env_ids), figsize=(6.4 * len(env_ids), 4.6), squeeze=False)
    for ax, env_id in zip(axes[0], env_ids, strict=True):
        fam = [g for g in groups[env_id] if g.family == family]
        for g in fam:
            _plot_group(ax, g, "episodes")
        _references(ax, references.get(env_id))
        _axes_style(ax, "training episodes", _ymax(references, [env_id], fam))
        ax.set_title(f"{env_short(env_id)}\n{_budget_note(fam)}", fontsize=10)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2, frameon=False)
    fig.suptitle(f"{FAMILY_TITLES[family]} (cf. paper {paper_fig})\nIQM over seeds with 95% bootstrap CI", fontsize=12)
    fig.tight_layout()
    fig.savefig(out / name, bbox_inches="tight")
    plt.close(fig)
    return name


def best_figure(out: Path, groups: dict[str, list[Group]], references: dict[str, Any]) -> str | None:
    plt = _plt()
    env_ids = [e for e, gs in groups.items() if gs]
    if not env_ids:
        return None
    fig, axes = plt.subplots(len(env_ids), 2, figsize=(13, 4.6 * len(env_ids)), squeeze=False)
    for row, env_id in enumerate(env_ids):
        chosen = [g for f in FAMILIES if (g := best_group(groups[env_id], ("SarsaAAC",), f)) is not None]
        chosen += [g for g in groups[env_id] if g.algo != "SarsaAAC"]
        for col, (x, xlabel) in enumerate((("episodes", "training episodes"), ("env_steps", "training env steps"))):
            ax = axes[row, col]
            for g in chosen:
                label = f"SarsaAAC {g.label}" if g.algo == "SarsaAAC" else g.label
                _plot_group(ax, g, x, label)
            _references(ax, references.get(env_id))
            _axes_style(ax, xlabel, _ymax(references, [env_id], chosen))
            ax.set_title(f"{env_short(env_id)}: vs {xlabel.split(' ', 1)[1]}", fontsize=10.5)
        axes[row, 1].legend(loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False, title=_budget_note(chosen).replace("; ", "\n"), title_fontsize=8.5)
    fig.suptitle("Best SarsaAAC config of each family and the SB3 baselines (cf. paper Fig. 8)\nIQM over seeds with 95% bootstrap CI", fontsize=12)
    fig.tight_layout()
    fig.savefig(out / "fig_best.png", bbox_inches="tight")
    plt.close(fig)
    return "fig_best.png"


RELIABILITY_STYLE = {"sarsa_aac": ("#d94801", "best SarsaAAC"), "baseline": ("#6a51a3", "best baseline"), "handcoded": ("black", "hand-coded")}


def _entry_label(name: str, entry: dict[str, Any]) -> str:
    what = RELIABILITY_STYLE[name][1]
    cell = "" if name == "handcoded" else f" ({entry['cell_id'].split('__')[1]}, {entry['cell_id'].split('__')[2]})"
    return f"{what}{cell}: mean {entry['distance_mean']:.1f} m"


def reliability_figure(out: Path, reliability: dict[str, Any]) -> str | None:
    plt = _plt()
    envs = reliability.get("envs", {})
    if not envs:
        return None
    fig, axes = plt.subplots(len(envs), 2, figsize=(13, 4.4 * len(envs)), squeeze=False)
    for row, (env_id, entries) in enumerate(envs.items()):
        ax_h, ax_c = axes[row]
        for name, entry in entries.items():
            color, _ = RELIABILITY_STYLE[name]
            counts = np.array(entry["histogram"]["counts"], dtype=float)
            width = entry["histogram"]["bin_metres"]
            edges = np.arange(len(counts) + 1) * width
            share = counts / counts.sum()
            ax_h.stairs(100 * share, edges, color=color, lw=1.8, label=_entry_label(name, entry))
            # share of players that dribbled at least m metres, m = 0, 1, 2, ...
            reaching = 1.0 - np.concatenate([[0.0], np.cumsum(share)])[:-1]
            ax_c.plot(edges[:-1], 100 * reaching, color=color, lw=2, marker="o", ms=2.5, label=RELIABILITY_STYLE[name][1])
        last = max(int(np.flatnonzero(np.array(e["histogram"]["counts"]))[-1]) + 2 for e in entries.values())
        ax_h.set_xlim(0, last)
        ax_h.set_xlabel("metres dribbled before losing the ball (or in 35 actions)")
        ax_h.set_ylabel("share of players (%)")
        ax_h.set_title(f"{env_short(env_id)}: histogram, {next(iter(entries.values()))['players']:,} fresh players", fontsize=10)
        ax_h.legend(loc="upper right", frameon=False)
        ax_c.set_xlim(0, last)
        ax_c.set_ylim(0, 102)
        ax_c.axvline(18, color="0.5", ls=":", lw=1)
        ax_c.set_xlabel("metres m")
        ax_c.set_ylabel("players dribbling at least m metres (%)")
        ax_c.set_title(f"{env_short(env_id)}: share reaching each metre", fontsize=10)
        ax_c.legend(loc="lower left", frameon=False)
    fig.suptitle("Reliability test (cf. paper Figs. 9-10): every player a fresh heterogeneous type, one greedy episode", fontsize=12)
    fig.tight_layout()
    fig.savefig(out / "fig_reliability.png", bbox_inches="tight")
    plt.close(fig)
    return "fig_reliability.png"


def final_figure(out: Path, groups: dict[str, list[Group]], references: dict[str, Any]) -> str | None:
    """Final greedy distance of every config: one dot per seed, IQM and CI."""
    plt = _plt()
    env_ids = [e for e, gs in groups.items() if gs]
    if not env_ids:
        return None
    fig, axes = plt.subplots(1, len(env_ids), figsize=(max(8.5, 6.8 * len(env_ids)), 0.42 * max(len(groups[e]) for e in env_ids) + 2.4), squeeze=False)
    for ax, env_id in zip(axes[0], env_ids, strict=True):
        gs = groups[env_id][::-1]
        for y, g in enumerate(gs):
            finals = g.final()
            point, low, high = scalar_ci(finals)
            ax.plot([low, high], [y, y], color=g.color, lw=5, alpha=0.45, solid_capstyle="butt")
            ax.plot(point, y, "|", color=g.color, ms=16, mew=2.5)
            ax.plot(finals, np.full(len(finals), y), "o", color=g.color, ms=3.5, mfc="white", mew=1)
        ax.set_yticks(range(len(gs)), [g.label for g in gs])
        _references(ax, None)
        ref = references.get(env_id)
        if ref:
            hand = ref["references"]["handcoded"]["final"]["distance_mean"]
            ceiling = ref["references"]["ceiling"]["mean"]
            ax.axvline(hand, color="black", ls="--", lw=1.2)
            ax.axvline(ceiling, color="0.45", ls=":", lw=1.5)
            top = len(gs) - 0.35
            ax.text(hand, top, f" hand-coded {hand:.1f} m", va="bottom", ha="left", fontsize=8.5)
            ax.text(ceiling, top, f"running ceiling {ceiling:.1f} m ", va="bottom", ha="right", fontsize=8.5, color="0.35")
            ax.set_ylim(-0.6, len(gs) + 0.1)
        ax.set_xlabel("final greedy dribble distance (m)")
        ax.set_xlim(0, _ymax(references, [env_id], []) if ref else None)
        ax.set_title(f"{env_short(env_id)}\n{_budget_note(groups[env_id])}", fontsize=10)
        ax.grid(axis="y", alpha=0)
    fig.suptitle("Final greedy distance per config\n(dots: seeds; tick: IQM; band: 95% bootstrap CI)", fontsize=12)
    fig.tight_layout()
    fig.savefig(out / "fig_final.png", bbox_inches="tight")
    plt.close(fig)
    return "fig_final.png"


# ---------------------------------------------------------------------------------------------------------------------
# The report
# ---------------------------------------------------------------------------------------------------------------------


def performance_table(groups: list[Group], reference: dict[str, Any] | None) -> str:
    ceiling = reference["references"]["ceiling"]["mean"] if reference else None
    header = ["config", "seeds", "env steps", "episodes", "final distance (m), IQM [95% CI]", "% of ceiling", "best curve point (m)", "max episode (m)", ">= 20 m", "ball lost"]
    rows = []
    for g in groups:
        finals = g.final()
        share = f"{100 * float(iqm(finals)) / ceiling:.0f}%" if ceiling else "n/a"
        best_point = np.mean([max(p["distance_mean"] for p in r["curve"]) for r in g.runs])
        rows.append(
            [
                g.label,
                str(len(g.runs)),
                fmt_int(np.mean(g.values("env_steps"))),
                fmt_int(np.mean(g.values("episodes"))),
                fmt_ci(finals),
                share,
                f"{best_point:.1f}",
                f"{np.max(g.final('distance_max')):.1f}",
                f"{100 * np.mean(g.final('reach20_share')):.0f}%",
                f"{100 * np.mean(g.final('ball_loss_rate')):.0f}%",
            ]
        )
    if reference:
        hand = reference["references"]["handcoded"]["final"]
        rows.append(["*hand-coded dribbler*", "-", "-", "-", f"{hand['distance_mean']:.1f}", f"{100 * hand['distance_mean'] / ceiling:.0f}%", "-", f"{hand['distance_max']:.1f}", f"{100 * hand['reach20_share']:.0f}%", f"{100 * hand['ball_loss_rate']:.0f}%"])
        c = reference["references"]["ceiling"]
        rows.append(["*running ceiling (no ball)*", "-", "-", "-", f"{c['mean']:.1f} (min {c['min']:.1f}, max {c['max']:.1f})", "100%", "-", f"{c['max']:.1f}", "-", "-"])
    return md_table(header, rows)


def cost_table(groups: list[Group], reference: dict[str, Any] | None) -> str:
    dqn = [g for g in groups if g.algo == "DQN"]
    dqn_us = float(np.median(dqn[0].values("predict_us"))) if dqn else None
    header = ["config", "episodes to 20 m", "train time to 20 m", "episodes to 25 m", "train time to 25 m", "decision cost (us/action)", "vs DQN", "train wall time per seed (s)"]
    rows = []
    for g in groups:
        us = float(np.median(g.values("predict_us")))
        rows.append(
            [
                g.label,
                fmt_reach(g, 20.0, "episodes"),
                fmt_reach(g, 20.0, "train_s"),
                fmt_reach(g, 25.0, "episodes"),
                fmt_reach(g, 25.0, "train_s"),
                f"{us:.0f}",
                f"{us / dqn_us:.2f}x" if dqn_us else "n/a",
                f"{np.mean(g.values('train_wall_s')):.0f}",
            ]
        )
    if reference:
        us = reference["references"]["handcoded"]["predict_us"]
        rows.append(["*hand-coded dribbler*", "-", "-", "-", "-", f"{us:.0f}", f"{us / dqn_us:.2f}x" if dqn_us else "n/a", "-"])
    return md_table(header, rows)


def _at_episodes(group: Group, episodes: float) -> str:
    """IQM of the greedy distance at ``episodes`` training episodes, if every run got that far."""
    if min(r["curve"][-1]["episodes"] for r in group.runs) < episodes:
        return f"a seed trained fewer than {fmt_int(episodes)} episodes"
    values = np.array([np.interp(episodes, [p["episodes"] for p in r["curve"]], [p["distance_mean"] for p in r["curve"]]) for r in group.runs])
    return f"{float(iqm(values)):.1f} m at {fmt_int(episodes)} episodes"


def _reach_claim(group: Group | None, metres: float, within: float | None) -> tuple[str, str]:
    """The claim "``metres`` within ``within`` training episodes" (or at the end of training, for None), decided by
    :func:`benchmarks.significance.target_verdict` on one score per seed: the greedy distance interpolated at
    ``within`` episodes (a run that stopped earlier: its last point), or the final distance."""
    if group is None:
        return "not run", "-"
    hits = group.first_reaching(metres)
    reached = [p for p in hits if p is not None]
    n = len(hits)
    final = fmt_ci(group.final())
    if within is None:
        scores = group.final()
    else:
        scores = np.array([np.interp(within, [p["episodes"] for p in r["curve"]], [p["distance_mean"] for p in r["curve"]]) for r in group.runs])
    check = target_verdict(scores, metres)
    where = "at the end of training" if within is None else f"at {fmt_int(within)} episodes"
    if within is not None and min(r["curve"][-1]["episodes"] for r in group.runs) < within:
        where += " (a run that stopped earlier: its last point)"
    test = f"mean {check.mean:.1f} m {where}, one-sided 95% lower bound {check.bound:.1f} m"
    if not reached:
        text = f"{group.label}: {metres:g} m not reached in {fmt_int(np.mean(group.values('episodes')))} episodes (final {final} m)"
    else:
        mean_ep = np.mean([p["episodes"] for p in reached])
        text = f"{group.label}: {metres:g} m after {fmt_int(mean_ep)} episodes ({len(reached)}/{n} seeds; final {final} m)"
    return f"{text}; {test}", _target_text(check.outcome)


def _target_text(outcome: str) -> str:
    return f"too few seeds (< {MIN_SEEDS})" if outcome == "too few seeds" else outcome


def paper_claims(groups: dict[str, list[Group]], reliability: dict[str, Any] | None) -> str:
    rows = []
    for env_id, gs in groups.items():
        by_config = {g.config: g for g in gs if g.algo == "SarsaAAC"}
        if not by_config:
            continue
        short = "paper env" if env_id == "RoboCupDribblePaper-v0" else env_id
        rbf = best_group(gs, ("SarsaAAC",), "RBF")
        text, verdict = _reach_claim(rbf, 25.0, 10_000)
        if rbf is not None:
            text += f"; {_at_episodes(rbf, 10_000)}"
        rows.append([short, "RBF arrays: 25 m in under 10,000 episodes (Fig. 7)", text, verdict])
        text, verdict = _reach_claim(by_config.get("mlp2"), 16.0, None)
        rows.append([short, "MLP (2 hidden): 16 m after at least 40,000 episodes (Fig. 5)", text, verdict])
        text, verdict = _reach_claim(by_config.get("rbfmlp2"), 16.0, 15_000)
        rows.append([short, "MLP+RBF (2 hidden): 16 m in 15,000 episodes (Fig. 6)", text, verdict])
        bigger = [by_config[c] for c in ("rbfmlp10", "rbfmlp20") if c in by_config]
        if bigger:
            # The paper's configs climb to about 12 m and stop: "met" needs each to reach 12 m (a config that fails
            # does not meet it) and none to go significantly beyond; per seed, its best curve point.
            best_points = [np.array([max(p["distance_mean"] for p in r["curve"]) for r in g.runs]) for g in bigger]
            reach = [target_verdict(b, 12.0, "at least").outcome for b in best_points]
            beyond = [target_verdict(b, 12.0, "at most").outcome == "not met" for b in best_points]
            text = "; ".join(f"{g.label}: best curve point {np.mean(b):.1f} m (mean over seeds)" for g, b in zip(bigger, best_points, strict=True))
            if "too few seeds" in reach:
                verdict = _target_text("too few seeds")
            elif any(beyond):
                verdict = "not met (they do better)"
            elif all(r == "met" for r in reach):
                verdict = "met"
            else:
                verdict = "not met (they stay below 12 m)" if "not met" in reach else "not shown"
            rows.append([short, "MLP+RBF (10, 20 hidden): about 12 m and no more (Fig. 6)", text, verdict])
        fam_best = {f: best_group(gs, ("SarsaAAC",), f) for f in FAMILIES}
        fam_best = {f: g for f, g in fam_best.items() if g is not None}
        if len(fam_best) > 1 and "RBF" in fam_best:
            # met only when the best RBF config beats the best config of every other family (Welch's test each)
            outcomes = {f: difference_verdict(fam_best["RBF"].final(), g.final()) for f, g in fam_best.items() if f != "RBF"}
            text = ", ".join(f"{f}: {fmt_ci(g.final())} m" for f, g in fam_best.items())
            if "too few seeds" in outcomes.values():
                met = _target_text("too few seeds")
            elif all(o == "A better" for o in outcomes.values()):
                met = "met"
            else:
                better = [f for f, o in outcomes.items() if o == "B better"]
                met = f"not met ({', '.join(better)} better)" if better else "not shown (no significant difference)"
            rows.append([short, "RBF arrays are the best family (Fig. 8)", f"best final per family: {text}", met])
        entry = (reliability or {}).get("envs", {}).get(env_id, {}).get("sarsa_aac")
        if entry:
            share = entry["share_at_least"]["18"]
            rows.append([short, "Reliability test: most players run at least 18 m (Fig. 9)", f"{100 * share:.1f}% of {entry['players']:,} players >= 18 m ({entry['cell_id']})", "yes" if share > 0.5 else "no"])
        else:
            rows.append([short, "Reliability test: most players run at least 18 m (Fig. 9)", "not run (python -m benchmarks.run --reliability)", "-"])
    return md_table(["env", "paper's claim", "ours", "met?"], rows, "llll")


def _interval(pair: tuple[float, float], digits: int = 1) -> str:
    return f"[{pair[0]:.{digits}f}, {pair[1]:.{digits}f}]"


def baseline_verdicts(groups: dict[str, list[Group]]) -> list[str]:
    lines = []
    for env_id, gs in groups.items():
        sarsa = best_group(gs, ("SarsaAAC",))
        base = best_group(gs, tuple(BASELINES))
        if sarsa is None or base is None:
            continue
        s, s_low, s_high = scalar_ci(sarsa.final())
        b, b_low, b_high = scalar_ci(base.final())
        # The verdict is a test on the difference (benchmarks/significance.py), never whether the CIs overlap.
        c = compare(sarsa.final(), base.final())
        verdict = {
            "A better": f"**SarsaAAC {sarsa.label} beats the baseline {base.label}**",
            "B better": f"**the baseline {base.label} beats SarsaAAC**",
            "no significant difference": "no significant difference",
            "too few seeds": f"no verdict (fewer than {MIN_SEEDS} seeds on a side)",
        }[c.outcome]
        verdict += (
            f" (Welch's t-test on the difference p = {c.welch_p:.3g}, n = {c.n_a} vs {c.n_b}; SarsaAAC - baseline: means "
            f"{c.mean_difference:+.1f} m {_interval(c.mean_difference_ci)}, IQMs {c.iqm_difference:+.1f} m {_interval(c.iqm_difference_ci)}; "
            f"P(SarsaAAC > baseline) = {c.probability_of_improvement:.2f} {_interval(c.probability_of_improvement_ci, 2)})"
        )
        beaten = [g.label for g in gs if g.algo != "SarsaAAC" and float(iqm(g.final())) > s]
        lines.append(
            f"- {env_id}: best SarsaAAC {sarsa.label} {s:.1f} m [{s_low:.1f}, {s_high:.1f}] vs best baseline {base.label} "
            f"{b:.1f} m [{b_low:.1f}, {b_high:.1f}]: {verdict}."
            + (f" Baselines with a higher IQM than the best SarsaAAC config (not tested): {', '.join(beaten)}." if beaten else "")
        )
        # Equal env steps are not equal compute: say which is faster per step too.
        lines.append(
            f"  Training wall time per seed: SarsaAAC {sarsa.label} {np.mean(sarsa.values('train_wall_s')):.0f} s, "
            f"{base.label} {np.mean(base.values('train_wall_s')):.0f} s (same env-step budget, {sarsa.budget:,} vs {base.budget:,})."
        )
    return lines


def reliability_table(reliability: dict[str, Any]) -> str:
    rows = []
    for env_id, entries in reliability.get("envs", {}).items():
        for name, e in entries.items():
            s = e["share_at_least"]
            rows.append(
                [
                    env_id,
                    RELIABILITY_STYLE[name][1] + ("" if name == "handcoded" else f" `{e['cell_id']}`"),
                    f"{e['players']:,}",
                    f"{e['distance_mean']:.1f}",
                    f"{e['distance_median']:.1f}",
                    *(f"{100 * s[k]:.1f}%" for k in ("8", "16", "18", "20", "25")),
                    f"{100 * e['ball_loss_rate']:.1f}%",
                ]
            )
    return md_table(["env", "policy", "players", "mean (m)", "median (m)", ">= 8 m", ">= 16 m", ">= 18 m", ">= 20 m", ">= 25 m", "ball lost"], rows, "llrrrrrrrrr")


def _unique(results: list[dict[str, Any]], key: str) -> list[Any]:
    seen = []
    for r in results:
        value = r.get(key)
        if value and value not in seen:
            seen.append(value)
    return seen


def run_log(out: Path) -> list[dict[str, Any]]:
    """Every invocation of the runner on ``out``, killed and refused ones too (:func:`benchmarks.provenance.invocations`)."""
    return invocations(out)


def _invocation_text(entry: dict[str, Any]) -> str:
    wall = "no end record" if entry["wall_s"] is None else f"{entry['wall_s'] / 60:.1f} min"
    cells = f", {entry['done']} cells run, {entry['skipped']} skipped" if "done" in entry else ""
    return f"{entry['status']}: {wall} with {entry['workers']} workers{cells}"


def setup_section(out: Path, results: list[dict[str, Any]], groups: dict[str, list[Group]], reliability: dict[str, Any] | None) -> list[str]:
    lines = ["## How this was made", ""]
    commands = _unique(results, "command")
    lines += ["Commands (from the repository root, with `PYTHONPATH=.:envs`):", "", "```bash"]
    lines += commands or ["(unknown: the cell files name no command)"]
    if reliability:
        lines.append(reliability.get("command") or "python -m benchmarks.run --reliability --out DIR")
    lines += [f"python -m benchmarks.report {out}", "```", ""]
    log = run_log(out)
    if log:
        total = sum(entry["wall_s"] or 0.0 for entry in log)
        parts = "; ".join(_invocation_text(e) for e in log)
        lines.append(f"Sweep wall time: {total / 60:.1f} min over {len(log)} invocation(s) of the runner ({parts}).")
    cpu_s = sum(r.get("wall_s", 0.0) for r in results)
    lines.append(f"Summed wall time of the {len(results)} cells: {cpu_s / 60:.1f} min (what one worker would need).")
    loads = [v for r in results for v in (r.get("loadavg") or {}).values() if v is not None]
    if loads:
        lines.append(
            f"The machine's 1-minute load average during the cells ranged {min(loads):.1f}-{max(loads):.1f}: other jobs "
            "shared the cores, so wall times and decision costs are indicative, not precise."
        )
    lines.append("")
    for m in _unique(results, "machine"):
        lines.append(f"- Machine: {m['cpu']}, {m['cores']} cores, {m['platform']}; torch threads per worker {m['torch_threads']}, BLAS threads 1.")
    for v in _unique(results, "versions"):
        lines.append("- Versions: " + ", ".join(f"{k} {val}" for k, val in v.items()))
    lines.append("")
    lines += ["Budgets:", ""]
    for env_id, gs in groups.items():
        lines.append(f"- {env_id}: {_budget_note(gs)}.")
    started = sorted(r["started"] for r in results if "started" in r)
    if started:
        lines.append(f"- Cells started between {started[0]} and {started[-1]}.")
    lines.append("")
    return lines


def method_section(results: list[dict[str, Any]]) -> list[str]:
    cell = next((r["cell"] for r in results if r["cell"]["algo"] != "Reference"), None)
    lines = ["## Method", ""]
    if cell:
        lines.append(
            f"- **Learning curves**: every {cell['eval_every']:,} training episodes, {cell['eval_episodes']} greedy episodes on a fixed evaluation set "
            f"(`evaluate_dribbling(..., seed={results[0].get('eval_seed', 10000)})`: the same players, starts and noise for every cell); a point before "
            "training and one where training ended. x = training episodes (or env steps) of the run; y = mean metres dribbled."
        )
        lines.append(
            f"- **Final evaluation**: {cell['final_episodes']:,} greedy episodes on another fixed set (seed {results[0].get('final_seed', 20000)}). "
            "'>= 20 m' is the share of those episodes that dribbled at least 20 m; 'ball lost' the share that ended by losing the ball "
            "(the rest kept it for all 35 actions)."
        )
    lines += [
        "- **Statistics**: IQM over seeds (the mean of the middle half; with 3 or fewer seeds the mean) with a 95% percentile "
        "bootstrap CI (scipy.stats.bootstrap, 2,000 resamples). With 3-5 seeds the intervals are rough.",
        f"- **Verdicts** (`benchmarks/significance.py`): SarsaAAC against a baseline by Welch's t-test on the difference of "
        f"mean final distances (two-sided, 5%), with bootstrap CIs of the differences of means and IQMs and the probability "
        f"of improvement beside it, never from overlapping CIs; a paper's figure is 'met' only when a one-sided t-test "
        f"shows our mean past it (5%). Fewer than {MIN_SEEDS} seeds on a side: no verdict.",
        "- **Episodes / time to 20 m and 25 m**: per seed, the first curve point whose greedy mean reaches the mark (training episodes, "
        "and training seconds excluding the evaluations); mean over the seeds that reached it.",
        "- **Decision cost**: median wall time of one `predict(obs, deterministic=True)` on a single observation "
        "(300 observations), including for baselines the conversion to the env's Tuple action. The paper's cost model "
        "for RBF arrays is 6·n·c_g + 3·c_c per decision (n Gaussians per approximator).",
        "- **References** (no learning): the hand-coded look-ahead dribbler (`robocup_dribble.dribbler.HandCodedDribbler`), "
        "evaluated on the same final set; the running ceiling (`running_ceiling`): metres 1,000 fresh players cover in "
        "35 full-power dashes from rest without a ball and without noise. No dribbler can beat it in 35 actions; "
        "'% of ceiling' divides by its mean.",
        "- **Baselines** train on the same env ids through `FlattenParameterizedAction` (PPO, A2C, SAC, TD3, DDPG) or "
        "`DiscretizeParameterizedAction` (DQN, 5 values per parameter, 80 actions), and are evaluated through an "
        "adapter that applies the wrappers' conversion to the greedy action. Hyperparameters: SB3 defaults except "
        "(see `benchmarks/presets.py` for the reasons):",
    ]
    seen = set()
    for r in results:
        algo = r["cell"]["algo"]
        if algo in BASELINES and algo not in seen:
            seen.add(algo)
            cfg = r["algo_config"]
            lines.append(f"  - {algo}: n_envs={cfg['n_envs']}, {cfg['wrapper']}" + (f" (bins={cfg['bins']})" if "bins" in cfg else "") + f", {json.dumps(cfg['kwargs'])}" + (f", Gaussian action noise sigma={cfg['action_noise_sigma']}" if "action_noise_sigma" in cfg else ""))
    lines += [
        "  The off-policy baselines take one gradient step per 16 (SAC, TD3, DDPG) or 8 (DQN) transitions, far fewer "
        "than their defaults (one per transition), to fit the time box at SarsaAAC's step budget. That handicaps their sample "
        "efficiency; it is the price of equal env steps within the time box.",
        "- **SarsaAAC** runs with its defaults on `DribbleVecEnv(16)`; only the policy and its `hidden_units` / `n_rbf` change.",
        "",
    ]
    return lines


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
    groups, references = group_results(results)
    if figures:
        family_figs = {f: family_figure(out, f, groups, references) for f in FAMILIES}
        best = best_figure(out, groups, references)
        final = final_figure(out, groups, references)
        rel_fig = reliability_figure(out, reliability) if reliability else None
    else:
        family_figs = {f: FAMILY_FIGURES[f][0] if any(g.family == f for gs in groups.values() for g in gs) else None for f in FAMILIES}
        best = "fig_best.png" if any(groups.values()) else None
        final = "fig_final.png" if best else None
        rel_fig = "fig_reliability.png" if reliability else None

    lines = [
        "# Benchmark: SarsaAAC against SB3 baselines on RoboCup dribbling",
        "",
        f"Generated {time.strftime('%Y-%m-%d %H:%M')} from {len(results)} cell files in `{out}`.",
        "",
        "## Summary",
        "",
        *(baseline_verdicts(groups) or ["- No env has both SarsaAAC and baseline cells."]),
        "",
        "### The paper's figures against ours",
        "",
        paper_claims(groups, reliability),
        "",
        "The paper's runs were on a real rcssserver 11 with reward constants, parameter meanings and exploration we had "
        "to choose ourselves (see `../shared/ref/paper-notes.md` and the env's README); its episode counts are for "
        "one learner, ours come from 16 lanes learning together.",
        "",
    ]
    lines += setup_section(out, results, groups, reliability)
    lines += method_section(results)
    lines += ["## Results per env (Table 1 of the paper, extended)", ""]
    for env_id, gs in groups.items():
        ref = references.get(env_id)
        lines += [f"### {env_title(env_id)}", "", "Greedy performance at the end of training:", "", performance_table(gs, ref), ""]
        lines += ["Learning speed and cost:", "", cost_table(gs, ref), ""]
    missing = [e for e in references if e not in groups]
    for env_id in missing:
        lines += [f"### {env_title(env_id)}", "", performance_table([], references[env_id]), ""]
    lines += ["## Figures", ""]
    for family in FAMILIES:
        if family_figs[family]:
            lines += [f"### {FAMILY_TITLES[family]} (paper {FAMILY_FIGURES[family][1]})", "", f"![{family}]({family_figs[family]})", ""]
    if best:
        lines += ["### Best of each family and the baselines (paper Fig. 8)", "", "Left: against training episodes (the paper's axis); right: against env steps (the budget all algorithms share).", "", f"![best]({best})", ""]
    if final:
        lines += ["### Final distance of every config", "", f"![final]({final})", ""]
    lines += ["## Reliability test (paper Figs. 9-10)", ""]
    if reliability:
        lines += [
            f"10,000 fresh players (a new player-type set for every episode, seed {reliability['seed']}), one episode each, greedy. "
            "The policies are the best SarsaAAC cell and the best baseline cell of each env (best config by IQM final distance, "
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
