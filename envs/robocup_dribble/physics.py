"""Batched rcssserver physics for one player and one ball per lane.

Every lane is an independent pitch with one player and one ball. The state of N lanes is one ``(N, STATE_SIZE)``
float64 array (columns named by the ``P_*``, ``B_*`` and ``S_*`` constants), the player types one ``(N, TYPE_SIZE)``
array (columns in :data:`robocup_dribble.player_types.TYPE_FIELDS` order) and the commands one ``(N, COMMAND_SIZE)``
array. :func:`step` advances all lanes by one server cycle in a single compiled (numba) call, so one lane costs a few
microseconds and thousands of lanes run without a Python loop.

Formulas and their order follow the rcssserver source as restated in ``../shared/ref/rcssserver-physics.md``
(cited below as "spec §n"); the numbers were checked against recordings of a real rcssserver 19.0.0
(shipped in ``robocup_dribble/data/golden``, replayed by ``python -m robocup_dribble.validate``). One server cycle (spec §1):

1. the command: a kick accelerates the ball at command time (spec §3), a turn sets the body (spec §4),
   a dash accelerates the player (spec §2; v19's two legs, spec §2.4, or the single-leg model, spec §2.3);
2. movement of ball and player: acceleration cap, speed cap, noise, ``p += v``, ``v *= decay`` (spec §5);
3. ball-player collision on the new positions: midpoint push-out, velocities times -0.1 (spec §6.1);
4. stamina, effort and recovery update (spec §2.5).

Randomness enters only through ``uniforms``, an ``(N, N_UNIFORMS)`` array of U[0, 1) draws the caller makes from
its own generator; each has a fixed role (``U_*``). With zero noise parameters the server's ``drand`` returns the
midpoint of an empty range, so noise-free physics is exact whatever the draws are.

Angles are radians inside the state (``P_BODY``) and degrees in commands, like the server.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from robocup_dribble.params import EPS, ServerProfile
from robocup_dribble.player_types import TYPE_FIELDS

# --- state columns -------------------------------------------------------------------------------------------------
P_X, P_Y, P_VX, P_VY, P_BODY = 0, 1, 2, 3, 4  # player position (m), velocity (m/cycle, after decay), body (rad)
B_X, B_Y, B_VX, B_VY = 5, 6, 7, 8  # ball position and velocity
S_STAMINA, S_EFFORT, S_RECOVERY, S_CAPACITY = 9, 10, 11, 12
STATE_SIZE = 13
STATE_FIELDS = ("px", "py", "pvx", "pvy", "body", "bx", "by", "bvx", "bvy", "stamina", "effort", "recovery", "capacity")

# --- player type columns (robocup_dribble.player_types.TYPE_FIELDS) ----------------------------------------------------
T_SPEED_MAX = TYPE_FIELDS.index("player_speed_max")
T_STAMINA_INC_MAX = TYPE_FIELDS.index("stamina_inc_max")
T_DECAY = TYPE_FIELDS.index("player_decay")
T_INERTIA = TYPE_FIELDS.index("inertia_moment")
T_DASH_POWER_RATE = TYPE_FIELDS.index("dash_power_rate")
T_SIZE = TYPE_FIELDS.index("player_size")
T_KICKABLE_MARGIN = TYPE_FIELDS.index("kickable_margin")
T_KICK_RAND = TYPE_FIELDS.index("kick_rand")
T_EXTRA_STAMINA = TYPE_FIELDS.index("extra_stamina")
T_EFFORT_MAX = TYPE_FIELDS.index("effort_max")
T_EFFORT_MIN = TYPE_FIELDS.index("effort_min")
T_KICK_POWER_RATE = TYPE_FIELDS.index("kick_power_rate")
TYPE_SIZE = len(TYPE_FIELDS)

# --- commands: one main command per lane and cycle ---------------------------------------------------------------------
C_KIND, C_POWER, C_DIRECTION = 0, 1, 2  # C_POWER is the turn moment (degrees) for CMD_TURN
COMMAND_SIZE = 3
CMD_NONE, CMD_DASH, CMD_KICK, CMD_TURN = 0, 1, 2, 3

# --- roles of the uniform draws ---------------------------------------------------------------------------------------
U_KICK_R, U_KICK_A = 0, 1  # kick noise (polar: radius, angle; box: x, y)
U_BALL_R, U_BALL_A = 2, 3  # ball movement noise
U_PLAYER_R, U_PLAYER_A = 4, 5  # player movement noise
U_TURN = 6  # turn noise, and the v19 bipedal dash rotation noise (only one of them per cycle)
U_COLLIDE = 7  # separation direction of a coincident ball and player
N_UNIFORMS = 8

# --- events reported by a step -----------------------------------------------------------------------------------------
E_COLLISION, E_KICK_OK = 0, 1
EVENT_SIZE = 2

# --- server constants as one float array (numba takes arrays, not dataclasses) -------------------------------------------
(
    K_BALL_SIZE, K_BALL_DECAY, K_BALL_RAND, K_BALL_SPEED_MAX, K_BALL_ACCEL_MAX, K_PLAYER_RAND, K_PLAYER_ACCEL_MAX,
    K_MAX_POWER, K_MIN_POWER, K_MAX_DASH_POWER, K_MIN_DASH_POWER, K_MAX_DASH_ANGLE, K_MIN_DASH_ANGLE, K_DASH_ANGLE_STEP,
    K_SIDE_DASH_RATE, K_BACK_DASH_RATE, K_MAX_MOMENT, K_MIN_MOMENT, K_STAMINA_MAX, K_STAMINA_CAPACITY,
    K_RECOVER_DEC_THR, K_RECOVER_DEC, K_RECOVER_MIN, K_EFFORT_DEC_THR, K_EFFORT_DEC, K_EFFORT_INC_THR, K_EFFORT_INC,
    K_BIPEDAL, K_DASH_DIRECTION, K_BOX_NOISE, K_EFFORT_BUG,
) = range(31)
N_CONSTANTS = 31


def profile_constants(profile: ServerProfile) -> np.ndarray:
    """Pack a profile into the constant vector the compiled kernel reads (``K_*`` indices)."""
    s = profile.server
    return np.array(
        [
            s.ball_size, s.ball_decay, s.ball_rand, s.ball_speed_max, s.ball_accel_max, s.player_rand, s.player_accel_max,
            s.max_power, s.min_power, s.max_dash_power, s.min_dash_power, s.max_dash_angle, s.min_dash_angle,
            s.dash_angle_step, s.side_dash_rate, s.back_dash_rate, s.max_moment, s.min_moment, s.stamina_max,
            s.stamina_capacity, s.recover_dec_thr, s.recover_dec, s.recover_min, s.effort_dec_thr, s.effort_dec,
            s.effort_inc_thr, s.effort_inc,
            float(profile.dash_model == "bipedal"), float(profile.dash_direction), float(profile.noise_shape == "box"),
            float(profile.effort_inc_uses_dec_thr),
        ],
        dtype=np.float64,
    )


def new_state(n_lanes: int) -> np.ndarray:
    """An all-zero state array for ``n_lanes`` lanes."""
    return np.zeros((n_lanes, STATE_SIZE), dtype=np.float64)


def recover(state: np.ndarray, types: np.ndarray, profile: ServerProfile, lanes: np.ndarray | slice = slice(None)) -> None:
    """The server's ``(recover)``: full stamina, recovery 1, effort at the type's maximum, full capacity (spec §2.5)."""
    state[lanes, S_STAMINA] = profile.server.stamina_max
    state[lanes, S_RECOVERY] = profile.server.recover_init
    state[lanes, S_EFFORT] = types[lanes, T_EFFORT_MAX]
    state[lanes, S_CAPACITY] = profile.server.stamina_capacity


def step(
    state: np.ndarray, types: np.ndarray, commands: np.ndarray, uniforms: np.ndarray, constants: np.ndarray
) -> np.ndarray:
    """Advance every lane by one server cycle, in place.

    :param state: ``(N, STATE_SIZE)`` float64, updated in place.
    :param types: ``(N, TYPE_SIZE)`` float64, each lane's player type.
    :param commands: ``(N, COMMAND_SIZE)`` float64: ``CMD_*`` kind, power (or turn moment), direction in degrees.
    :param uniforms: ``(N, N_UNIFORMS)`` float64 U[0, 1) draws (roles ``U_*``).
    :param constants: the vector from :func:`profile_constants`.
    :return: ``(N, EVENT_SIZE)`` bool events: a ball-player collision happened, a kick was accepted.
    """
    n = state.shape[0]
    for name, array, width in (("types", types, TYPE_SIZE), ("commands", commands, COMMAND_SIZE), ("uniforms", uniforms, N_UNIFORMS)):
        if array.shape != (n, width):
            raise ValueError(f"{name} must have shape ({n}, {width}) to match state {state.shape}, got {array.shape}")
    events = np.zeros((n, EVENT_SIZE), dtype=np.bool_)
    _step_lanes(state, types, commands, uniforms, constants, events)
    return events


# ---------------------------------------------------------------------------------------------------------------------
# Compiled kernel. Each helper works on one lane; _step_lanes loops over lanes in machine code.
# ---------------------------------------------------------------------------------------------------------------------


@njit(cache=True, error_model="numpy", inline="always")
def _drand(lo: float, hi: float, u: float) -> float:
    """rcssserver's ``drand``: uniform in [lo, hi) (bounds swapped if reversed); the midpoint for an empty range."""
    if hi < lo:
        lo, hi = hi, lo
    if hi - lo < 1e-10:
        return 0.5 * (lo + hi)
    return lo + (hi - lo) * u


@njit(cache=True, error_model="numpy", inline="always")
def normalize_angle(a: float) -> float:
    """Wrap an angle in radians to [-pi, pi]."""
    while a > math.pi:
        a -= 2.0 * math.pi
    while a < -math.pi:
        a += 2.0 * math.pi
    return a


@njit(cache=True, error_model="numpy")
def _noise(r_max: float, u_r: float, u_a: float, box: bool) -> tuple[float, float]:
    """Movement/kick noise of size ``r_max``: polar (v12+, radius uniform) or box (v11), spec §5.2 and §3.5."""
    if box:
        return _drand(-r_max, r_max, u_r), _drand(-r_max, r_max, u_a)
    radius = _drand(0.0, r_max, u_r)
    angle = _drand(-math.pi, math.pi, u_a)
    return radius * math.cos(angle), radius * math.sin(angle)


@njit(cache=True, error_model="numpy")
def _dir_rate(direction: float, k: np.ndarray) -> float:
    """Dash efficiency by direction in degrees relative to the body (spec §2.2, v13+)."""
    d = abs(direction)
    side, back = k[K_SIDE_DASH_RATE], k[K_BACK_DASH_RATE]
    if d <= 90.0:
        rate = side + (1.0 - side) * (1.0 - d / 90.0)
    else:
        rate = back - (back - side) * (1.0 - (d - 90.0) / 90.0)
    return min(max(rate, 0.0), 1.0)


@njit(cache=True, error_model="numpy")
def _leg_accel(power: float, direction: float, body: float, effort: float, dash_power_rate: float, k: np.ndarray):
    """Acceleration of a dash (or of one leg) with effective power ``power`` (spec §2.3)."""
    rate = _dir_rate(direction, k) if k[K_DASH_DIRECTION] > 0.5 else 1.0
    magnitude = abs(effort * power * rate * dash_power_rate)
    heading = body + math.radians(direction)
    sign = 1.0 if power >= 0.0 else -1.0
    return sign * magnitude * math.cos(heading), sign * magnitude * math.sin(heading)


@njit(cache=True, error_model="numpy")
def _dash(s: np.ndarray, t: np.ndarray, power: float, direction: float, u_turn: float, k: np.ndarray):
    """Apply a dash: returns the player's acceleration; updates stamina (and body, for v19's two legs)."""
    power = min(max(power, k[K_MIN_DASH_POWER]), k[K_MAX_DASH_POWER])
    if k[K_DASH_DIRECTION] > 0.5:
        direction = min(max(direction, k[K_MIN_DASH_ANGLE]), k[K_MAX_DASH_ANGLE])
        step = k[K_DASH_ANGLE_STEP]
        if step > EPS:
            direction = step * np.rint(direction / step)  # rint: halves to even, like the server
    else:
        direction = 0.0
    available = s[S_STAMINA] + t[T_EXTRA_STAMINA]
    body, effort, dpr = s[P_BODY], s[S_EFFORT], t[T_DASH_POWER_RATE]

    if k[K_BIPEDAL] < 0.5:  # one leg (v18 and earlier, spec §2.3)
        cost = power if power >= 0.0 else -2.0 * power
        cost = min(cost, available)
        effective = cost if power >= 0.0 else -0.5 * cost
        s[S_STAMINA] = max(0.0, s[S_STAMINA] - cost)
        return _leg_accel(effective, direction, body, effort, dpr, k)

    # v19: both legs get (power, direction); the cost split quirk rotates the body when stamina is short (spec §2.4)
    leg_cost = 0.5 * power if power >= 0.0 else -power
    total = 2.0 * leg_cost
    if total < 1e-5:
        return 0.0, 0.0
    cost = min(total, available)
    left_cost = cost * leg_cost / total
    right_cost = cost * leg_cost / (left_cost + leg_cost)  # the server uses the already-updated left share
    if power >= 0.0:
        left_power, right_power = 2.0 * left_cost, 2.0 * right_cost
    else:
        left_power, right_power = -left_cost, -right_cost
    left_power = min(max(left_power, k[K_MIN_DASH_POWER]), k[K_MAX_DASH_POWER])
    right_power = min(max(right_power, k[K_MIN_DASH_POWER]), k[K_MAX_DASH_POWER])
    lx, ly = _leg_accel(left_power, direction, body, effort, dpr, k)
    rx, ry = _leg_accel(right_power, direction, body, effort, dpr, k)
    ux, uy = math.cos(body), math.sin(body)
    omega = (ux * (s[P_VX] + lx) + uy * (s[P_VY] + ly) - ux * (s[P_VX] + rx) - uy * (s[P_VY] + ry)) / (2.0 * t[T_SIZE])
    rand = k[K_PLAYER_RAND]
    s[P_BODY] = normalize_angle(body + (1.0 + _drand(-rand, rand, u_turn)) * omega)
    s[S_STAMINA] = max(0.0, s[S_STAMINA] - cost)
    return 0.5 * (lx + rx), 0.5 * (ly + ry)


@njit(cache=True, error_model="numpy")
def _kick(s: np.ndarray, t: np.ndarray, power: float, direction: float, u_r: float, u_a: float, k: np.ndarray):
    """A kick at command time: returns (accepted, ball acceleration x, y) (spec §3)."""
    power = min(max(power, k[K_MIN_POWER]), k[K_MAX_POWER])
    direction = math.radians(min(max(direction, k[K_MIN_MOMENT]), k[K_MAX_MOMENT]))
    rx, ry = s[B_X] - s[P_X], s[B_Y] - s[P_Y]
    distance = math.hypot(rx, ry)
    reach = t[T_SIZE] + k[K_BALL_SIZE] + t[T_KICKABLE_MARGIN]
    if distance * distance > reach * reach:
        return False, 0.0, 0.0
    body = s[P_BODY]
    dir_diff = abs(normalize_angle(math.atan2(ry, rx) - body))
    dist_ball = distance - t[T_SIZE] - k[K_BALL_SIZE]
    effective = power * t[T_KICK_POWER_RATE] * (1.0 - 0.25 * dir_diff / math.pi - 0.25 * dist_ball / t[T_KICKABLE_MARGIN])
    ax = effective * math.cos(body + direction)
    ay = effective * math.sin(body + direction)
    box = k[K_BOX_NOISE] > 0.5
    if box:  # v11: box of half-width kick_rand * power / max_power
        max_rand = t[T_KICK_RAND] * power / k[K_MAX_POWER]
    else:  # v12+: grows with the ball's distance, angle and speed
        pos_rate = 0.5 + 0.25 * (dir_diff / math.pi + dist_ball / t[T_KICKABLE_MARGIN])
        speed_rate = 0.5 + 0.5 * math.hypot(s[B_VX], s[B_VY]) / (k[K_BALL_SPEED_MAX] * k[K_BALL_DECAY])
        max_rand = t[T_KICK_RAND] * (power / k[K_MAX_POWER]) * (pos_rate + speed_rate)
    nx, ny = _noise(max_rand, u_r, u_a, box)
    return True, ax + nx, ay + ny


@njit(cache=True, error_model="numpy")
def _turn(s: np.ndarray, t: np.ndarray, moment: float, u_turn: float, k: np.ndarray) -> None:
    """A turn: the body rotates by the moment over (1 + inertia * speed), with noise (spec §4)."""
    moment = math.radians(min(max(moment, k[K_MIN_MOMENT]), k[K_MAX_MOMENT]))
    rand = k[K_PLAYER_RAND]
    speed = math.hypot(s[P_VX], s[P_VY])
    turned = (1.0 + _drand(-rand, rand, u_turn)) * moment / (1.0 + t[T_INERTIA] * speed)
    s[P_BODY] = normalize_angle(s[P_BODY] + turned)


@njit(cache=True, error_model="numpy")
def _move(s: np.ndarray, ix: int, ax: float, ay: float, accel_max: float, speed_max: float, rand: float,
          decay: float, u_r: float, u_a: float, box: bool) -> None:
    """``MPObject::_inc`` for the object whose columns start at ``ix`` (spec §5.1)."""
    vx, vy = s[ix + 2], s[ix + 3]
    if ax != 0.0 or ay != 0.0:  # both caps are skipped when there is no acceleration
        a = math.hypot(ax, ay)
        if a > accel_max:
            ax, ay = ax * accel_max / a, ay * accel_max / a
        vx, vy = vx + ax, vy + ay
        v = math.hypot(vx, vy)
        if v > speed_max:
            vx, vy = vx * speed_max / v, vy * speed_max / v
    nx, ny = _noise(rand * math.hypot(vx, vy), u_r, u_a, box)
    vx, vy = vx + nx, vy + ny
    s[ix], s[ix + 1] = s[ix] + vx, s[ix + 1] + vy
    s[ix + 2], s[ix + 3] = decay * vx, decay * vy


@njit(cache=True, error_model="numpy")
def _collide(s: np.ndarray, t: np.ndarray, u: float, k: np.ndarray) -> bool:
    """Resolve a ball-player overlap by the midpoint push-out; both velocities times -0.1 (spec §6.1)."""
    reach = k[K_BALL_SIZE] + t[T_SIZE]
    collided = False
    for _ in range(10):
        dx, dy = s[B_X] - s[P_X], s[B_Y] - s[P_Y]
        distance = math.hypot(dx, dy)
        if distance >= reach:
            break
        collided = True
        mx, my = 0.5 * (s[B_X] + s[P_X]), 0.5 * (s[B_Y] + s[P_Y])
        half = 0.5 * distance
        if half < EPS:  # coincident: separate in a random direction
            angle = _drand(-math.pi, math.pi, u)
            ex, ey = math.cos(angle), math.sin(angle)
        else:
            ex, ey = dx / distance, dy / distance
        push = 0.5 * reach + EPS
        bx, by, px, py = s[B_X], s[B_Y], s[P_X], s[P_Y]
        for _grow in range(10):  # rounding may leave them overlapping: grow the offsets by 0.01 %
            bx, by = mx + ex * push, my + ey * push
            px, py = mx - ex * push, my - ey * push
            if math.hypot(bx - px, by - py) >= reach:
                break
            push *= 1.0001
        s[B_X], s[B_Y], s[P_X], s[P_Y] = bx, by, px, py
    if collided:
        s[B_VX], s[B_VY] = -0.1 * s[B_VX], -0.1 * s[B_VY]
        s[P_VX], s[P_VY] = -0.1 * s[P_VX], -0.1 * s[P_VY]
    return collided


@njit(cache=True, error_model="numpy")
def _update_stamina(s: np.ndarray, t: np.ndarray, k: np.ndarray) -> None:
    """``Player::updateStamina``: recovery and effort decay, effort rise, stamina recovery and capacity (spec §2.5)."""
    stamina_max = k[K_STAMINA_MAX]
    stamina = s[S_STAMINA]
    if stamina <= k[K_RECOVER_DEC_THR] * stamina_max:
        s[S_RECOVERY] = max(k[K_RECOVER_MIN], s[S_RECOVERY] - k[K_RECOVER_DEC])
    if stamina <= k[K_EFFORT_DEC_THR] * stamina_max:
        s[S_EFFORT] = max(t[T_EFFORT_MIN], s[S_EFFORT] - k[K_EFFORT_DEC])
    rise_threshold = k[K_EFFORT_DEC_THR] if k[K_EFFORT_BUG] > 0.5 else k[K_EFFORT_INC_THR]
    if stamina >= rise_threshold * stamina_max:
        s[S_EFFORT] = min(t[T_EFFORT_MAX], s[S_EFFORT] + k[K_EFFORT_INC])
    increase = min(s[S_RECOVERY] * t[T_STAMINA_INC_MAX], stamina_max - stamina)
    has_capacity = k[K_STAMINA_CAPACITY] >= 0.0
    if has_capacity:
        increase = min(increase, s[S_CAPACITY])
    s[S_STAMINA] = min(stamina_max, stamina + increase)
    if has_capacity:
        s[S_CAPACITY] = max(0.0, s[S_CAPACITY] - increase)


@njit(cache=True, error_model="numpy")
def step_lane(s: np.ndarray, t: np.ndarray, c: np.ndarray, u: np.ndarray, k: np.ndarray, events: np.ndarray) -> None:
    """One server cycle of one lane (rows of the arrays :func:`step` takes); compiled code may call it directly."""
    box = k[K_BOX_NOISE] > 0.5
    kind = int(c[C_KIND])
    ball_ax = ball_ay = player_ax = player_ay = 0.0
    events[E_KICK_OK] = False
    if kind == CMD_KICK:
        ok, ball_ax, ball_ay = _kick(s, t, c[C_POWER], c[C_DIRECTION], u[U_KICK_R], u[U_KICK_A], k)
        events[E_KICK_OK] = ok
    elif kind == CMD_TURN:
        _turn(s, t, c[C_POWER], u[U_TURN], k)
    elif kind == CMD_DASH:
        player_ax, player_ay = _dash(s, t, c[C_POWER], c[C_DIRECTION], u[U_TURN], k)
    _move(s, B_X, ball_ax, ball_ay, k[K_BALL_ACCEL_MAX], k[K_BALL_SPEED_MAX], k[K_BALL_RAND], k[K_BALL_DECAY],
          u[U_BALL_R], u[U_BALL_A], box)
    _move(s, P_X, player_ax, player_ay, k[K_PLAYER_ACCEL_MAX], t[T_SPEED_MAX], k[K_PLAYER_RAND], t[T_DECAY],
          u[U_PLAYER_R], u[U_PLAYER_A], box)
    events[E_COLLISION] = _collide(s, t, u[U_COLLIDE], k)
    _update_stamina(s, t, k)


@njit(cache=True, error_model="numpy")
def _step_lanes(state, types, commands, uniforms, k, events) -> None:
    for i in range(state.shape[0]):
        step_lane(state[i], types[i], commands[i], uniforms[i], k, events[i])
