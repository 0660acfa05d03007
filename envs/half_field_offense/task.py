"""The settings of a Half Field Offense trial (:class:`HFOTask`): HFO's command-line options that shape 1v0 play,
the reward variant, and the two conventions on which published setups differ.

Defaults are those of the published 1v0 runs (dqn-hfo, gym-soccer, MP-DQN): 500 cycles a trial, a ball untouched
for 100 cycles ends it, the ball starts in the first fifth of the attacking half, the current HFO distance normaliser
and the shaped reward as gym-soccer codes it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

DISTANCE_NORMALISERS = {"current": math.sqrt(52.5**2 + 68.0**2), "pre2018": math.sqrt(52.5**2 + 34.0**2)}
"""HFO's largest landmark distance (m) by version: since its commit f574833 (2018-09-11) half the pitch length and the
full width (85.91 m); before it half the length and half the width (62.55 m), which Hausknecht & Stone (2016) ran."""
REWARDS = ("shaped", "sparse")
"""``"shaped"``: dqn-hfo's and gym-soccer's reward (:mod:`half_field_offense.reward`); ``"sparse"``: +1 for a goal."""


@dataclass(frozen=True)
class HFOTask:
    """Trial, start and reward settings of Half Field Offense 1v0.

    :param frames_per_trial: HFO's ``--frames-per-trial``: a trial that has run more cycles ends as ``OUT_OF_TIME``
        (truncated); the published 1v0 runs used 500 (HFO's own default is 1000).
    :param untouched_time: HFO's ``--untouched-time``: a ball outside every kickable area for more cycles ends the
        trial as ``OUT_OF_TIME`` (terminated).
    :param ball_x_min: HFO's ``--ball-x-min``: the ball starts at x in [ball_x_min, ball_x_max] times 52.5 m.
    :param ball_x_max: HFO's ``--ball-x-max``.
    :param ball_y_min: HFO's ``--ball-y-min``: the ball starts at y in [ball_y_min, ball_y_max] times 34 m.
    :param ball_y_max: HFO's ``--ball-y-max``.
    :param offense_on_ball: HFO's ``--offense-on-ball``: the agent starts 0.1 m behind the ball.
    :param distance_normaliser: ``"current"`` or ``"pre2018"`` HFO's landmark distance scale
        (:data:`DISTANCE_NORMALISERS`).
    :param reward: one of :data:`REWARDS`.
    :param zero_terminal_deltas: the shaped reward's differences are zero on a trial's last step (dqn-hfo) instead
        of paid (gym-soccer, which MP-DQN ran); the goal bonus is paid either way.
    :param tackle: the action set has Tackle as a fourth action (Hausknecht & Stone 2016, dqn-hfo); P-DQN, MP-DQN
        and H-PPO ran the three actions Dash, Turn and Kick.
    """

    frames_per_trial: int = 500
    untouched_time: int = 100
    ball_x_min: float = 0.0
    ball_x_max: float = 0.2
    ball_y_min: float = -0.8
    ball_y_max: float = 0.8
    offense_on_ball: bool = False
    distance_normaliser: str = "current"
    reward: str = "shaped"
    zero_terminal_deltas: bool = False
    tackle: bool = False

    def __post_init__(self) -> None:
        for name in ("frames_per_trial", "untouched_time"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
        for name in ("offense_on_ball", "zero_terminal_deltas", "tackle"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ValueError(f"{name} must be a bool, got {getattr(self, name)!r}")
        for low, high in (("ball_x_min", "ball_x_max"), ("ball_y_min", "ball_y_max")):
            lo, hi = getattr(self, low), getattr(self, high)
            if not all(isinstance(v, (int, float, np.integer, np.floating)) and math.isfinite(v) for v in (lo, hi)):
                raise ValueError(f"{low} and {high} must be finite numbers, got {lo!r} and {hi!r}")
            if not -1.0 <= lo <= hi <= 1.0:
                raise ValueError(f"{low} <= {high} must lie in [-1, 1] (fractions of the half pitch), got {lo!r}, {hi!r}")
        if self.distance_normaliser not in DISTANCE_NORMALISERS:
            raise ValueError(
                f"distance_normaliser must be one of {sorted(DISTANCE_NORMALISERS)}, got {self.distance_normaliser!r}"
            )
        if self.reward not in REWARDS:
            raise ValueError(f"reward must be one of {list(REWARDS)}, got {self.reward!r}")

    def constants(self) -> np.ndarray:
        """The settings as the vector the compiled loop reads (``R_*`` columns)."""
        values = {
            "frames_per_trial": self.frames_per_trial,
            "untouched_time": self.untouched_time,
            "ball_x_min": self.ball_x_min,
            "ball_x_max": self.ball_x_max,
            "ball_y_min": self.ball_y_min,
            "ball_y_max": self.ball_y_max,
            "offense_on_ball": self.offense_on_ball,
            "max_distance": DISTANCE_NORMALISERS[self.distance_normaliser],
            "sparse_reward": self.reward == "sparse",
            "zero_terminal_deltas": self.zero_terminal_deltas,
        }
        return np.array([float(values[name]) for name in CONSTANT_FIELDS], dtype=np.float64)


CONSTANT_FIELDS = (
    "frames_per_trial", "untouched_time", "ball_x_min", "ball_x_max", "ball_y_min", "ball_y_max", "offense_on_ball",
    "max_distance", "sparse_reward", "zero_terminal_deltas",
)  # fmt: skip
"""The layout of :meth:`HFOTask.constants`."""
(
    R_FRAMES_PER_TRIAL, R_UNTOUCHED_TIME, R_BALL_X_MIN, R_BALL_X_MAX, R_BALL_Y_MIN, R_BALL_Y_MAX, R_OFFENSE_ON_BALL,
    R_MAX_DISTANCE, R_SPARSE_REWARD, R_ZERO_TERMINAL_DELTAS,
) = (CONSTANT_FIELDS.index(name) for name in CONSTANT_FIELDS)  # fmt: skip
TASK_FIELDS = tuple(field.name for field in dataclasses.fields(HFOTask))
"""The task's keyword arguments."""
