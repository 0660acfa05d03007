"""The report's figures (matplotlib, Agg): learning curves per approximator family (paper Figs. 5-7), the best of each
family against the baselines (Fig. 8), the final distance of every config, and the reliability test (Figs. 9-10)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from benchmarks import domains
from benchmarks.groups import Group, best_group, budget_note, iqm_ci, scalar_ci
from benchmarks.presets import FAMILIES

COLORS = {
    "tile": "#d62728",
    "deep": "#ff7f0e",
    "hybridppo": "#74c476",
    "pdqn": "#2ca02c",
    "mpdqn": "#006d2c",
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

RELIABILITY_STYLE = {
    "sarsa_aac": ("#d94801", "best SarsaAAC"),
    "peer": ("#006d2c", "best parameterized peer"),
    "baseline": ("#6a51a3", "best baseline"),
    "handcoded": ("black", "hand-coded"),
}


def color_of(group: Group) -> str:
    return COLORS.get(group.config, "#333333")


def env_short(env_id: str) -> str:
    return {
        "RoboCupDribblePaper-v0": "RoboCupDribblePaper-v0 (v11 physics)",
        "RoboCupDribble-v0": "RoboCupDribble-v0 (v19 physics)",
        "Platform-v0": "Platform-v0",
    }.get(env_id, env_id)


def _plt():
    import matplotlib  # optional (sb3-aac[plots]); the Agg backend must be chosen before pyplot is imported

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # after the backend (above)

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
    ax.plot(grid, point, color=color_of(group), lw=2, label=f"{label or group.label} (n={n})")
    if n > 1:
        ax.fill_between(grid, low, high, color=color_of(group), alpha=0.2, lw=0)


REFERENCE_STYLES = ("--", ":", "-.", (0, (1, 3)))


def _published(env_id: str) -> tuple[tuple[str, float, str], ...]:
    return domains.episodic_domain(env_id).references


def _references(ax, env_id: str, reference: dict[str, Any] | None, legend: bool = True) -> None:
    """Horizontal reference lines: the hand-coded dribbler and the upper bound, or the domain's published figures."""
    if not domains.is_dribbling(env_id):
        for i, (name, value, _) in enumerate(_published(env_id)):
            style = REFERENCE_STYLES[i % len(REFERENCE_STYLES)]
            ax.axhline(value, color="0.3", ls=style, lw=1.1, label=f"{name}, published ({value:.3g})" if legend else None)
        return
    if reference is None:
        return
    ref = reference["references"]
    hand = ref["handcoded"]["final"]["distance_mean"]
    bound = ref["bound"]["mean"]
    ax.axhline(hand, color="black", ls="--", lw=1.2, label=f"hand-coded dribbler ({hand:.1f} m)" if legend else None)
    ax.axhline(bound, color="0.45", ls=":", lw=1.5, label=f"{ref['bound']['label']} ({bound:.1f} m)" if legend else None)


def _axes_style(ax, env_id: str, xlabel: str, ylim: tuple[float, float]) -> None:
    ax.set_xlabel(xlabel)
    ax.set_ylabel(f"greedy {domains.metric_label(env_id)}")
    ax.set_ylim(*ylim)
    ax.xaxis.set_major_formatter(_thousands())


def _thousands():
    from matplotlib.ticker import FuncFormatter  # optional (sb3-aac[plots]), as in _plt

    return FuncFormatter(lambda v, _: f"{v / 1000:g}k" if abs(v) >= 1000 else f"{v:g}")


def _ylim(references: dict[str, Any], env_id: str, groups: list[Group]) -> tuple[float, float]:
    """The score axis of an env: from 0 (or the lowest curve point, for returns that go negative) to above the
    highest curve point and reference (at least 25 m on dribbling, 1.05 for shares and Platform's return)."""
    top = [float(np.max(g.curve()[1])) for g in groups]
    low = min([0.0, *(float(np.min(g.curve()[1])) for g in groups)])
    if domains.is_dribbling(env_id):
        top += [r["references"]["bound"]["mean"] for e, r in references.items() if e == env_id]
        return 0.0, max([25.0, *top]) * 1.08
    top += [value for _, value, _ in _published(env_id)]
    return low * 1.08, max([1.0, *top]) * 1.05


def family_figure(out: Path, family: str, groups: dict[str, list[Group]], references: dict[str, Any]) -> str | None:
    plt = _plt()
    env_ids = [e for e, gs in groups.items() if any(g.family == family for g in gs) and domains.is_dribbling(e)]
    if not env_ids:
        return None
    name, paper_fig = FAMILY_FIGURES[family]
    fig, axes = plt.subplots(1, len(env_ids), figsize=(6.4 * len(env_ids), 4.6), squeeze=False)
    for ax, env_id in zip(axes[0], env_ids, strict=True):
        fam = [g for g in groups[env_id] if g.family == family]
        for g in fam:
            _plot_group(ax, g, "episodes")
        _references(ax, env_id, references.get(env_id))
        _axes_style(ax, env_id, "training episodes", _ylim(references, env_id, fam))
        ax.set_title(f"{env_short(env_id)}\n{budget_note(fam)}", fontsize=10)
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
    axes_x = (("episodes", "training episodes"), ("env_steps", "training env steps"), ("train_s", "training seconds"))
    fig, axes = plt.subplots(len(env_ids), 3, figsize=(19, 4.6 * len(env_ids)), squeeze=False)
    for row, env_id in enumerate(env_ids):
        chosen = [g for f in FAMILIES if (g := best_group(groups[env_id], ("SarsaAAC",), f)) is not None]
        chosen += [g for g in groups[env_id] if g.algo != "SarsaAAC"]
        for col, (x, xlabel) in enumerate(axes_x):
            ax = axes[row, col]
            for g in chosen:
                label = f"SarsaAAC {g.label}" if g.algo == "SarsaAAC" else g.label
                _plot_group(ax, g, x, label)
            _references(ax, env_id, references.get(env_id))
            _axes_style(ax, env_id, xlabel, _ylim(references, env_id, chosen))
            if x == "train_s":
                ax.set_xscale("log")
                ax.xaxis.set_major_formatter(_thousands())
            ax.set_title(f"{env_short(env_id)}: vs {xlabel.split(' ', 1)[1]}", fontsize=10.5)
        axes[row, 2].legend(
            loc="center left",
            bbox_to_anchor=(1.01, 0.5),
            frameon=False,
            title=budget_note(chosen).replace("; ", "\n"),
            title_fontsize=8.5,
        )
    fig.suptitle(
        "Best SarsaAAC config of each family, the parameterized peers and the SB3 baselines (cf. paper Fig. 8)\n"
        "IQM over seeds with 95% bootstrap CI",
        fontsize=12,
    )
    fig.tight_layout()
    fig.savefig(out / "fig_best.png", bbox_inches="tight")
    plt.close(fig)
    return "fig_best.png"


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
        ax_h.set_title(
            f"{env_short(env_id)}: histogram, {next(iter(entries.values()))['players']:,} fresh players", fontsize=10
        )
        ax_h.legend(loc="upper right", frameon=False)
        ax_c.set_xlim(0, last)
        ax_c.set_ylim(0, 102)
        ax_c.axvline(18, color="0.5", ls=":", lw=1)
        ax_c.set_xlabel("metres m")
        ax_c.set_ylabel("players dribbling at least m metres (%)")
        ax_c.set_title(f"{env_short(env_id)}: share reaching each metre", fontsize=10)
        ax_c.legend(loc="lower left", frameon=False)
    fig.suptitle(
        "Reliability test (cf. paper Figs. 9-10): every player a fresh heterogeneous type, one greedy episode", fontsize=12
    )
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
    fig, axes = plt.subplots(
        1,
        len(env_ids),
        figsize=(max(8.5, 6.8 * len(env_ids)), 0.42 * max(len(groups[e]) for e in env_ids) + 2.4),
        squeeze=False,
    )
    for ax, env_id in zip(axes[0], env_ids, strict=True):
        gs = groups[env_id][::-1]
        for y, g in enumerate(gs):
            finals = g.final()
            point, low, high = scalar_ci(finals)
            ax.plot([low, high], [y, y], color=color_of(g), lw=5, alpha=0.45, solid_capstyle="butt")
            ax.plot(point, y, "|", color=color_of(g), ms=16, mew=2.5)
            ax.plot(finals, np.full(len(finals), y), "o", color=color_of(g), ms=3.5, mfc="white", mew=1)
        ax.set_yticks(range(len(gs)), [g.label for g in gs])
        ref = references.get(env_id)
        if not domains.is_dribbling(env_id):
            for name, value, _ in _published(env_id):
                ax.axvline(value, color="0.45", ls=":", lw=1.2)
                ax.text(value, len(gs) - 0.35, f"{name} {value:.3g} ", va="bottom", ha="right", fontsize=7.5, rotation=90)
            ax.set_ylim(-0.6, len(gs) + 0.1)
        elif ref:
            hand = ref["references"]["handcoded"]["final"]["distance_mean"]
            bound = ref["references"]["bound"]["mean"]
            ax.axvline(hand, color="black", ls="--", lw=1.2)
            ax.axvline(bound, color="0.45", ls=":", lw=1.5)
            top = len(gs) - 0.35
            ax.text(hand, top, f" hand-coded {hand:.1f} m", va="bottom", ha="left", fontsize=8.5)
            label = ref["references"]["bound"]["label"]
            ax.text(bound, top, f"{label} {bound:.1f} m ", va="bottom", ha="right", fontsize=8.5, color="0.35")
            ax.set_ylim(-0.6, len(gs) + 0.1)
        ax.set_xlabel(f"final greedy {domains.metric_label(env_id)}")
        if ref or not domains.is_dribbling(env_id):
            low, high = _ylim(references, env_id, [])
            lowest = min([low, *(float(np.min(g.final())) for g in gs)])
            ax.set_xlim(lowest * 1.08 if lowest < 0 else lowest, high)
        ax.set_title(f"{env_short(env_id)}\n{budget_note(groups[env_id])}", fontsize=10)
        ax.grid(axis="y", alpha=0)
    fig.suptitle("Final greedy score per config\n(dots: seeds; tick: IQM; band: 95% bootstrap CI)", fontsize=12)
    fig.tight_layout()
    fig.savefig(out / "fig_final.png", bbox_inches="tight")
    plt.close(fig)
    return "fig_final.png"
