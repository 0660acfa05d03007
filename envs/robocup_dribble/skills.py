"""The paper's four action types, each turned into one server command per cycle.

Uc-Cetina (2013) names the action types (Dash Max, Kick Velocity, Kick Position, Kick Align) and says they take
7 parameters in all, at most 2 each; the parameter meanings were lost with the paper's figures. Ours (chosen by us,
documented here and in docs/robocup_dribble.md):

====================  =========================  ===================================================================
action type           parameters (units, range)  server command this cycle
====================  =========================  ===================================================================
0 ``DASH_MAX``        direction (deg, ±180)      ``(dash 100 direction)``: full power toward ``direction``, relative
                                                 to the body. v11 had no dash direction: there the command is
                                                 ``(dash 100·cos(direction))``, the part of a full-power dash along
                                                 the body axis (backwards for ``|direction| > 90``, at double cost).
1 ``KICK_VELOCITY``   speed (m/cycle, 0..ball     the kick that gives the ball the velocity ``polar(speed, body +
                      speed max), direction       direction)`` for the coming cycle (before decay).
                      (deg, ±180)
2 ``KICK_POSITION``   x, y (m, ±2, body frame)    the kick that puts the ball at ``(x, y)`` (body frame) from the
                                                 player's own position one cycle later (the player coasts while it
                                                 kicks).
3 ``KICK_ALIGN``      speed (m/cycle, 0..ball     the kick that makes the ball run along the player's running
                      speed max), offset (m, ±1)  direction (its body direction, along which DASH_MAX(0) runs) at
                                                 ``speed``, with lateral ``offset`` (positive to the player's right,
                                                 i.e. +y when facing +x) from the player one cycle later. (Its
                                                 velocity would be a worse axis: it starts in a random direction.)
====================  =========================  ===================================================================

Every kick aims at a target ball velocity; when the ball cannot reach it with maximum power (the kick's effective
power shrinks with the ball's distance and angle, docs/physics.md §3), the kick goes at maximum power in the direction of the
needed change, which is the reachable velocity closest to the target. Parameters outside their ranges are clipped
to them, as the server clips the power and direction of a command. The action space of one lane is
``Tuple(Discrete(4), Tuple(Box(1), Box(2), Box(2), Box(2)))``; a batch of actions is an ``(N,)`` int array of types
plus an ``(N, 7)`` array of all parameters (``PARAM_*`` columns).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces
from numba import njit

from robocup_dribble import physics
from robocup_dribble.params import ServerProfile

ACTION_NAMES = ("DASH_MAX", "KICK_VELOCITY", "KICK_POSITION", "KICK_ALIGN")
DASH_MAX, KICK_VELOCITY, KICK_POSITION, KICK_ALIGN = (ACTION_NAMES.index(name) for name in ACTION_NAMES)
N_ACTION_TYPES = len(ACTION_NAMES)

ACTION_PARAMS = (
    ("dash_direction",),
    ("kick_speed", "kick_direction"),
    ("position_x", "position_y"),
    ("align_speed", "align_offset"),
)
"""The parameter names of each action type, in type order; a batch's ``(N, 7)`` parameters concatenate them."""
PARAM_NAMES = tuple(name for names in ACTION_PARAMS for name in names)
PARAM_SIZES = tuple(len(names) for names in ACTION_PARAMS)
PARAM_SLICES = tuple(slice(PARAM_NAMES.index(names[0]), PARAM_NAMES.index(names[-1]) + 1) for names in ACTION_PARAMS)
PARAM_DASH_DIRECTION, PARAM_KICK_SPEED, PARAM_KICK_DIRECTION, PARAM_POSITION_X, PARAM_POSITION_Y, PARAM_ALIGN_SPEED, \
    PARAM_ALIGN_OFFSET = (PARAM_NAMES.index(name) for name in PARAM_NAMES)  # fmt: skip
N_PARAMS = len(PARAM_NAMES)
PARAM_STARTS = np.array([s.start for s in PARAM_SLICES], dtype=np.int64)
"""The column of each action type's first parameter (compiled code reads it)."""
PARAM_WIDTHS = np.array(PARAM_SIZES, dtype=np.int64)

KICK_POSITION_RANGE = 2.0  # m, |x| and |y| of KICK_POSITION
ALIGN_OFFSET_RANGE = 1.0  # m, |offset| of KICK_ALIGN


def parameter_bounds(profile: ServerProfile) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of the 7 parameters (``PARAM_*`` order) under a server profile."""
    speed = profile.server.ball_speed_max
    low = np.array([-180.0, 0.0, -180.0, -KICK_POSITION_RANGE, -KICK_POSITION_RANGE, 0.0, -ALIGN_OFFSET_RANGE])
    high = np.array([180.0, speed, 180.0, KICK_POSITION_RANGE, KICK_POSITION_RANGE, speed, ALIGN_OFFSET_RANGE])
    return low, high


def action_space(profile: ServerProfile) -> spaces.Tuple[Any]:
    """``Tuple(Discrete(4), Tuple(Box(1), Box(2), Box(2), Box(2)))`` with the profile's physical bounds (float32)."""
    low, high = parameter_bounds(profile)
    boxes = tuple(spaces.Box(low[s].astype(np.float32), high[s].astype(np.float32), dtype=np.float32) for s in PARAM_SLICES)
    return spaces.Tuple((spaces.Discrete(N_ACTION_TYPES), spaces.Tuple(boxes)))


def as_env_actions(action_types: np.ndarray, params: np.ndarray, param_slices: tuple[slice, ...] = PARAM_SLICES) -> np.ndarray:
    """A batch ``(N,)`` types and ``(N, P)`` parameters as an ``(N,)`` object array of per-lane Tuple actions, each
    action type's parameters the columns of its slice (by default the dribbling skills': P = 7)."""
    actions = np.empty(len(action_types), dtype=object)
    params32 = np.asarray(params, dtype=np.float32)
    for i, kind in enumerate(np.asarray(action_types).tolist()):
        actions[i] = (kind, tuple(params32[i, s] for s in param_slices))
    return actions


@njit(cache=True, error_model="numpy", inline="always")
def _kick_toward(state, i, types, ti, target_vx: float, target_vy: float, k: np.ndarray):
    """The kick command whose result is closest to giving the ball the velocity (target_vx, target_vy)."""
    ax, ay = target_vx - state[i, physics.B_VX], target_vy - state[i, physics.B_VY]
    rx, ry = state[i, physics.B_X] - state[i, physics.P_X], state[i, physics.B_Y] - state[i, physics.P_Y]
    body = state[i, physics.P_BODY]
    dir_diff = abs(physics.normalize_angle(math.atan2(ry, rx) - body))
    dist_ball = physics.norm(rx, ry) - types[ti, physics.T_SIZE] - k[physics.K_BALL_SIZE]
    rate = physics.kick_rate(types[ti, physics.T_KICK_POWER_RATE], dir_diff, dist_ball, types[ti, physics.T_KICKABLE_MARGIN])
    max_power = k[physics.K_MAX_POWER]
    power = min(physics.norm(ax, ay) / rate, max_power) if rate > 0.0 else max_power
    return physics.CMD_KICK, power, math.degrees(physics.normalize_angle(math.atan2(ay, ax) - body))


@njit(cache=True, error_model="numpy", inline="always")
def command(state, i, types, ti, kind: int, a: float, b: float, k: np.ndarray):
    """The server command ``(CMD_* kind, power, direction)`` of action type ``kind`` with parameters ``a`` (and ``b``
    for the two-parameter types), already within :func:`parameter_bounds`, for lane ``i`` (type row ``ti``)."""
    body = state[i, physics.P_BODY]
    if kind == DASH_MAX:  # a: direction
        if k[physics.K_DASH_DIRECTION] > 0.5:
            return physics.CMD_DASH, k[physics.K_MAX_DASH_POWER], a
        # v11: no dash direction; dash with the body-axis share of full power
        return physics.CMD_DASH, k[physics.K_MAX_DASH_POWER] * math.cos(math.radians(a)), 0.0
    if kind == KICK_VELOCITY:  # a: speed, b: direction
        heading = body + math.radians(b)
        return _kick_toward(state, i, types, ti, a * math.cos(heading), a * math.sin(heading), k)
    px, py = state[i, physics.P_X] + state[i, physics.P_VX], state[i, physics.P_Y] + state[i, physics.P_VY]  # coasting
    if kind == KICK_POSITION:  # ball at p_next + R(body)(a, b)
        gx = px + a * math.cos(body) - b * math.sin(body)
        gy = py + a * math.sin(body) + b * math.cos(body)
        return _kick_toward(state, i, types, ti, gx - state[i, physics.B_X], gy - state[i, physics.B_Y], k)
    # KICK_ALIGN: a: speed along the body (running) direction, b: lateral offset from the player's next position
    tx, ty = math.cos(body), math.sin(body)
    nx, ny = -ty, tx  # the player's right-hand side (+y when facing +x)
    lateral = (state[i, physics.B_X] - state[i, physics.P_X] - state[i, physics.P_VX]) * nx + (
        state[i, physics.B_Y] - state[i, physics.P_Y] - state[i, physics.P_VY]
    ) * ny
    correction = b - lateral
    return _kick_toward(state, i, types, ti, a * tx + correction * nx, a * ty + correction * ny, k)


@njit(cache=True, error_model="numpy")
def command_lane(s: np.ndarray, t: np.ndarray, kind: int, p: np.ndarray, k: np.ndarray, out: np.ndarray) -> None:
    """:func:`command` for one lane given as vectors (state row, type row, ``(7,)`` parameters); writes ``out``
    (``COMMAND_SIZE``)."""
    first = PARAM_STARTS[kind]
    b = p[first + 1] if PARAM_WIDTHS[kind] > 1 else 0.0
    c_kind, power, direction = command(
        s.reshape((1, physics.STATE_SIZE)), 0, t.reshape((1, physics.TYPE_SIZE)), 0, kind, p[first], b, k
    )
    out[physics.C_KIND], out[physics.C_POWER], out[physics.C_DIRECTION] = c_kind, power, direction
