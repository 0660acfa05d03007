"""HFO's referee for 1v0 (the ``HFORef`` of HFO's rcssserver 15.2.2 fork, restated): where a trial starts, and
after every cycle whether it goes on or how it ended.

A trial ends (:func:`judge`, checks in this order) with

* ``GOAL``: the ball crossed the goal line between the posts in this cycle: its previous position was not past the
  line (|x| <= 52.5 + ball size), not already wide of the goal behind the line, and the line from it to the new
  position crosses x = 52.5 + ball size within the goal width's half plus the post radius of the centre;
* ``OUT_OF_BOUNDS``: the ball's *previous* position (at the end of the last cycle) lay outside the HFO area
  x in [0, 52.5], |y| <= 34, so the referee calls it one cycle after the ball left (a ball wide of the goal too);
* ``OUT_OF_TIME``: the ball was in nobody's kickable area for more than ``untouched_time`` cycles, or the trial ran
  more than ``frames_per_trial`` cycles;

else the trial goes on: the untouched count rises by one, and restarts from zero (the agent holds the ball) when
the ball lies inside the agent's kickable area (the server's, player size + margin + ball size).

A trial starts (:func:`place`, five uniforms): the ball at x ~ U(ball_x_min, ball_x_max) * 52.5, y ~ U(ball_y_min,
ball_y_max) * 34; the agent at the ball plus 10.5 m times (U(0, 1) + o) for one of HFO's ten offsets o (picked
uniformly), clipped to x in [-0.1, 52.5] and |y| <= 27.2, or 0.1 m behind the ball with ``offense_on_ball``; both at
rest, the player recovered (full stamina, effort and recovery) and keeping its body direction, as the trainer's
placement does.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from half_field_offense import task
from robocup_dribble import physics
from robocup_dribble.params import GOAL_POST_RADIUS, PITCH_HALF_LENGTH, PITCH_HALF_WIDTH

STATUS_NAMES = ("IN_GAME", "GOAL", "OUT_OF_BOUNDS", "OUT_OF_TIME")
"""The trial status HFO reports, by code."""
IN_GAME, GOAL, OUT_OF_BOUNDS, OUT_OF_TIME = range(len(STATUS_NAMES))

AGENT_OFFSETS = np.array(
    [(-1, -1), (-1, 1), (1, 1), (1, -1), (0, 2), (0, -2), (-2, -2), (-2, 2), (2, 2), (2, -2)], dtype=np.float64
)
"""HFO's offsets of the agent from the ball, in units of :data:`OFFSET_SCALE`."""
OFFSET_SCALE = 0.2 * PITCH_HALF_LENGTH  # m (10.5)
AGENT_MIN_X, AGENT_MAX_X, AGENT_MAX_ABS_Y = -0.1, PITCH_HALF_LENGTH, 0.8 * PITCH_HALF_WIDTH
ON_BALL_GAP = 0.1  # m the agent stands behind the ball with offense_on_ball
N_START_UNIFORMS = 5
"""Uniforms a start draws, in order: ball x, ball y, the offset, the agent's x and y fractions (always all five)."""


@njit(cache=True, error_model="numpy")
def place(state, i, types, ti, uniforms, row: int, c, k) -> None:
    """Start a trial in lane ``i`` of ``state`` (module docstring) from the five values in row ``row`` of
    ``uniforms`` (:data:`N_START_UNIFORMS`)."""
    u_bx, u_by, u_offset, u_ax, u_ay = uniforms[row, 0], uniforms[row, 1], uniforms[row, 2], uniforms[row, 3], uniforms[row, 4]
    bx = PITCH_HALF_LENGTH * (c[task.R_BALL_X_MIN] + (c[task.R_BALL_X_MAX] - c[task.R_BALL_X_MIN]) * u_bx)
    by = PITCH_HALF_WIDTH * (c[task.R_BALL_Y_MIN] + (c[task.R_BALL_Y_MAX] - c[task.R_BALL_Y_MIN]) * u_by)
    if c[task.R_OFFENSE_ON_BALL] > 0.5:
        px, py = bx - ON_BALL_GAP, by
    else:
        o = min(int(u_offset * AGENT_OFFSETS.shape[0]), AGENT_OFFSETS.shape[0] - 1)
        px = min(max(bx + OFFSET_SCALE * (u_ax + AGENT_OFFSETS[o, 0]), AGENT_MIN_X), AGENT_MAX_X)
        py = min(max(by + OFFSET_SCALE * (u_ay + AGENT_OFFSETS[o, 1]), -AGENT_MAX_ABS_Y), AGENT_MAX_ABS_Y)
    state[i, physics.P_X], state[i, physics.P_Y], state[i, physics.P_VX], state[i, physics.P_VY] = px, py, 0.0, 0.0
    state[i, physics.B_X], state[i, physics.B_Y], state[i, physics.B_VX], state[i, physics.B_VY] = bx, by, 0.0, 0.0
    state[i, physics.S_FROZEN] = 0.0
    physics.recover_lane(state, i, types, ti, k)


@njit(cache=True, error_model="numpy", inline="always")
def crossed_goal_line(prev_x: float, prev_y: float, x: float, y: float, ball_size: float, goal_width: float) -> bool:
    """The ball went into the right-hand goal between ``(prev_x, prev_y)`` and ``(x, y)`` (the referee's
    ``crossGoalLine``)."""
    line = PITCH_HALF_LENGTH + ball_size
    mouth = 0.5 * goal_width + GOAL_POST_RADIUS
    if prev_x == x or x <= line or abs(prev_x) > line or x <= 0.0:
        return False
    if abs(prev_y) > mouth and abs(prev_x) > PITCH_HALF_LENGTH:
        return False
    y_at_line = prev_y + (y - prev_y) * (line - prev_x) / (x - prev_x)
    return abs(y_at_line) <= mouth


@njit(cache=True, error_model="numpy", inline="always")
def outside_area(x: float, y: float) -> bool:
    """``(x, y)`` lies outside the HFO area: x in [0, 52.5], |y| <= 34."""
    return x < 0.0 or x > PITCH_HALF_LENGTH or abs(y) > PITCH_HALF_WIDTH


@njit(cache=True, error_model="numpy", inline="always")
def judge(state, i, types, ti, prev_x: float, prev_y: float, untouched: int, cycles: int, c, k) -> tuple[int, int]:
    """The status after a cycle of lane ``i`` whose ball was at ``(prev_x, prev_y)`` before it, given the cycles
    the ball had been untouched before it and the trial's cycles including it; returns ``(status, untouched)``."""
    bx, by = state[i, physics.B_X], state[i, physics.B_Y]
    if crossed_goal_line(prev_x, prev_y, bx, by, k[physics.K_BALL_SIZE], k[physics.K_GOAL_WIDTH]):
        return GOAL, untouched
    if outside_area(prev_x, prev_y):
        return OUT_OF_BOUNDS, untouched
    if untouched > c[task.R_UNTOUCHED_TIME] or cycles > c[task.R_FRAMES_PER_TRIAL]:
        return OUT_OF_TIME, untouched
    reach = physics.kickable_radius(types[ti, physics.T_SIZE], k[physics.K_BALL_SIZE], types[ti, physics.T_KICKABLE_MARGIN])
    dx, dy = bx - state[i, physics.P_X], by - state[i, physics.P_Y]
    return IN_GAME, (0 if dx * dx + dy * dy < reach * reach else untouched + 1)
