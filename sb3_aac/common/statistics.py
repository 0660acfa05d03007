"""Two small tests shared by the command line and the benchmarks: Welch's t-test and the t-interval of a mean.

scipy is imported when one is called (it is an optional dependency: ``pip install sb3-aac[plots]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def scores_sample(values: Any, name: str) -> np.ndarray:
    """``values`` as a float array. :raises ValueError: unless it is a 1-D sequence of finite scores."""
    array = np.asarray(values, dtype=float)
    if array.ndim != 1:
        raise ValueError(f"{name} must be a 1-D sequence of scores, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite, got {array.tolist()}")
    return array


def welch_test(a: Any, b: Any) -> tuple[float, float]:
    """Welch's two-sided t-test of mean(a) = mean(b): ``(t, p)``; ``scipy.stats.ttest_ind(equal_var=False)``.

    When both samples have zero variance scipy gives NaN; then the means either agree (``t = 0, p = 1``) or differ
    with no noise at all (``t = +-inf, p = 0``).

    :raises ValueError: for fewer than 2 scores on a side, or scores that are not a finite 1-D sequence.
    """
    from scipy import stats

    a, b = scores_sample(a, "a"), scores_sample(b, "b")
    if len(a) < 2 or len(b) < 2:
        raise ValueError(f"Welch's test needs at least 2 scores per side, got {len(a)} and {len(b)}")
    if np.ptp(a) == 0 and np.ptp(b) == 0:
        diff = a[0] - b[0]
        return (0.0, 1.0) if diff == 0 else (float(np.sign(diff) * np.inf), 0.0)
    result = stats.ttest_ind(a, b, equal_var=False)
    return float(result.statistic), float(result.pvalue)


def mean_interval(values: Any, confidence: float = 0.95) -> tuple[float, float]:
    """The two-sided Student-t confidence interval of the mean of ``values`` at ``confidence``.

    :raises ValueError: for fewer than 2 values, non-finite values, or ``confidence`` outside (0, 1).
    """
    from scipy import stats

    x = scores_sample(values, "values")
    if len(x) < 2:
        raise ValueError(f"a confidence interval of a mean needs at least 2 values, got {len(x)}")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie in (0, 1), got {confidence!r}")
    half = float(stats.t.ppf(0.5 + confidence / 2, len(x) - 1)) * float(np.std(x, ddof=1)) / np.sqrt(len(x))
    return float(np.mean(x)) - half, float(np.mean(x)) + half
