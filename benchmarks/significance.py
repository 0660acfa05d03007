"""Verdicts over seeds that cannot mislead: tests on the *difference* of two configs, and tests against a target.

Every verdict of the report comes from here, and none from whether two confidence intervals overlap (two 95%
intervals can overlap while the difference is significant, and can miss each other by a hair while it is not).

* :func:`compare` / :func:`verdict`: config A against config B, one final score per seed (independent seeds).
  The decision is **Welch's t-test** on the difference of the means (two-sided, level ``alpha``): "A better" or
  "B better" when it rejects, by the sign of the mean difference, else "no significant difference". Fewer than
  :data:`MIN_SEEDS` seeds on either side give "too few seeds" whatever the numbers. Reported beside it (not
  deciding): percentile bootstrap CIs of the difference of means and of IQMs (each side resampled on its own,
  seeded), and the probability of improvement with its bootstrap CI.
* :func:`target_verdict`: one config against a fixed target (a paper's figure). "met" only when a **one-sided
  one-sample t-test** rejects "the mean is on the wrong side of the target" at level ``alpha`` (equivalently: the
  one-sided ``1 - alpha`` lower confidence bound of the mean is above the target, for an "at least" target); "not
  met" when the opposite one-sided test rejects; "not shown" otherwise; "too few seeds" below ``min_seeds``.

The probability of improvement is rliable's (Agarwal et al. 2021): ``P(X > Y) + 0.5 P(X = Y)`` for X a score of A
and Y one of B, estimated over all pairs of seeds (the Mann-Whitney U statistic divided by ``n_a * n_b``).
rliable itself is not used: its bootstrap imports ``arch``, which does not import next to pandas 3 here.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np
from scipy import stats

from sb3_aac.common.statistics import scores_sample, welch_test

MIN_SEEDS = 10  # seeds per side below which no comparison or target verdict is given (headline pairs)
ALPHA = 0.05
BOOTSTRAP_RESAMPLES = 10_000
CONFIDENCE = 0.95
IQM_TRIM = 0.25  # the interquartile mean cuts 25% at each end (scipy.stats.trim_mean), as rliable's IQM

Outcome = Literal["A better", "B better", "no significant difference", "too few seeds"]
TargetOutcome = Literal["met", "not met", "not shown", "too few seeds"]


@dataclass(frozen=True)
class Comparison:
    """Config A against config B (one score per seed each); differences are A - B.

    ``outcome`` is decided by ``welch_p`` alone (see :func:`compare`); the intervals are percentile bootstrap
    intervals at :data:`CONFIDENCE`, for reading, not for deciding.
    """

    outcome: Outcome
    n_a: int
    n_b: int
    alpha: float
    min_seeds: int
    mean_difference: float
    welch_t: float
    welch_p: float
    mean_difference_ci: tuple[float, float]
    iqm_difference: float
    iqm_difference_ci: tuple[float, float]
    probability_of_improvement: float
    probability_of_improvement_ci: tuple[float, float]

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class TargetCheck:
    """One config's per-seed scores against a target; ``outcome`` from one-sided one-sample t-tests."""

    outcome: TargetOutcome
    n: int
    target: float
    direction: Literal["at least", "at most"]
    mean: float
    p_value: float  # of the test whose rejection means "met" (H0: the mean is on the wrong side of the target)
    bound: float  # the one-sided 1 - alpha confidence bound of the mean on the side the target is checked from
    alpha: float

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _check_alpha(alpha: float) -> None:
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha must be in (0, 1), got {alpha}")


def iqm(values: np.ndarray, axis: int = -1) -> np.ndarray:
    """Interquartile mean along ``axis``: the mean after cutting :data:`IQM_TRIM` of the values at each end."""
    return np.asarray(stats.trim_mean(values, IQM_TRIM, axis=axis))


def probability_of_improvement(a: Any, b: Any) -> float:
    """``P(X > Y) + 0.5 P(X = Y)`` over all pairs (X from ``a``, Y from ``b``): rliable's probability of improvement."""
    a, b = scores_sample(a, "a"), scores_sample(b, "b")
    if len(a) == 0 or len(b) == 0:
        raise ValueError("probability_of_improvement needs at least one score per side")
    return float(_poi(a[None, :], b[None, :])[0])


def _poi(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Probability of improvement of each row of ``a`` (R, n) over the same row of ``b`` (R, m)."""
    greater = np.mean(a[:, :, None] > b[:, None, :], axis=(1, 2))
    ties = np.mean(a[:, :, None] == b[:, None, :], axis=(1, 2))
    return np.asarray(greater + 0.5 * ties, dtype=float)


def _percentile_ci(samples: np.ndarray) -> tuple[float, float]:
    tail = 100 * (1 - CONFIDENCE) / 2
    low, high = np.percentile(samples, [tail, 100 - tail])
    return float(low), float(high)


def bootstrap_differences(
    a: Any, b: Any, seed: int = 0, n_resamples: int = BOOTSTRAP_RESAMPLES
) -> dict[str, tuple[float, float]]:
    """Percentile bootstrap CIs (:data:`CONFIDENCE`) of ``mean(a) - mean(b)``, ``IQM(a) - IQM(b)`` and the probability
    of improvement of ``a`` over ``b``; ``a`` and ``b`` are resampled independently (the seeds are independent runs)
    from ``numpy.random.default_rng(seed)``, so the same inputs and seed give the same intervals."""
    a, b = scores_sample(a, "a"), scores_sample(b, "b")
    if len(a) == 0 or len(b) == 0:
        raise ValueError("bootstrap_differences needs at least one score per side")
    if n_resamples < 1:
        raise ValueError(f"n_resamples must be positive, got {n_resamples}")
    rng = np.random.default_rng(seed)
    resampled_a = a[rng.integers(len(a), size=(n_resamples, len(a)))]
    resampled_b = b[rng.integers(len(b), size=(n_resamples, len(b)))]
    return {
        "mean_difference": _percentile_ci(resampled_a.mean(axis=1) - resampled_b.mean(axis=1)),
        "iqm_difference": _percentile_ci(iqm(resampled_a, axis=1) - iqm(resampled_b, axis=1)),
        "probability_of_improvement": _percentile_ci(_poi(resampled_a, resampled_b)),
    }


def _decide(a: np.ndarray, b: np.ndarray, alpha: float, min_seeds: int) -> tuple[Outcome, float, float]:
    """The outcome of :func:`compare` and Welch's ``(t, p)`` (NaN with fewer than 2 scores on a side)."""
    _check_alpha(alpha)
    if min_seeds < 2:
        raise ValueError(f"min_seeds must be at least 2 (a t-test needs a variance), got {min_seeds}")
    if len(a) == 0 or len(b) == 0:
        raise ValueError(f"a comparison needs scores on both sides, got {len(a)} and {len(b)}")
    t, p = welch_test(a, b) if len(a) >= 2 and len(b) >= 2 else (float("nan"), float("nan"))
    if len(a) < min_seeds or len(b) < min_seeds:
        return "too few seeds", t, p
    if p < alpha:
        return ("A better" if a.mean() > b.mean() else "B better"), t, p
    return "no significant difference", t, p


def compare(a: Any, b: Any, alpha: float = ALPHA, min_seeds: int = MIN_SEEDS, seed: int = 0) -> Comparison:
    """Config A against config B from one final score per seed: the verdict and the figures behind it.

    The outcome is "too few seeds" if either side has fewer than ``min_seeds`` scores; otherwise "A better" /
    "B better" when Welch's two-sided test on the difference of means rejects at ``alpha`` (the sign of the mean
    difference says which), else "no significant difference". The bootstrap intervals (``seed``) never decide.
    """
    a, b = scores_sample(a, "a"), scores_sample(b, "b")
    outcome, t, p = _decide(a, b, alpha, min_seeds)
    cis = bootstrap_differences(a, b, seed)
    return Comparison(
        outcome=outcome,
        n_a=len(a),
        n_b=len(b),
        alpha=alpha,
        min_seeds=min_seeds,
        mean_difference=float(a.mean() - b.mean()),
        welch_t=t,
        welch_p=p,
        mean_difference_ci=cis["mean_difference"],
        iqm_difference=float(iqm(a) - iqm(b)),
        iqm_difference_ci=cis["iqm_difference"],
        probability_of_improvement=probability_of_improvement(a, b),
        probability_of_improvement_ci=cis["probability_of_improvement"],
    )


def verdict(a: Any, b: Any, alpha: float = ALPHA, min_seeds: int = MIN_SEEDS) -> Outcome:
    """The outcome of :func:`compare` without its bootstrap intervals (cheap enough to call thousands of times)."""
    return _decide(scores_sample(a, "a"), scores_sample(b, "b"), alpha, min_seeds)[0]


def target_verdict(
    values: Any,
    target: float,
    direction: Literal["at least", "at most"] = "at least",
    alpha: float = ALPHA,
    min_seeds: int = MIN_SEEDS,
) -> TargetCheck:
    """Whether the config whose per-seed scores are ``values`` reaches ``target`` ("at least") or stays under it
    ("at most").

    "met" only when the one-sided one-sample t-test of H0 "mean < target" (for "at least"; "mean > target" for
    "at most") rejects at ``alpha``, i.e. the one-sided ``1 - alpha`` confidence bound of the mean is past the
    target; "not met" when the opposite one-sided test rejects; "not shown" when neither does; "too few seeds" with
    fewer than ``min_seeds`` scores. Scores without any spread count as exact (a test of a constant cannot err).
    """
    values = scores_sample(values, "values")
    _check_alpha(alpha)
    if direction not in ("at least", "at most"):
        raise ValueError(f"direction must be 'at least' or 'at most', got {direction!r}")
    if min_seeds < 2:
        raise ValueError(f"min_seeds must be at least 2 (a t-test needs a variance), got {min_seeds}")
    n, mean = len(values), float(np.mean(values)) if len(values) else float("nan")
    sign = 1.0 if direction == "at least" else -1.0
    if n < 2:
        p_met = p_not = bound = float("nan")
    elif np.ptp(values) == 0:
        p_met = 0.0 if sign * (mean - target) > 0 else 1.0
        p_not = 0.0 if sign * (mean - target) < 0 else 1.0
        bound = mean
    else:
        # H0 of "met": the mean is on the wrong side (below an "at least" target, above an "at most" one)
        p_met = float(stats.ttest_1samp(values, target, alternative="greater" if sign > 0 else "less").pvalue)
        p_not = float(stats.ttest_1samp(values, target, alternative="less" if sign > 0 else "greater").pvalue)
        margin = float(stats.t.ppf(1 - alpha, n - 1) * stats.sem(values))
        bound = mean - sign * margin
    outcome: TargetOutcome
    if n < min_seeds:
        outcome = "too few seeds"
    elif p_met < alpha:
        outcome = "met"
    elif p_not < alpha:
        outcome = "not met"
    else:
        outcome = "not shown"
    return TargetCheck(outcome, n, float(target), direction, mean, p_met, bound, alpha)
