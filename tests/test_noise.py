"""The noise model against the spread a real server showed: 10 cases, each recorded 50 times with default noise.

For each case we run 4000 simulated repetitions and compare every cycle's mean and spread of positions and
velocities with the recorded ones. A sample variance of 50 runs divided by the true variance follows
chi2(49)/49, so the median ratio over a case's cells stays near 1; a box-shaped noise (the v11 model, twice the
variance) or a wrong scale moves it far away, which the last test checks.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from robocup_dribble import physics, validate
from tests.conftest import golden_file

CASES = list(validate.read_cases(golden_file("rcss-noise.jsonl")))
COLUMNS = {
    "px": physics.P_X,
    "py": physics.P_Y,
    "pvx": physics.P_VX,
    "pvy": physics.P_VY,
    "bx": physics.B_X,
    "by": physics.B_Y,
    "bvx": physics.B_VX,
    "bvy": physics.B_VY,
}
RUNS = 4000


def variance_ratios(case: dict, shape: str = "polar") -> tuple[np.ndarray, np.ndarray]:
    """Recorded/simulated variance ratios and mean z-scores over the case's cells with real spread."""
    profile = dataclasses.replace(validate.case_profile(case), noise_shape=shape)
    states, _ = validate.simulate_case(case, RUNS, np.random.default_rng(7), profile)
    ratios, z_scores = [], []
    n = case["repetitions"]
    for cycle, summary in enumerate(case["summary_per_cycle"]):
        for name, column in COLUMNS.items():
            simulated = states[:, cycle, column]
            sigma = simulated.std()
            if sigma < 1e-6:  # a quantity the noise does not reach (e.g. the idle ball)
                assert summary[name]["std"] < 1e-5, (case["id"], cycle, name)
                continue
            ratios.append(summary[name]["std"] ** 2 / sigma**2)
            z_scores.append((summary[name]["mean"] - simulated.mean()) / (sigma / np.sqrt(n)))
    return np.array(ratios), np.array(z_scores)


@pytest.mark.parametrize("case", CASES, ids=[case["id"] for case in CASES])
def test_spread_and_mean_match_the_server(case):
    ratios, z_scores = variance_ratios(case)
    assert len(ratios) > 0
    assert 0.6 < np.median(ratios) < 1.6, f"{case['id']}: median variance ratio {np.median(ratios):.2f}"
    assert np.all(ratios > 0.3) and np.all(ratios < 2.5), f"{case['id']}: variance ratios {np.round(ratios, 2)}"
    assert np.all(np.abs(z_scores) < 5.0), f"{case['id']}: mean z-scores {np.round(z_scores, 1)}"


def test_the_check_rejects_box_shaped_noise():
    rejected = 0
    for case in CASES:
        ratios, _ = variance_ratios(case, shape="box")
        rejected += not 0.6 < np.median(ratios) < 1.6
    assert rejected >= 8, f"box noise passed for {len(CASES) - rejected} of {len(CASES)} cases"
