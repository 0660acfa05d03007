"""The benchmark's verdict statistics (benchmarks/significance.py): reference numbers, power, false positives."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from benchmarks import significance as sig

A = [1.0, 2.0, 3.0, 4.0, 5.0]
B = [2.0, 4.0, 6.0, 8.0, 10.0]


def test_welch_against_the_textbook_formula():
    # mean difference -3; variances 2.5 and 10; se = sqrt(2.5/5 + 10/5); Welch-Satterthwaite df = 6.25 / (0.25/4 + 4/4)
    se = np.sqrt(2.5 / 5 + 10 / 5)
    df = (2.5 / 5 + 10 / 5) ** 2 / ((2.5 / 5) ** 2 / 4 + (10 / 5) ** 2 / 4)
    t, p = sig.welch_test(A, B)
    assert t == pytest.approx(-3 / se, rel=1e-12)
    assert df == pytest.approx(5.882352941176471)
    assert p == pytest.approx(2 * stats.t.sf(3 / se, df), rel=1e-10)
    assert p == pytest.approx(0.1075, abs=5e-5)  # R: t.test(1:5, c(2, 4, 6, 8, 10)): t = -1.8974, p-value = 0.1075


def test_welch_without_any_noise():
    assert sig.welch_test([3.0, 3.0], [3.0, 3.0, 3.0]) == (0.0, 1.0)
    t, p = sig.welch_test([4.0, 4.0], [3.0, 3.0])
    assert t == np.inf and p == 0.0


def test_probability_of_improvement_is_the_mann_whitney_u_share():
    rng = np.random.default_rng(5)
    a = rng.integers(0, 6, size=12).astype(float)  # many ties
    b = rng.integers(0, 6, size=9).astype(float)
    u = stats.mannwhitneyu(a, b).statistic
    assert sig.probability_of_improvement(a, b) == pytest.approx(u / (12 * 9), abs=1e-12)
    assert sig.probability_of_improvement([1.0, 2.0], [0.0, 3.0]) == 0.5
    assert sig.probability_of_improvement([1.0], [1.0]) == 0.5


@settings(max_examples=50, deadline=None)
@given(
    st.lists(st.floats(-50, 50, allow_nan=False), min_size=1, max_size=12),
    st.lists(st.floats(-50, 50, allow_nan=False), min_size=1, max_size=12),
)
def test_probability_of_improvement_is_complementary(a, b):
    assert sig.probability_of_improvement(a, b) + sig.probability_of_improvement(b, a) == pytest.approx(1.0)


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.floats(0, 40, allow_nan=False), min_size=2, max_size=12),
    st.lists(st.floats(0, 40, allow_nan=False), min_size=2, max_size=12),
)
def test_swapping_the_configs_mirrors_the_verdict(a, b):
    mirrored = {"A better": "B better", "B better": "A better"}
    forward = sig.verdict(a, b, min_seeds=2)
    assert sig.verdict(b, a, min_seeds=2) == mirrored.get(forward, forward)


def test_bootstrap_intervals_are_seeded_and_hold_their_points():
    rng = np.random.default_rng(1)
    a, b = rng.normal(20, 2, 10), rng.normal(18, 2, 10)
    first = sig.compare(a, b, seed=3)
    assert first == sig.compare(a, b, seed=3)
    assert first.mean_difference_ci != sig.compare(a, b, seed=4).mean_difference_ci
    for point, (low, high) in (
        (first.mean_difference, first.mean_difference_ci),
        (first.iqm_difference, first.iqm_difference_ci),
        (first.probability_of_improvement, first.probability_of_improvement_ci),
    ):
        assert low <= point <= high
    assert 0.0 <= first.probability_of_improvement_ci[0] <= first.probability_of_improvement_ci[1] <= 1.0
    assert first.iqm_difference == pytest.approx(stats.trim_mean(a, 0.25) - stats.trim_mean(b, 0.25))


def test_a_known_difference_is_detected():
    rng = np.random.default_rng(0)
    a, b = rng.normal(2.0, 1.0, 10), rng.normal(0.0, 1.0, 10)  # 2 sd apart: Welch's power ~0.99
    result = sig.compare(a, b)
    assert result.outcome == "A better" and result.welch_p < 0.01
    assert result.mean_difference_ci[0] > 0 and result.probability_of_improvement > 0.8
    assert sig.verdict(b, a) == "B better"


def rejection_rate(shift: float, repetitions: int, n: int = 10, seed: int = 0) -> float:
    rng = np.random.default_rng(seed)
    outcomes = [sig.verdict(rng.normal(shift, 1.0, n), rng.normal(0.0, 1.0, n)) for _ in range(repetitions)]
    return float(np.mean([o != "no significant difference" for o in outcomes]))


def test_identical_distributions_are_flagged_at_rate_alpha():
    rate = rejection_rate(0.0, 4000)
    # binomial sd of the rate at 4,000 repetitions: 0.0034; 3 sd either side of alpha
    assert abs(rate - sig.ALPHA) < 0.011, rate


def test_power_one_sd_apart_with_ten_seeds_matches_theory():
    """1 sd apart, 10 seeds each: the test rejects as often as the noncentral t distribution says (~56%)."""
    df, nc = 18, 1.0 / np.sqrt(2 / 10)
    critical = stats.t.ppf(1 - sig.ALPHA / 2, df)
    power = stats.nct.sf(critical, df, nc) + stats.nct.cdf(-critical, df, nc)
    assert power == pytest.approx(0.56, abs=0.01)
    rate = rejection_rate(1.0, 2000, seed=1)
    assert abs(rate - power) < 0.04, (rate, power)  # Welch's df are a little below 18: slightly lower power


def test_too_few_seeds_decides_nothing():
    a, b = np.full(9, 30.0) + np.arange(9) * 0.01, np.full(9, 10.0) + np.arange(9) * 0.01
    result = sig.compare(a, b)
    assert result.outcome == "too few seeds" and result.welch_p < 1e-10  # the numbers are still reported
    assert sig.verdict(a, b, min_seeds=9) == "A better"
    assert sig.compare([1.0], [2.0, 3.0]).outcome == "too few seeds"


def test_target_verdicts():
    rng = np.random.default_rng(2)
    above, below, around = rng.normal(27, 1, 10), rng.normal(23, 1, 10), rng.normal(25, 3, 10)
    assert sig.target_verdict(above, 25.0).outcome == "met"
    assert sig.target_verdict(below, 25.0).outcome == "not met"
    assert sig.target_verdict(below, 25.0, "at most").outcome == "met"
    assert sig.target_verdict(above, 25.0, "at most").outcome == "not met"
    check = sig.target_verdict(around, 25.0)
    assert check.outcome == "not shown"
    # the bound is scipy's one-sided 95% confidence bound of the mean
    low = stats.ttest_1samp(around, 25.0, alternative="greater").confidence_interval(0.95).low
    assert check.bound == pytest.approx(low)
    assert check.p_value == pytest.approx(stats.ttest_1samp(around, 25.0, alternative="greater").pvalue)
    assert sig.target_verdict(above[:9], 25.0).outcome == "too few seeds"
    # a config that fails outright does not "meet" an at-least target however few seeds it has
    assert sig.target_verdict(np.zeros(10), 12.0).outcome == "not met"


def test_target_met_only_at_rate_alpha_when_exactly_on_target():
    rng = np.random.default_rng(3)
    outcomes = [sig.target_verdict(rng.normal(20, 2, 10), 20.0).outcome for _ in range(2000)]
    assert abs(outcomes.count("met") / 2000 - sig.ALPHA) < 0.015


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: sig.compare([[1.0, 2.0]], [1.0]), "1-D"),
        (lambda: sig.compare([1.0, float("nan")], [1.0, 2.0]), "finite"),
        (lambda: sig.compare([1.0, 2.0], [1.0, 2.0], alpha=1.5), "alpha"),
        (lambda: sig.compare([1.0, 2.0], [], min_seeds=2), "both sides"),
        (lambda: sig.verdict([1.0, 2.0], [1.0, 2.0], min_seeds=1), "min_seeds"),
        (lambda: sig.target_verdict([1.0, 2.0], 1.0, direction="above"), "direction"),
        (lambda: sig.welch_test([1.0], [1.0, 2.0]), "at least 2"),
    ],
)
def test_bad_input_is_refused(call, message):
    with pytest.raises(ValueError, match=message):
        call()
