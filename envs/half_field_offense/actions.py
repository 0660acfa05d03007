"""HFO's low-level actions and how its agent turns them into server commands (rcsc's ``PlayerAgent``, restated).

Actions: 0 ``DASH(power, direction)``, 1 ``TURN(direction)``, 2 ``KICK(power, direction)`` and, with the task's
``tackle``, 3 ``TACKLE(direction)``; powers in [0, 100], directions in degrees in [-180, 180] relative to the body,
as HFO's Gymnasium ports declare them. One action is one server cycle.

The agent's transforms (:func:`command`), applied to the exact state (full state):

* any action while the player is frozen by a tackle is refused (nothing is sent, the action failed);
* DASH: power and direction clipped to the server's ranges, the direction rounded to ``dash_angle_step``; then the
  power is conserved: cut to the stamina left plus the extra stamina, and to the power whose acceleration brings the
  player exactly to its top speed where a full one would pass it (rcsc's ``conserve_dash_power``); rounded to 0.001;
* TURN: the wanted turn times ``1 + inertia_moment * speed`` (the moment that turns by it without noise), clipped to
  +-180 and rounded to 0.001;
* KICK: refused unless the ball is kickable as rcsc sees it (:data:`half_field_offense.features.KICKABLE_BUFFER`);
  the power clipped to [0, 100] and rounded to 0.001;
* TACKLE: the direction as given.

Whether the action was possible is the last feature of the next observation.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces
from numba import njit

from half_field_offense.features import KICKABLE_BUFFER
from robocup_dribble import physics

ACTION_NAMES = ("DASH", "TURN", "KICK", "TACKLE")
DASH, TURN, KICK, TACKLE = range(len(ACTION_NAMES))
ACTION_PARAMS = (
    ("dash_power", "dash_direction"),
    ("turn_direction",),
    ("kick_power", "kick_direction"),
    ("tackle_direction",),
)
"""Each action's parameters, in the order of the action space."""
PARAM_NAMES = tuple(name for names in ACTION_PARAMS for name in names)
PARAM_SIZES = tuple(len(names) for names in ACTION_PARAMS)
PARAM_STARTS = np.cumsum((0, *PARAM_SIZES[:-1])).astype(np.int64)
"""Column of each action's first parameter in the flat ``(6,)`` parameter vector."""
PARAM_SIZES_ARRAY = np.array(PARAM_SIZES, dtype=np.int64)
PARAM_SLICES = tuple(slice(int(start), int(start) + size) for start, size in zip(PARAM_STARTS, PARAM_SIZES, strict=True))
POWER_RANGE, DIRECTION_RANGE = (0.0, 100.0), (-180.0, 180.0)
PARAM_LOW = np.array(
    [POWER_RANGE[0], DIRECTION_RANGE[0], DIRECTION_RANGE[0], POWER_RANGE[0], DIRECTION_RANGE[0], DIRECTION_RANGE[0]]
)
PARAM_HIGH = np.array(
    [POWER_RANGE[1], DIRECTION_RANGE[1], DIRECTION_RANGE[1], POWER_RANGE[1], DIRECTION_RANGE[1], DIRECTION_RANGE[1]]
)
COMMAND_DIGITS = 1000.0  # rcsc rounds a command's power and moment to 0.001


def n_actions(tackle: bool) -> int:
    """The number of actions: three, or four with Tackle."""
    return len(ACTION_NAMES) if tackle else len(ACTION_NAMES) - 1


def n_params(tackle: bool) -> int:
    """The length of the flat parameter vector: five, or six with Tackle."""
    return sum(PARAM_SIZES[: n_actions(tackle)])


def action_space(tackle: bool) -> spaces.Tuple[Any]:
    """``Tuple(Discrete(K), Tuple(Box(2), Box(1), Box(2)[, Box(1)]))`` with HFO's parameter ranges (float32)."""
    boxes = [
        spaces.Box(PARAM_LOW[start : start + size].astype(np.float32), PARAM_HIGH[start : start + size].astype(np.float32))
        for start, size in zip(PARAM_STARTS[: n_actions(tackle)], PARAM_SIZES[: n_actions(tackle)], strict=True)
    ]
    return spaces.Tuple((spaces.Discrete(n_actions(tackle)), spaces.Tuple(boxes)))


@njit(cache=True, error_model="numpy", inline="always")
def _clip(value: float, low: float, high: float) -> float:
    return min(max(value, low), high)


@njit(cache=True, error_model="numpy", inline="always")
def dash_direction_rate(direction: float, k) -> float:
    """The server's effectiveness of a dash in ``direction`` (deg, already clipped and rounded), as rcsc computes it."""
    d = abs(direction)
    side, back = k[physics.K_SIDE_DASH_RATE], k[physics.K_BACK_DASH_RATE]
    rate = back - (back - side) * (1.0 - (d - 90.0) / 90.0) if d > 90.0 else side + (1.0 - side) * (1.0 - d / 90.0)
    return min(max(1e-5, rate), 1.0)


@njit(cache=True, error_model="numpy", inline="always")
def _dash(state, i, types, ti, power: float, direction: float, k) -> tuple[float, float]:
    """rcsc's ``setDash``: the ``(power, direction)`` it sends for a wanted dash (module docstring)."""
    low, high = k[physics.K_MIN_DASH_POWER], k[physics.K_MAX_DASH_POWER]
    power = _clip(power, low, high)
    direction = _clip(direction, k[physics.K_MIN_DASH_ANGLE], k[physics.K_MAX_DASH_ANGLE])
    step = k[physics.K_DASH_ANGLE_STEP]
    if step >= 1e-10:
        direction = step * np.rint(direction / step)
    backwards = power < 0.0
    required = -2.0 * power if backwards else power
    available = state[i, physics.S_STAMINA] + types[ti, physics.T_EXTRA_STAMINA]
    if available < required:
        power = -0.5 * available if backwards else available
    rate = dash_direction_rate(direction, k)
    dash_rate = state[i, physics.S_EFFORT] * types[ti, physics.T_DASH_POWER_RATE]
    accel = abs(power * rate * dash_rate)
    angle = state[i, physics.P_BODY] + math.radians(direction + (180.0 if backwards else 0.0))
    cos_a, sin_a = math.cos(angle), math.sin(angle)
    vx, vy = state[i, physics.P_VX], state[i, physics.P_VY]
    speed_max = types[ti, physics.T_SPEED_MAX]
    mx, my = vx + accel * cos_a, vy + accel * sin_a
    if mx * mx + my * my > speed_max * speed_max + 0.0001:  # the accel that reaches the top speed exactly
        along, across = vx * cos_a + vy * sin_a, -vx * sin_a + vy * cos_a
        accel = math.sqrt(max(speed_max * speed_max - across * across, 0.0)) - along
    power = accel / dash_rate / rate
    power = _clip(-power if backwards else power, low, high)
    return np.rint(power * COMMAND_DIGITS) / COMMAND_DIGITS, direction


@njit(cache=True, error_model="numpy")
def command(state, i, types, ti, kind: int, a: float, b: float, k) -> tuple[int, float, float, bool]:
    """The server command ``(physics.CMD_* kind, power or moment, direction)`` lane ``i``'s agent sends for action
    ``kind`` with parameters ``a`` (and ``b``), and whether the action was possible (module docstring)."""
    if state[i, physics.S_FROZEN] > 0.0:
        return physics.CMD_NONE, 0.0, 0.0, False
    if kind == DASH:
        power, direction = _dash(state, i, types, ti, a, b, k)
        return physics.CMD_DASH, power, direction, True
    if kind == TURN:
        speed = physics.norm(state[i, physics.P_VX], state[i, physics.P_VY])
        moment = _clip(a * (1.0 + speed * types[ti, physics.T_INERTIA]), k[physics.K_MIN_MOMENT], k[physics.K_MAX_MOMENT])
        return physics.CMD_TURN, np.rint(moment * COMMAND_DIGITS) / COMMAND_DIGITS, 0.0, True
    if kind == KICK:
        reach = physics.kickable_radius(
            types[ti, physics.T_SIZE], k[physics.K_BALL_SIZE], types[ti, physics.T_KICKABLE_MARGIN]
        )
        dx, dy = state[i, physics.B_X] - state[i, physics.P_X], state[i, physics.B_Y] - state[i, physics.P_Y]
        if math.sqrt(dx * dx + dy * dy) > reach - KICKABLE_BUFFER:
            return physics.CMD_NONE, 0.0, 0.0, False
        power = _clip(a, 0.0, k[physics.K_MAX_POWER])
        return physics.CMD_KICK, np.rint(power * COMMAND_DIGITS) / COMMAND_DIGITS, b, True
    return physics.CMD_TACKLE, 0.0, a, True
