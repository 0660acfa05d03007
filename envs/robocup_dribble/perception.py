"""What a player in a match perceives of the dribble, and the estimate it keeps from that (``perception="match"``).

In a match a player does not read the exact state; rcssserver 19 sends it (synchronous mode, the default view: normal
width, high quality, neck straight, focus point at the player):

* **see**, after every second cycle (``src/player.cpp``, ``Player::change_view``: ``visual_send_interval`` 2, view
  cone 4/3 of ``visible_angle`` 90 = 120 degrees). The ball's distance ``d`` is quantised logarithmically and then to
  0.1 m (:func:`seen_distance`, ``src/visualsenderplayer.cpp``, ``QuantizeObservation::calcDist``), its direction
  relative to the body is rounded to whole degrees (``Rad2IDegRound``, the v7+ senders' ``rad2Deg``). Only while the
  ball is inside the cone (``|direction| < 60`` degrees) the relative velocity comes too: the distance change as
  ``quantised distance * Quantize(radial speed / d, 0.02)`` and the direction change (degrees/cycle) quantised to 0.1
  (``QuantizeObservation::calcVel``). A ball outside the cone but within ``VISIBLE_DISTANCE`` (3 m) is reported
  with distance and direction only (``(B) dist dir``); beyond both it is not seen.
* **sense_body**, after every cycle (``src/bodysender.cpp``): the player's speed quantised to 0.01 m/cycle and its
  direction relative to the body truncated to whole degrees (:func:`sensed_speed`).

The player's estimate (:func:`update_estimate`, the world model of a simple RoboCup agent): each cycle the noise-free
physics predicts player and ball from the last estimate and the command sent; the sensed speed replaces the
player's velocity; a seen ball replaces the ball's position relative to the player, and its velocity, when the ball
was in the view cone, or else the ball's position error (against the prediction) is put down to its velocity since
the last sight. The body angle is the true one (an agent reads it from the seen field lines to about a degree; the
skills never turn the player). The same function serves the env (:func:`perceive_lane`: perceptions computed from
the true state) and the real-server client (:class:`robocup_dribble.rcss.perception.PerceivedWorld`: perceptions
read from the server's messages).

Left out: the see's quantisation is rcssserver 19's only see noise by default (``gaussian_see`` off), so nothing
random is drawn; the player's own position is dead reckoning from the sensed speeds (as the client's; an agent would
also localise from the seen flags, which matters little for a ball seen relative to the player).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from robocup_dribble import physics
from robocup_dribble.params import EPS

PERCEPTIONS = ("full", "match")
"""What the policy's observation and the skills' commands are computed from: ``"full"`` the exact state (the
default), ``"match"`` the player's estimate from its own perception (this module)."""

SIGHT_INTERVAL = 2
"""Cycles from one see to the next (synchronous mode, normal view width)."""
VIEW_CONE = math.radians(90.0 * 4.0 / 3.0)
"""Width of the view cone (radians): 4/3 of ``visible_angle`` (90 degrees) for the normal width in synchronous mode."""
VISIBLE_DISTANCE = 3.0
"""Metres within which the ball is seen (without velocity) outside the view cone (``VISIBLE_DISTANCE``)."""
DISTANCE_STEP = 0.1
"""Step of the logarithmic distance quantisation: ``quantize_step`` 0.1 times the normal view's noise term 1."""
DIRECTION_CHANGE_STEP = 0.1
"""Degrees per cycle: 0.1 times the normal view's noise term 1 (``Player::dirQStep``)."""
RELATIVE_DISTANCE_CHANGE_STEP = 0.02
"""Step of the radial speed divided by the distance (``calcVel``)."""
SPEED_STEP = 0.01
"""m/cycle: sense_body's speed quantisation."""
RAD2DEG = 180.0 / math.pi
"""As rcssserver's ``RAD2DEG`` (``180.0 / M_PI``)."""
VELOCITY_GAIN = 1.0
"""Share of a seen ball's position error (against the prediction) that corrects its estimated velocity."""

NOT_SEEN, SEEN_CLOSE, SEEN_IN_CONE = 0, 1, 2
"""Kinds of sighting of the ball: not in the see, distance and direction only (``(B)``), with its changes (``(b)``)."""


def check_perception(perception: str) -> str:
    """``perception`` if it is one of :data:`PERCEPTIONS`.

    :raises ValueError: naming the allowed values otherwise.
    """
    if perception not in PERCEPTIONS:
        raise ValueError(f"perception must be one of {list(PERCEPTIONS)}, got {perception!r}")
    return perception


@njit(cache=True, error_model="numpy", inline="always")
def quantise(value: float, step: float) -> float:
    """rcssserver's ``Quantize``: ``value`` rounded to a multiple of ``step`` (halves to even, as C's ``rint``)."""
    return float(np.rint(value / step)) * step


@njit(cache=True, error_model="numpy", inline="always")
def whole_degrees(angle: float) -> float:
    """rcssserver's ``Rad2IDeg`` (sense_body): ``angle`` (radians) in degrees, truncated toward zero."""
    return float(int(angle * RAD2DEG))


@njit(cache=True, error_model="numpy", inline="always")
def rounded_degrees(angle: float) -> float:
    """rcssserver's ``Rad2IDegRound`` (see): ``angle`` (radians) in degrees, rounded (halves to even, C's ``rint``)."""
    return float(np.rint(angle * RAD2DEG))


@njit(cache=True, error_model="numpy", inline="always")
def seen_distance(actual: float) -> float:
    """The distance a see reports for an object ``actual`` metres away, with the focus point at the player (v18+'s
    ``QuantizeObservation::calcDist``, whose focus term then equals the distance term)."""
    quantised = math.exp(quantise(math.log(actual + EPS), DISTANCE_STEP))
    focus = actual  # the focus point is the player's position: the object's distance to it is the distance
    quantised_focus = math.exp(quantise(math.log(focus + EPS), DISTANCE_STEP))
    observed = max(0.0, actual - ((focus - quantised_focus) + (actual - quantised)) / 2.0)
    return quantise(observed, 0.1)


@njit(cache=True, error_model="numpy", inline="always")
def seen_ball(state, i: int) -> tuple[int, float, float, float, float]:
    """The ball of lane ``i`` as a see after this state reports it: ``(kind, distance, direction, distance_change,
    direction_change)`` (kind :data:`NOT_SEEN`, :data:`SEEN_CLOSE` or :data:`SEEN_IN_CONE`; the changes are 0 unless
    in the cone; directions in degrees relative to the body, the neck being straight)."""
    rx, ry = state[i, physics.B_X] - state[i, physics.P_X], state[i, physics.B_Y] - state[i, physics.P_Y]
    actual = physics.norm(rx, ry)
    angle = 0.0 if rx == 0.0 and ry == 0.0 else math.atan2(ry, rx)
    relative = physics.normalize_angle(angle - state[i, physics.P_BODY])
    distance = seen_distance(actual)
    direction = rounded_degrees(relative)
    if abs(relative) < VIEW_CONE * 0.5:
        if actual == 0.0:
            return SEEN_IN_CONE, distance, direction, 0.0, 0.0
        vx = state[i, physics.B_VX] - state[i, physics.P_VX]
        vy = state[i, physics.B_VY] - state[i, physics.P_VY]
        ex, ey = rx / actual, ry / actual
        radial = vx * ex + vy * ey
        turn = (vy * ex - vx * ey) / actual * RAD2DEG
        turn = 0.0 if turn == 0.0 else quantise(turn, DIRECTION_CHANGE_STEP)
        return SEEN_IN_CONE, distance, direction, distance * quantise(radial / actual, RELATIVE_DISTANCE_CHANGE_STEP), turn
    if actual <= VISIBLE_DISTANCE:
        return SEEN_CLOSE, distance, direction, 0.0, 0.0
    return NOT_SEEN, 0.0, 0.0, 0.0, 0.0


@njit(cache=True, error_model="numpy", inline="always")
def sensed_speed(state, i: int) -> tuple[float, float]:
    """The player's speed (m/cycle) and its direction relative to the body (degrees) as sense_body reports them."""
    vx, vy = state[i, physics.P_VX], state[i, physics.P_VY]
    heading = 0.0 if vx == 0.0 and vy == 0.0 else math.atan2(vy, vx)
    return quantise(physics.norm(vx, vy), SPEED_STEP), whole_degrees(
        physics.normalize_angle(heading - state[i, physics.P_BODY])
    )


@njit(cache=True, error_model="numpy")
def update_estimate(
    estimate,
    i: int,
    types,
    ti: int,
    kind: int,
    power: float,
    direction: float,
    body: float,
    speed: float,
    speed_direction: float,
    sighting: int,
    distance: float,
    ball_direction: float,
    distance_change: float,
    direction_change: float,
    unseen: int,
    calm,
    k0,
) -> int:
    """Advance lane ``i``'s estimate by a cycle with the command ``(kind, power, direction)`` and correct it by what
    the player perceived after it (module docstring); returns the cycles since the ball was last seen.

    :param body: the true body angle (radians). :param speed: sensed speed, ``speed_direction`` its direction
        (degrees from the body). :param sighting: :data:`NOT_SEEN` (also for a cycle without a see),
        :data:`SEEN_CLOSE` or :data:`SEEN_IN_CONE`, with the seen ``distance``, ``ball_direction`` (degrees from the
        body) and, in the cone, ``distance_change`` and ``direction_change``. :param unseen: cycles since the ball was
        last seen, before this one. :param calm: ``(1, N_UNIFORMS)`` draws for the prediction. :param k0: noise-free
        :func:`robocup_dribble.physics.profile_constants`.
    """
    physics.cycle(estimate, i, types, ti, kind, power, direction, calm, 0, k0)
    estimate[i, physics.P_BODY] = body
    heading = body + math.radians(speed_direction)
    estimate[i, physics.P_VX], estimate[i, physics.P_VY] = speed * math.cos(heading), speed * math.sin(heading)
    unseen += 1
    if sighting == NOT_SEEN:
        return unseen
    angle = body + math.radians(ball_direction)
    ex, ey = math.cos(angle), math.sin(angle)
    seen_x = estimate[i, physics.P_X] + distance * ex
    seen_y = estimate[i, physics.P_Y] + distance * ey
    if sighting == SEEN_IN_CONE:
        across = math.radians(direction_change) * distance
        estimate[i, physics.B_VX] = estimate[i, physics.P_VX] + distance_change * ex - across * ey
        estimate[i, physics.B_VY] = estimate[i, physics.P_VY] + distance_change * ey + across * ex
    else:  # the position missed by the prediction is put down to the ball's velocity since the last sight
        decay = k0[physics.K_BALL_DECAY]
        travelled = 0.0  # the ball's path over the unseen cycles per unit of its velocity after the first
        for j in range(unseen):
            travelled += decay ** float(j)
        share = VELOCITY_GAIN * decay / travelled
        estimate[i, physics.B_VX] += share * (seen_x - estimate[i, physics.B_X])
        estimate[i, physics.B_VY] += share * (seen_y - estimate[i, physics.B_Y])
    estimate[i, physics.B_X], estimate[i, physics.B_Y] = seen_x, seen_y
    return 0


@njit(cache=True, error_model="numpy", inline="always")
def perceive_lane(
    state, estimate, i: int, types, ti: int, kind: int, power: float, direction: float, sees: bool, unseen: int, calm, k0
) -> int:
    """:func:`update_estimate` of lane ``i`` with what the player perceives of the true ``state`` after a cycle with
    the command ``(kind, power, direction)``: its sensed speed, and the seen ball if ``sees`` (a see follows this
    cycle). Returns the cycles since the ball was last seen."""
    speed, speed_direction = sensed_speed(state, i)
    sighting, distance, ball_direction, distance_change, direction_change = NOT_SEEN, 0.0, 0.0, 0.0, 0.0
    if sees:
        sighting, distance, ball_direction, distance_change, direction_change = seen_ball(state, i)
    return update_estimate(
        estimate, i, types, ti, kind, power, direction, state[i, physics.P_BODY], speed, speed_direction,
        sighting, distance, ball_direction, distance_change, direction_change, unseen, calm, k0,
    )  # fmt: skip
