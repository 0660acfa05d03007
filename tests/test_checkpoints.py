"""GreedyCheckpoints: when the checkpoints fall, what they record, and how a checkpoint stops training."""

from __future__ import annotations

import pytest
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac import SarsaAAC
from sb3_aac.common.checkpoints import GreedyCheckpoints
from sb3_aac.common.envs import ParameterizedTargetEnv


class StopAt(GreedyCheckpoints):
    """Scores the model by its step count; stops training once a score reaches ``limit``."""

    def __init__(self, every: int, limit: float):
        super().__init__(every, lambda model: float(model.num_timesteps))
        self.limit = limit

    def on_checkpoint(self, score: float) -> bool:
        return score < self.limit


def model(n_envs: int) -> SarsaAAC:
    return SarsaAAC("RbfPolicy", make_vec_env(ParameterizedTargetEnv, n_envs=n_envs, seed=0), seed=0)


def test_a_checkpoint_at_the_first_step_past_each_multiple() -> None:
    checkpoints = GreedyCheckpoints(7, lambda m: float(m.num_timesteps))
    model(3).learn(30, callback=checkpoints)
    # num_timesteps moves by 3 per step: 9 is the first at or past 7, 15 past 14, 21 past 21, 30 past 28.
    assert checkpoints.curve == [(9, 9.0), (15, 15.0), (21, 21.0), (30, 30.0)]


def test_on_checkpoint_false_stops_training() -> None:
    stop = StopAt(10, limit=20)
    trained = model(2).learn(100, callback=stop)
    assert [steps for steps, _ in stop.curve] == [10, 20]
    assert trained.num_timesteps == 20


def test_every_must_be_a_positive_step_count() -> None:
    with pytest.raises(ValueError, match="every must be >= 1 env step, got 0"):
        GreedyCheckpoints(0, lambda m: 0.0)
