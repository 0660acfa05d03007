"""ActionStats (the action and critic statistics every algorithm logs) against hand-computed numbers."""

import math

import numpy as np
import pytest
from gymnasium import spaces

from sb3_aac.common.action_stats import ActionStats
from sb3_aac.common.spaces import ParameterizedActionSpec

# Type 0 owns one parameter in [0, 10], type 1 two in [-2, 2], type 2 one in [-1, 1].
SPACE = spaces.Tuple(
    (
        spaces.Discrete(3),
        spaces.Tuple(
            (spaces.Box(0.0, 10.0, (1,)), spaces.Box(-2.0, 2.0, (2,)), spaces.Box(-1.0, 1.0, (1,))),
        ),
    )
)


class Recorder:
    def __init__(self) -> None:
        self.values: dict[str, float] = {}

    def record(self, key: str, value: float) -> None:
        self.values[key] = value


def test_shares_parameter_statistics_in_env_units_and_values():
    stats = ActionStats(ParameterizedActionSpec.from_space(SPACE), value_name="value")
    # Scaled parameters, one column per scalar (type 0 | type 1, type 1 | type 2); only the chosen type's count.
    stats.add(np.array([0, 1]), np.array([[0.0, 0.5, -1.0, 0.9], [0.7, 0.0, 1.0, 0.9]]), np.array([1.0, 2.0]))
    stats.add(np.array([1]), np.array([[-0.3, 1.0, 0.0, 0.9]]))
    stats.add_values(np.array([3.0]))
    logger = Recorder()
    stats.record(logger)
    expected = {
        "rollout/type_freq_0": 1 / 3,
        "rollout/type_freq_1": 2 / 3,
        "rollout/type_freq_2": 0.0,
        "rollout/param_mean_0_0": 5.0,  # scaled 0 is the middle of [0, 10]
        "rollout/param_std_0_0": 0.0,
        "rollout/param_mean_1_0": 1.0,  # scaled (0 + 1) / 2 on [-2, 2]
        "rollout/param_std_1_0": 1.0,  # scaled 0.5, times the half-range 2
        "rollout/param_mean_1_1": 1.0,  # scaled (1 + 0) / 2
        "rollout/param_std_1_1": 1.0,
        "train/value_mean": 2.0,
        "train/value_std": math.sqrt(2 / 3),
        "train/value_min": 1.0,
        "train/value_max": 3.0,
    }
    assert logger.values == pytest.approx(expected)  # no parameter keys for type 2, which no step chose
    logger = Recorder()
    stats.record(logger)  # record() starts afresh
    assert logger.values == {}


def test_the_value_name_is_one_of_the_two_critic_outputs():
    spec = ParameterizedActionSpec.from_space(SPACE)
    logger = Recorder()
    stats = ActionStats(spec, value_name="q")
    stats.add_values(np.array([-1.0, 1.0]))
    stats.record(logger)
    assert logger.values == {"train/q_mean": 0.0, "train/q_std": 1.0, "train/q_min": -1.0, "train/q_max": 1.0}
    with pytest.raises(ValueError, match=r"value_name must be one of \('value', 'q'\), got 'v'"):
        ActionStats(spec, value_name="v")
