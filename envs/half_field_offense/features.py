"""HFO's 59 low-level features of a 1v0 agent (HFO's ``LowLevelFeatureExtractor`` with ``--fullstate``, restated).

Every feature lies in [-1, 1]. An angle is two features, its sine and cosine; a landmark is three, the sine and
cosine of its bearing relative to the body and its proximity ``1 - 2 min(d / D, 1)`` with ``D`` HFO's largest
distance (:data:`half_field_offense.task.DISTANCE_NORMALISERS`); a flag is +1 (true) or -1. With full state every
validity flag is +1. The angle of a zero vector is 0, as rcsc's ``Vector2D::th`` gives it. HFO computes in single
precision; these are computed in double and stored as float32.

Kickable (feature 12) is rcsc's: the ball within the kickable area less 0.055 m (its margin for an exactly seen
ball), 1.03 m for the default player; the referee and the server's kick use the whole area (1.085 m).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from half_field_offense import task
from robocup_dribble import physics
from robocup_dribble.params import PITCH_HALF_LENGTH, PITCH_HALF_WIDTH

PENALTY_AREA_LENGTH = 16.5  # m (the server's hard-coded field geometry)
PENALTY_AREA_WIDTH = 40.32  # m
GOAL_HALF_WIDTH = 7.01  # m: the server's goal_width 14.02 halved (the features use the default, as HFO's do)
KICKABLE_BUFFER = 0.055  # m rcsc leaves inside the kickable area for a ball it sees exactly
SELF_SPEED_MAX = 0.46  # m/cycle: HFO's observedSelfSpeedMax
STAMINA_MAX = 8000.0  # HFO's observedStaminaMax
BALL_SPEED_MAX = 5.0  # m/cycle: HFO's observedBallSpeedMax
BOUNDARY_X_SCALE = 1.1 * PITCH_HALF_LENGTH  # m: out-of-bounds distances along x are divided by this (57.75)
BOUNDARY_Y_SCALE = 1.05 * 2.0 * PITCH_HALF_WIDTH  # m: and along y by this (71.4)

LANDMARK_NAMES = (
    "goal_centre", "goal_post_top", "goal_post_bottom", "penalty_box_centre", "penalty_box_top",
    "penalty_box_bottom", "centre_field", "corner_top_left", "corner_top_right", "corner_bottom_right",
    "corner_bottom_left",
)  # fmt: skip
LANDMARKS = np.array(
    [
        (PITCH_HALF_LENGTH, 0.0),
        (PITCH_HALF_LENGTH, -GOAL_HALF_WIDTH),
        (PITCH_HALF_LENGTH, GOAL_HALF_WIDTH),
        (PITCH_HALF_LENGTH - PENALTY_AREA_LENGTH, 0.0),
        (PITCH_HALF_LENGTH - PENALTY_AREA_LENGTH, -0.5 * PENALTY_AREA_WIDTH),
        (PITCH_HALF_LENGTH - PENALTY_AREA_LENGTH, 0.5 * PENALTY_AREA_WIDTH),
        (0.0, 0.0),  # the pitch's centre, not the HFO area's (LARG/HFO#37)
        (0.0, -PITCH_HALF_WIDTH),
        (PITCH_HALF_LENGTH, -PITCH_HALF_WIDTH),
        (PITCH_HALF_LENGTH, PITCH_HALF_WIDTH),
        (0.0, PITCH_HALF_WIDTH),
    ]
)
"""The fixed landmarks' positions (m), in feature order; y grows downwards on HFO's screen, so "top" is -y."""


def _landmark(name: str) -> tuple[str, str, str]:
    return (f"{name}_sin", f"{name}_cos", f"{name}_proximity")


FEATURE_NAMES = (
    "self_position_valid", "self_velocity_valid", "self_velocity_angle_sin", "self_velocity_angle_cos", "self_speed",
    "body_sin", "body_cos", "stamina", "frozen", "colliding_ball", "colliding_player", "colliding_post", "kickable",
    *(feature for name in LANDMARK_NAMES for feature in _landmark(name)),
    "proximity_left", "proximity_right", "proximity_top", "proximity_bottom", "ball_position_valid",
    *_landmark("ball"),
    "ball_velocity_valid", "ball_speed", "ball_velocity_angle_sin", "ball_velocity_angle_cos", "last_action_success",
)  # fmt: skip
"""The 59 features in HFO's order."""
N_FEATURES = len(FEATURE_NAMES)
(
    F_KICKABLE, F_GOAL_SIN, F_GOAL_COS, F_GOAL_PROXIMITY, F_BALL_SIN, F_BALL_COS, F_BALL_PROXIMITY, F_LAST_ACTION,
) = (FEATURE_NAMES.index(name) for name in (
    "kickable", "goal_centre_sin", "goal_centre_cos", "goal_centre_proximity", "ball_sin", "ball_cos", "ball_proximity",
    "last_action_success",
))  # fmt: skip
F_LANDMARKS = FEATURE_NAMES.index("goal_centre_sin")
F_BOUNDARIES = FEATURE_NAMES.index("proximity_left")


@njit(cache=True, error_model="numpy", inline="always")
def _flag(value: bool) -> float:
    return 1.0 if value else -1.0


@njit(cache=True, error_model="numpy", inline="always")
def _scaled(value: float, high: float) -> float:
    """HFO's normalisation of ``value`` in [0, high] to [-1, 1] (clipped)."""
    return 2.0 * min(max(value / high, 0.0), 1.0) - 1.0


@njit(cache=True, error_model="numpy", inline="always")
def _bearing(obs, oi: int, f: int, dx: float, dy: float, cos_body: float, sin_body: float, max_distance: float) -> None:
    """Landmark features at ``obs[oi, f:f + 3]`` of the vector ``(dx, dy)`` from the player to it."""
    distance = math.sqrt(dx * dx + dy * dy)
    if distance > 0.0:
        obs[oi, f] = (dy * cos_body - dx * sin_body) / distance
        obs[oi, f + 1] = (dx * cos_body + dy * sin_body) / distance
    else:  # the landmark's angle is 0
        obs[oi, f], obs[oi, f + 1] = -sin_body, cos_body
    obs[oi, f + 2] = -_scaled(distance, max_distance)


@njit(cache=True, error_model="numpy")
def observe(state, i, types, ti, collided: bool, posted: bool, last_action_ok: bool, c, k, obs, oi: int) -> None:
    """Write lane ``i``'s features to row ``oi`` of ``obs`` given this cycle's collision flags and whether the last
    action was possible (the lane's type in row ``ti`` of ``types``)."""
    px, py, vx, vy = state[i, physics.P_X], state[i, physics.P_Y], state[i, physics.P_VX], state[i, physics.P_VY]
    bx, by, bvx, bvy = state[i, physics.B_X], state[i, physics.B_Y], state[i, physics.B_VX], state[i, physics.B_VY]
    cos_body, sin_body = math.cos(state[i, physics.P_BODY]), math.sin(state[i, physics.P_BODY])
    max_distance = c[task.R_MAX_DISTANCE]
    obs[oi, 0] = obs[oi, 1] = 1.0
    speed = math.sqrt(vx * vx + vy * vy)
    if speed > 0.0:  # the angle body - velocity direction
        obs[oi, 2], obs[oi, 3] = (sin_body * vx - cos_body * vy) / speed, (cos_body * vx + sin_body * vy) / speed
    else:
        obs[oi, 2], obs[oi, 3] = sin_body, cos_body
    obs[oi, 4] = _scaled(speed, SELF_SPEED_MAX)
    obs[oi, 5], obs[oi, 6] = sin_body, cos_body
    obs[oi, 7] = _scaled(state[i, physics.S_STAMINA], STAMINA_MAX)
    obs[oi, 8] = _flag(state[i, physics.S_FROZEN] > 0.0)
    obs[oi, 9], obs[oi, 10], obs[oi, 11] = _flag(collided), -1.0, _flag(posted)
    reach = physics.kickable_radius(types[ti, physics.T_SIZE], k[physics.K_BALL_SIZE], types[ti, physics.T_KICKABLE_MARGIN])
    rx, ry = bx - px, by - py
    obs[oi, F_KICKABLE] = _flag(math.sqrt(rx * rx + ry * ry) <= reach - KICKABLE_BUFFER)
    for m in range(LANDMARKS.shape[0]):
        _bearing(obs, oi, F_LANDMARKS + 3 * m, LANDMARKS[m, 0] - px, LANDMARKS[m, 1] - py, cos_body, sin_body, max_distance)
    f = F_BOUNDARIES
    obs[oi, f] = -_scaled(px, BOUNDARY_X_SCALE)
    obs[oi, f + 1] = -_scaled(PITCH_HALF_LENGTH - px, BOUNDARY_X_SCALE)
    obs[oi, f + 2] = -_scaled(PITCH_HALF_WIDTH + py, BOUNDARY_Y_SCALE)
    obs[oi, f + 3] = -_scaled(PITCH_HALF_WIDTH - py, BOUNDARY_Y_SCALE)
    obs[oi, f + 4] = 1.0
    _bearing(obs, oi, F_BALL_SIN, rx, ry, cos_body, sin_body, max_distance)
    obs[oi, F_BALL_PROXIMITY + 1] = 1.0
    ball_speed = math.sqrt(bvx * bvx + bvy * bvy)
    obs[oi, F_BALL_PROXIMITY + 2] = _scaled(ball_speed, BALL_SPEED_MAX)
    if ball_speed > 0.0:
        obs[oi, F_BALL_PROXIMITY + 3], obs[oi, F_BALL_PROXIMITY + 4] = bvy / ball_speed, bvx / ball_speed
    else:
        obs[oi, F_BALL_PROXIMITY + 3], obs[oi, F_BALL_PROXIMITY + 4] = 0.0, 1.0
    obs[oi, F_LAST_ACTION] = _flag(last_action_ok)
