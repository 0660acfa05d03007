"""The report's view of the results: the runs of one env x algorithm x config x budget as a :class:`Group`, their
learning curves on a common grid, and the interquartile mean (IQM) over seeds with its 95% percentile bootstrap
interval (``scipy.stats.bootstrap``), which the tables and figures show. Verdicts come from
:mod:`benchmarks.significance`, never from these intervals."""

from __future__ import annotations

import warnings
from collections import defaultdict
from typing import Any

import numpy as np
from scipy import stats

from benchmarks import domains
from benchmarks.presets import BASELINES, ENV_IDS, PEERS, SARSA_CONFIGS, base_config, config_label, is_tuned
from benchmarks.significance import IQM_TRIM, iqm

# The three kinds of learner a user chooses between; a headline pair is the best of two kinds on one env.
KINDS: dict[str, tuple[str, ...]] = {
    "SarsaAAC": ("SarsaAAC",),
    "parameterized peer": tuple(PEERS),
    "SB3 baseline": tuple(BASELINES),
}
INTERVAL_RESAMPLES = 2000  # bootstrap resamples of the intervals drawn and tabulated (verdicts use significance's)
GRID_POINTS = 80


class Group:
    """The runs (seeds) of one env x algorithm x config x budget (env steps, or ``seconds`` of training if > 0)."""

    def __init__(self, env_id: str, algo: str, config: str, budget: int, runs: list[dict[str, Any]], seconds: int = 0):
        self.env_id, self.algo, self.config, self.budget, self.seconds = env_id, algo, config, budget, seconds
        self.runs = sorted(runs, key=lambda r: r["cell"]["seed"])
        self.metric = domains.metric(env_id)  # the score that ranks policies on this env

    @property
    def label(self) -> str:
        return config_label(self.algo, self.config)

    @property
    def family(self) -> str:
        return self.runs[0]["family"]

    def final(self, key: str | None = None) -> np.ndarray:
        """Per seed: the final evaluation's ``key`` (default: the env's score)."""
        return np.array([r["final"][key or self.metric] for r in self.runs], dtype=float)

    def values(self, key: str) -> np.ndarray:
        return np.array([r[key] for r in self.runs], dtype=float)

    def curve(self, x: str = "episodes", y: str | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Grid ``(G,)`` over the x range every run reached, and the runs' interpolated values ``(runs, G)``
        (``y`` default: the env's score)."""
        end = min(r["curve"][-1][x] for r in self.runs)
        grid = np.linspace(0.0, end, GRID_POINTS) if end > 0 else np.zeros(1)
        return grid, self.at(x, grid, y)

    def at(self, x: str, where: float | np.ndarray, y: str | None = None) -> np.ndarray:
        """Per run (rows): the score (or ``y``) interpolated at ``where`` on the ``x`` axis of its curve (a run that
        ended before: its last point)."""
        key = y or self.metric
        return np.array([np.interp(where, [p[x] for p in r["curve"]], [p[key] for p in r["curve"]]) for r in self.runs])

    def first_reaching(self, threshold: float) -> list[dict[str, Any] | None]:
        """Per run: the first curve point whose score is at least ``threshold`` (None if never)."""
        return [next((p for p in r["curve"] if p[self.metric] >= threshold), None) for r in self.runs]


def group_results(results: list[dict[str, Any]]) -> tuple[dict[str, list[Group]], dict[str, dict[str, Any]]]:
    """Training groups per env (SarsaAAC configs in the paper's order, then baselines) and references per env."""
    buckets: dict[tuple[str, str, str, int, int], list[dict[str, Any]]] = defaultdict(list)
    references = {}
    for r in results:
        c = r["cell"]
        if c["algo"] == "Reference":
            references[c["env_id"]] = r
        elif "final" in r:
            buckets[(c["env_id"], c["algo"], c["config"], c["budget"], c.get("seconds", 0))].append(r)
    order = {name: i for i, name in enumerate([*SARSA_CONFIGS, *(a.lower() for a in (*PEERS, *BASELINES))])}
    groups: dict[str, list[Group]] = defaultdict(list)
    for key in sorted(buckets, key=lambda k: (k[0], k[4], order.get(base_config(k[2]), 99), is_tuned(k[2]), k[3])):
        env_id, algo, config, budget, seconds = key
        groups[env_id].append(Group(env_id, algo, config, budget, buckets[key], seconds))
    env_order = [e for e in ENV_IDS if e in groups or e in references] + sorted(set(groups) - set(ENV_IDS))
    return {e: groups.get(e, []) for e in env_order}, references


def iqm_ci(values: np.ndarray, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """IQM over runs (axis 0) and its 95% percentile bootstrap interval; the interval is the point itself for 1 run
    or runs that all agree."""
    values = np.asarray(values, dtype=float)
    point = iqm(values, axis=0)
    if values.shape[0] < 2:
        return point, point.copy(), point.copy()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # degenerate resamples (all runs equal) warn
        result = stats.bootstrap(
            (values,),
            lambda sample, axis: stats.trim_mean(sample, IQM_TRIM, axis=axis),
            n_resamples=INTERVAL_RESAMPLES,
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


def find_group(groups: list[Group], algo: str, config: str, budget: int) -> Group | None:
    """The group of ``algo`` with ``config`` at env-step ``budget`` among ``groups``, or None."""
    return next((g for g in groups if (g.algo, g.config, g.budget) == (algo, config, budget)), None)


def best_group(groups: list[Group], algos: tuple[str, ...], family: str | None = None, min_seeds: int = 0) -> Group | None:
    """The group with the highest IQM final score among ``algos`` (and ``family``) with at least ``min_seeds`` runs."""
    pool = [g for g in groups if g.algo in algos and (family is None or g.family == family) and len(g.runs) >= min_seeds]
    return max(pool, key=lambda g: float(iqm(g.final()))) if pool else None


def budget_note(groups: list[Group]) -> str:
    """The groups' env-step budgets and seed counts, SarsaAAC first (a figure title, a setup line)."""
    parts: dict[tuple[int, int], list[str]] = defaultdict(list)
    for g in groups:
        parts[(g.budget, len(g.runs))].append(g.label)
    return "; ".join(f"{b:,} env steps x {n} seeds ({', '.join(labels)})" for (b, n), labels in sorted(parts.items()))
