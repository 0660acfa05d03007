"""The domain tasks of benchmarks/learning.py (Moving-v0, Sliding-v0, CatchPoint-v0 scored by greedy success) and the
comparison with TD3 of benchmarks/learning.py (efficiency)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from benchmarks import domains, learning
from benchmarks.learning import Curve, compare, reference_step
from hybrid_domains.baselines import scripted_policy


class Scripted:
    """The domain's scripted controller behind SB3's ``predict`` (one observation or a batch)."""

    def __init__(self, env_id: str):
        self.act = scripted_policy(env_id)

    def predict(self, obs: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True):
        obs = np.asarray(obs)
        if obs.ndim == 1:
            return self.act(obs), state
        actions = np.empty(len(obs), dtype=object)
        actions[:] = [self.act(o) for o in obs]
        return actions, state


@pytest.mark.parametrize("task", sorted(learning.DOMAIN_TASKS))
def test_domain_task_trains_and_scores_a_success_rate(task):
    model = learning.build(task, "tile", 0, None, None, {})
    model.learn(300, log_interval=None)
    assert model.num_timesteps == 300
    score = learning.TASKS[task][4](model, True)
    assert 0.0 <= score <= 1.0


@pytest.mark.parametrize("env_id", ["CatchPoint-v0", "Moving-v0"])
def test_batched_success_plays_the_slots_of_episodic_returns(env_id):
    # The scripted controller succeeds on most but not all episodes, so the flags tell episodes apart.
    batched = learning.domain_episode_success(env_id, Scripted(env_id), 40, seed=3, width=7)
    _, one_by_one = domains.episodic_returns(env_id, Scripted(env_id), 40, seed=3)
    np.testing.assert_array_equal(batched, one_by_one)
    assert 0.5 < batched.mean() < 1.0


def test_domain_success_needs_a_success_flag():
    with pytest.raises(ValueError, match="flags no success"):
        learning.domain_success("Platform-v0")


def curve(learner: str, seed: int, scores: list[float], final: float, every: int = 10) -> Curve:
    points = [(every * (i + 1), s) for i, s in enumerate(scores)]
    return Curve("catch", learner, 4 if learner == "td3" else 1, seed, every, every * len(scores), points, final, 1.0)


def test_reference_step_is_where_the_mean_curve_reaches_90_percent_of_the_mean_final():
    td3 = [curve("td3", 0, [0.2, 0.8, 0.9, 1.0], 1.0), curve("td3", 1, [0.4, 0.9, 1.0, 1.0], 0.8)]
    # mean curve 0.3, 0.85, 0.95, 1.0; mean final 0.9, 90 % of it 0.81: reached at the second checkpoint
    assert reference_step(td3) == 20
    assert reference_step([curve("td3", 0, [0.1, 0.2], 1.0)]) is None


def test_compare_reads_learners_at_the_reference_step_and_gives_the_verdict():
    td3 = [curve("td3", seed, [0.2, 0.9, 1.0], 1.0) for seed in range(3)]
    close = [curve("tile", seed, [0.5, 0.86, 0.9], 0.9) for seed in range(3)]
    far = [curve("deep", seed, [0.5, 0.84, 0.9], 0.9) for seed in range(3)]
    short = [curve("mlp2", 0, [0.5], 0.5)]
    lines = compare(td3 + close + far + short)
    assert lines[0].startswith("catch   td3 lanes=4") and "reference_step=20" in lines[0]
    by_learner = {line.split()[1]: line for line in lines[1:]}
    assert "vs TD3 0.900: -0.040 met" in by_learner["tile"]
    assert "vs TD3 0.900: -0.060 missed" in by_learner["deep"]
    assert "end before TD3's reference step 20" in by_learner["mlp2"]
