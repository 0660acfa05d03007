"""The paper's four action types, each turned into one server command per cycle.

Uc-Cetina (2013) names the action types (Dash Max, Kick Velocity, Kick Position, Kick Align) and says they take
7 parameters in all, at most 2 each; the parameter meanings were lost with the paper's figures. Ours (chosen by us,
documented here and in the README):

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
power shrinks with the ball's distance and angle, spec §3), the kick goes at maximum power in the direction of the
needed change, which is the reachable velocity closest to the target. Parameters outside their ranges are clipped
to them, as the server clips the power and direction of a command. The action space of one lane is
``Tuple(Discrete(4), Tuple(Box(1), Box(2), Box(2), Box(2)))``; a batch of actions is an ``(N,)`` int array of types
plus an ``(N, 7)`` array of all parameters (``PARAM_*`` columns).
"""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces
from numba import njit

from robocup_dribble import physics
from robocup_dribble.params import ServerProfile

DASH_MAX, KICK_VELOCITY, KICK_POSITION, KICK_ALIGN = 0, 1, 2, 3
ACTION_NAMES = ("DASH_MAX", "KICK_VELOCITY", "KICK_POSITION", "KICK_ALIGN")
N_ACTION_TYPES = 4

PARAM_DASH_DIRECTION = 0
PARAM_KICK_SPEED, PARAM_KICK_DIRECTION = 1, 2
PARAM_POSITION_X, PARAM_POSITION_Y = 3, 4
PARAM_ALIGN_SPEED, PARAM_ALIGN_OFFSET = 5, 6
N_PARAMS = 7
PARAM_NAMES = ("dash_direction", "kick_speed", "kick_direction", "position_x", "position_y", "align_speed", "align_offset")
PARAM_SLICES = (slice(0, 1), slice(1, 3), slice(3, 5), slice(5, 7))  # the columns of each action type

KICK_POSITION_RANGE = 2.0  # m, |x| and |y| of KICK_POSITION
ALIGN_OFFSET_RANGE = 1.0  # m, |offset| of KICK_ALIGN


def parameter_bounds(profile: ServerProfile) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of the 7 parameters (``PARAM_*`` order) under a server profile."""
    speed = profile.server.ball_speed_max
    low = np.array([-180.0, 0.0, -180.0, -KICK_POSITION_RANGE, -KICK_POSITION_RANGE, 0.0, -ALIGN_OFFSET_RANGE])
    high = np.array([180.0, speed, 180.0, KICK_POSITION_RANGE, KICK_POSITION_RANGE, speed, ALIGN_OFFSET_RANGE])
    return low, high


def action_space(profile: ServerProfile) -> spaces.Tuple:
    """``Tuple(Discrete(4), Tuple(Box(1), Box(2), Box(2), Box(2)))`` with the profile's physical bounds (float32)."""
    low, high = parameter_bounds(profile)
    boxes = tuple(spaces.Box(low[s].astype(np.float32), high[s].astype(np.float32), dtype=np.float32) for s in PARAM_SLICES)
    return spaces.Tuple((spaces.Discrete(N_ACTION_TYPES), spaces.Tuple(boxes)))


def as_env_actions(action_types: np.ndarray, params: np.ndarray) -> np.ndarray:
    """A batch ``(N,)`` types and ``(N, 7)`` parameters as an ``(N,)`` object array of per-lane Tuple actions."""
    actions = np.empty(len(action_types), dtype=object)
    params32 = np.asarray(params, dtype=np.float32)
    for i, kind in enumerate(np.asarray(action_types).tolist()):
        actions[i] = (kind, tuple(params32[i, s] for s in PARAM_SLICES))
    return actions


def commands_for(
    state: np.ndarray, types: np.ndarray, action_types: np.ndarray, params: np.ndarray, constants: np.ndarray
) -> np.ndarray:
    """Turn a batch of (action type, parameters) into one server command per lane.

    :param state: ``(N, STATE_SIZE)`` physics state.
    :param types: ``(N, TYPE_SIZE)`` player types.
    :param action_types: ``(N,)`` ints in 0..3 (already validated).
    :param params: ``(N, 7)`` float64 parameters, already clipped to :func:`parameter_bounds`.
    :param constants: :func:`robocup_dribble.physics.profile_constants` of the profile.
    :return: ``(N, COMMAND_SIZE)`` commands for :func:`robocup_dribble.physics.step`.
    """
    commands = np.empty((state.shape[0], physics.COMMAND_SIZE), dtype=np.float64)
    _commands(state, types, action_types, params, constants, commands)
    return commands


@njit(cache=True)
def _kick_toward(s: np.ndarray, t: np.ndarray, target_vx: float, target_vy: float, k: np.ndarray, command: np.ndarray):
    """The kick whose result is closest to giving the ball the velocity (target_vx, target_vy)."""
    ax, ay = target_vx - s[physics.B_VX], target_vy - s[physics.B_VY]
    rx, ry = s[physics.B_X] - s[physics.P_X], s[physics.B_Y] - s[physics.P_Y]
    body = s[physics.P_BODY]
    dir_diff = abs(physics.normalize_angle(math.atan2(ry, rx) - body))
    dist_ball = math.hypot(rx, ry) - t[physics.T_SIZE] - k[physics.K_BALL_SIZE]
    rate = t[physics.T_KICK_POWER_RATE] * (1.0 - 0.25 * dir_diff / math.pi - 0.25 * dist_ball / t[physics.T_KICKABLE_MARGIN])
    max_power = k[physics.K_MAX_POWER]
    power = min(math.hypot(ax, ay) / rate, max_power) if rate > 0.0 else max_power
    command[physics.C_KIND] = physics.CMD_KICK
    command[physics.C_POWER] = power
    command[physics.C_DIRECTION] = math.degrees(physics.normalize_angle(math.atan2(ay, ax) - body))


@njit(cache=True)
def _commands(state, types, action_types, params, k, commands) -> None:
    for i in range(state.shape[0]):
        command_lane(state[i], types[i], action_types[i], params[i], k, commands[i])


@njit(cache=True)
def command_lane(s: np.ndarray, t: np.ndarray, kind: int, p: np.ndarray, k: np.ndarray, command: np.ndarray) -> None:
    """The server command of one lane's action (rows of the arrays :func:`commands_for` takes)."""
    body = s[physics.P_BODY]
    if kind == DASH_MAX:
        command[physics.C_KIND] = physics.CMD_DASH
        if k[physics.K_DASH_DIRECTION] > 0.5:
            command[physics.C_POWER] = k[physics.K_MAX_DASH_POWER]
            command[physics.C_DIRECTION] = p[PARAM_DASH_DIRECTION]
        else:  # v11: no dash direction; dash with the body-axis share of full power
            command[physics.C_POWER] = k[physics.K_MAX_DASH_POWER] * math.cos(math.radians(p[PARAM_DASH_DIRECTION]))
            command[physics.C_DIRECTION] = 0.0
    elif kind == KICK_VELOCITY:
        heading = body + math.radians(p[PARAM_KICK_DIRECTION])
        speed = p[PARAM_KICK_SPEED]
        _kick_toward(s, t, speed * math.cos(heading), speed * math.sin(heading), k, command)
    elif kind == KICK_POSITION:  # ball at p_next + R(body)(x, y); the player coasts: p_next = p + v
        x, y = p[PARAM_POSITION_X], p[PARAM_POSITION_Y]
        gx = s[physics.P_X] + s[physics.P_VX] + x * math.cos(body) - y * math.sin(body)
        gy = s[physics.P_Y] + s[physics.P_VY] + x * math.sin(body) + y * math.cos(body)
        _kick_toward(s, t, gx - s[physics.B_X], gy - s[physics.B_Y], k, command)
    else:  # KICK_ALIGN: along the body (running) direction, with a lateral offset from the player's next position
        tx, ty = math.cos(body), math.sin(body)
        nx, ny = -ty, tx  # the player's right-hand side (+y when facing +x)
        lateral = (s[physics.B_X] - s[physics.P_X] - s[physics.P_VX]) * nx + (s[physics.B_Y] - s[physics.P_Y] - s[physics.P_VY]) * ny
        correction = p[PARAM_ALIGN_OFFSET] - lateral
        speed = p[PARAM_ALIGN_SPEED]
        _kick_toward(s, t, speed * tx + correction * nx, speed * ty + correction * ny, k, command)
