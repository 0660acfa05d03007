"""Batched rcssserver physics for one player and one ball per lane.

Every lane is an independent pitch with one player and one ball. The state of N lanes is one ``(N, STATE_SIZE)``
float64 array (columns named by the ``P_*``, ``B_*`` and ``S_*`` constants), the player types one ``(N, TYPE_SIZE)``
array (columns in :data:`robocup_dribble.player_types.TYPE_FIELDS` order) and the commands one ``(N, COMMAND_SIZE)``
array; every layout is a tuple of field names (``*_FIELDS``) and the column constants are looked up in it by name.
:func:`step` advances all lanes by one server cycle in a single compiled (numba) call; compiled code calls
:func:`cycle`, one lane's cycle on scalars read from and written back to the 2-D arrays (no row views), directly.

Formulas and their order follow the rcssserver source as restated in ``docs/physics.md`` (cited below by section,
"docs/physics.md §n"); the numbers were checked against recordings of a real rcssserver 19.0.0 (shipped in
``robocup_dribble/data/golden``, replayed by ``python -m robocup_dribble.validate``). One server cycle
(docs/physics.md §1):

1. the command: a kick accelerates the ball at command time (docs/physics.md §3), a turn sets the body (§4), a dash
   accelerates the player (§2; v19's two legs, §2.4, or the single-leg model, §2.3), a tackle may push the ball and
   freezes the player (§3.7; a frozen player's command is refused), and the frozen count goes down;
2. movement of ball and player: acceleration cap, speed cap, noise, goal posts near the goal lines (§6.3),
   ``p += v``, ``v *= decay`` (docs/physics.md §5);
3. ball-player collision on the new positions: midpoint push-out, velocities times -0.1 (docs/physics.md §6.1);
4. stamina, effort and recovery update (docs/physics.md §2.5).

Randomness enters only through ``uniforms``, an ``(N, N_UNIFORMS)`` array of U[0, 1) draws the caller makes from
its own generator; each has a fixed role (``U_*``). Vector lengths are ``sqrt(x*x + y*y)`` as in the server's
``Vector2D`` (before the flat kernel, ``math.hypot``: results differ in the last bits, far below the recordings'
6 printed digits). With zero noise parameters the server's ``drand`` returns the
midpoint of an empty range, so noise-free physics is exact whatever the draws are.

Angles are radians inside the state (``P_BODY``) and degrees in commands, like the server.

The Python API (:func:`step`, :func:`recover`, :func:`profile_constants`, :func:`new_state`) checks shapes, dtypes
and values before any compiled code runs. The compiled per-lane building blocks (:func:`cycle`, :func:`step_lane`,
:func:`recover_lane`, ...) are for other compiled code and do no checks: from Python, use :func:`step`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from robocup_dribble import params
from robocup_dribble.params import EPS, GOAL_POST_RADIUS, PITCH_HALF_LENGTH, ServerProfile
from robocup_dribble.player_types import TYPE_FIELDS

# Every vector the compiled code reads is laid out by one tuple of field names; the column constants below are
# looked up by name in it, so a field can be added or moved in one place.

# --- state columns -------------------------------------------------------------------------------------------------
STATE_FIELDS = (
    "px", "py", "pvx", "pvy", "body", "bx", "by", "bvx", "bvy", "stamina", "effort", "recovery", "capacity", "frozen",
)  # fmt: skip
"""Player position (m), velocity (m/cycle, after decay), body (rad); ball position and velocity; stamina model;
cycles the player stays frozen by its last tackle (its commands are refused while this is > 0)."""
P_X, P_Y, P_VX, P_VY, P_BODY = (STATE_FIELDS.index(f) for f in ("px", "py", "pvx", "pvy", "body"))
B_X, B_Y, B_VX, B_VY = (STATE_FIELDS.index(f) for f in ("bx", "by", "bvx", "bvy"))
S_STAMINA, S_EFFORT, S_RECOVERY, S_CAPACITY = (STATE_FIELDS.index(f) for f in ("stamina", "effort", "recovery", "capacity"))
S_FROZEN = STATE_FIELDS.index("frozen")
STATE_SIZE = len(STATE_FIELDS)

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
COMMAND_FIELDS = ("kind", "power", "direction")  # power is the turn moment (degrees) for CMD_TURN, unused by CMD_TACKLE
C_KIND, C_POWER, C_DIRECTION = (COMMAND_FIELDS.index(f) for f in COMMAND_FIELDS)
COMMAND_SIZE = len(COMMAND_FIELDS)
CMD_NONE, CMD_DASH, CMD_KICK, CMD_TURN, CMD_TACKLE = 0, 1, 2, 3, 4
N_COMMANDS = 5

# --- roles of the uniform draws ---------------------------------------------------------------------------------------
UNIFORM_FIELDS = ("kick_r", "kick_a", "ball_r", "ball_a", "player_r", "player_a", "turn", "collide")
"""Kick noise (polar: radius, angle; box: x, y; also a tackle's noise), ball and player movement noise (same), turn
noise (also the v19 bipedal dash rotation noise and a tackle's success draw: only one of them per cycle), separation
direction of a coincident ball and player (also of an object at the very centre of a goal post)."""
U_KICK_R, U_KICK_A, U_BALL_R, U_BALL_A, U_PLAYER_R, U_PLAYER_A, U_TURN, U_COLLIDE = (
    UNIFORM_FIELDS.index(f) for f in UNIFORM_FIELDS
)
N_UNIFORMS = len(UNIFORM_FIELDS)

# --- events reported by a step -----------------------------------------------------------------------------------------
EVENT_FIELDS = ("collision", "kick_ok", "post")
"""A ball-player collision happened; a kick was accepted; the player collided with a goal post."""
E_COLLISION, E_KICK_OK, E_POST = (EVENT_FIELDS.index(f) for f in EVENT_FIELDS)
EVENT_SIZE = len(EVENT_FIELDS)

# --- server constants as one float vector (numba takes arrays, not dataclasses) ------------------------------------------
SERVER_CONSTANT_FIELDS = (
    "ball_size",
    "ball_decay",
    "ball_rand",
    "ball_speed_max",
    "ball_accel_max",
    "player_rand",
    "player_accel_max",
    "max_power",
    "min_power",
    "max_dash_power",
    "min_dash_power",
    "max_dash_angle",
    "min_dash_angle",
    "dash_angle_step",
    "side_dash_rate",
    "back_dash_rate",
    "max_moment",
    "min_moment",
    "stamina_max",
    "stamina_capacity",
    "recover_init",
    "recover_dec_thr",
    "recover_dec",
    "recover_min",
    "effort_dec_thr",
    "effort_dec",
    "effort_inc_thr",
    "effort_inc",
    "goal_width",
    "tackle_dist",
    "tackle_back_dist",
    "tackle_width",
    "tackle_exponent",
    "tackle_cycles",
    "tackle_power_rate",
    "max_tackle_power",
    "max_back_tackle_power",
    "tackle_rand_factor",
)
"""The :class:`robocup_dribble.params.ServerParams` fields the kernel reads, under their own names."""
BEHAVIOUR_FIELDS = ("bipedal", "dash_direction", "box_noise", "effort_bug")
"""The profile's version behaviours as 0/1 flags: two-leg dash, dash direction, box noise, v11 effort rise bug."""
CONSTANT_FIELDS = SERVER_CONSTANT_FIELDS + BEHAVIOUR_FIELDS
(
    K_BALL_SIZE,
    K_BALL_DECAY,
    K_BALL_RAND,
    K_BALL_SPEED_MAX,
    K_BALL_ACCEL_MAX,
    K_PLAYER_RAND,
    K_PLAYER_ACCEL_MAX,
    K_MAX_POWER,
    K_MIN_POWER,
    K_MAX_DASH_POWER,
    K_MIN_DASH_POWER,
    K_MAX_DASH_ANGLE,
    K_MIN_DASH_ANGLE,
    K_DASH_ANGLE_STEP,
    K_SIDE_DASH_RATE,
    K_BACK_DASH_RATE,
    K_MAX_MOMENT,
    K_MIN_MOMENT,
    K_STAMINA_MAX,
    K_STAMINA_CAPACITY,
    K_RECOVER_INIT,
    K_RECOVER_DEC_THR,
    K_RECOVER_DEC,
    K_RECOVER_MIN,
    K_EFFORT_DEC_THR,
    K_EFFORT_DEC,
    K_EFFORT_INC_THR,
    K_EFFORT_INC,
    K_GOAL_WIDTH,
    K_TACKLE_DIST,
    K_TACKLE_BACK_DIST,
    K_TACKLE_WIDTH,
    K_TACKLE_EXPONENT,
    K_TACKLE_CYCLES,
    K_TACKLE_POWER_RATE,
    K_MAX_TACKLE_POWER,
    K_MAX_BACK_TACKLE_POWER,
    K_TACKLE_RAND_FACTOR,
    K_BIPEDAL,
    K_DASH_DIRECTION,
    K_BOX_NOISE,
    K_EFFORT_BUG,
) = (CONSTANT_FIELDS.index(f) for f in CONSTANT_FIELDS)  # unpacking checks the count; the names follow the fields
N_CONSTANTS = len(CONSTANT_FIELDS)


def profile_constants(profile: ServerProfile) -> np.ndarray:
    """Pack a profile into the constant vector the compiled kernel reads (:data:`CONSTANT_FIELDS` order)."""
    behaviours = {
        "bipedal": profile.dash_model == "bipedal",
        "dash_direction": profile.dash_direction,
        "box_noise": profile.noise_shape == "box",
        "effort_bug": profile.effort_inc_uses_dec_thr,
    }
    values = [getattr(profile.server, name) for name in SERVER_CONSTANT_FIELDS]
    values += [float(behaviours[name]) for name in BEHAVIOUR_FIELDS]
    return np.array(values, dtype=np.float64)


def new_state(n_lanes: int) -> np.ndarray:
    """An all-zero state array for ``n_lanes`` lanes."""
    return np.zeros((n_lanes, STATE_SIZE), dtype=np.float64)


def recover(state: np.ndarray, types: np.ndarray, profile: ServerProfile, lanes: np.ndarray | slice = slice(None)) -> None:
    """The server's ``(recover)`` for ``lanes`` (indices or a slice; docs/physics.md §2.5): see :func:`recover_lane`."""
    check_array("state", state, (None, STATE_SIZE))
    types = input_array("types", types, (state.shape[0], TYPE_SIZE))
    _recover_lanes(state, types, np.arange(state.shape[0])[lanes], profile_constants(profile))


def step(
    state: np.ndarray, types: np.ndarray, commands: np.ndarray, uniforms: np.ndarray, constants: np.ndarray
) -> np.ndarray:
    """Advance every lane by one server cycle, in place.

    :param state: ``(N, STATE_SIZE)`` float64, updated in place.
    :param types: ``(N, TYPE_SIZE)`` float64, each lane's player type.
    :param commands: ``(N, COMMAND_SIZE)`` float64: ``CMD_*`` kind, power (or turn moment), direction in degrees.
    :param uniforms: ``(N, N_UNIFORMS)`` float64 U[0, 1) draws (roles ``U_*``).
    :param constants: the vector from :func:`profile_constants`.
    :return: ``(N, EVENT_SIZE)`` bool events (:data:`EVENT_FIELDS`).
    :raises ValueError: for an array of the wrong shape or dtype; nothing changes.
    """
    check_array("state", state, (None, STATE_SIZE))
    n = state.shape[0]
    types = input_array("types", types, (n, TYPE_SIZE))
    commands = input_array("commands", commands, (n, COMMAND_SIZE))
    uniforms = input_array("uniforms", uniforms, (n, N_UNIFORMS))
    constants = input_array("constants", constants, (N_CONSTANTS,))
    if not np.isin(commands[:, C_KIND], np.arange(N_COMMANDS)).all():
        raise ValueError(f"commands[:, {C_KIND}] must hold command kinds CMD_NONE..CMD_TACKLE (0..{N_COMMANDS - 1})")
    events = np.zeros((n, EVENT_SIZE), dtype=np.bool_)
    _step_lanes(state, types, commands, uniforms, constants, events)
    return events


def check_array(name: str, array: np.ndarray, shape: tuple[int | None, ...], dtype: type = np.float64) -> None:
    """Raise ValueError unless ``array`` is a C-contiguous numpy array of ``dtype`` and ``shape`` (None: any size).

    Every public function that hands arrays to a compiled kernel checks them with this first: the kernels do no
    bounds checks, so a wrong shape would read or write outside the arrays.
    """
    if not isinstance(array, np.ndarray) or array.dtype != dtype or not array.flags.c_contiguous:  # type: ignore[redundant-expr]
        got = type(array).__name__ if not isinstance(array, np.ndarray) else f"{array.dtype} array"  # type: ignore[redundant-expr]
        raise ValueError(f"{name} must be a C-contiguous {np.dtype(dtype)} numpy array, got {got}")
    mismatched = any(want is not None and got != want for got, want in zip(array.shape, shape, strict=False))
    if array.ndim != len(shape) or mismatched:
        wanted = "(" + ", ".join("N" if want is None else str(want) for want in shape) + ("," if len(shape) == 1 else "") + ")"
        raise ValueError(f"{name} must have shape {wanted}, got {array.shape}")


def input_array(name: str, values: Any, shape: tuple[int | None, ...], dtype: type = np.float64) -> np.ndarray:
    """``values`` as a C-contiguous array of ``dtype`` (a copy only if needed), checked by :func:`check_array`."""
    try:
        array: np.ndarray = np.ascontiguousarray(values, dtype=dtype)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name} must be convertible to a {np.dtype(dtype)} array, got {values!r:.200}") from error
    check_array(name, array, shape, dtype)
    return array


# ---------------------------------------------------------------------------------------------------------------------
# Compiled kernel. A lane is a row index into 2-D arrays; each cycle reads the row into scalars, works on them and
# writes them back (no row views, no per-lane allocation). Vector lengths are sqrt(x*x + y*y), as the server's
# Vector2D computes them.
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


@njit(cache=True, error_model="numpy", inline="always")
def norm(x: float, y: float) -> float:
    """Length of the vector (x, y), as the server computes it."""
    return math.sqrt(x * x + y * y)


kickable_radius = njit(cache=True, error_model="numpy", inline="always")(params.kickable_radius)
"""Compiled :func:`robocup_dribble.params.kickable_radius` (player_size + ball_size + kickable_margin)."""


@njit(cache=True, error_model="numpy", inline="always")
def kick_rate(kick_power_rate: float, dir_diff: float, dist_ball: float, kickable_margin: float) -> float:
    """Ball acceleration per unit of kick power (docs/physics.md §3.4): smaller for a ball farther away or off the body axis.

    :param dir_diff: |angle of the ball relative to the body| (rad). :param dist_ball: gap between the surfaces (m).
    """
    return kick_power_rate * (1.0 - 0.25 * dir_diff / math.pi - 0.25 * dist_ball / kickable_margin)


@njit(cache=True, error_model="numpy")
def _noise(r_max: float, u_r: float, u_a: float, box: bool) -> tuple[float, float]:
    """Movement/kick noise of size ``r_max``: polar (v12+, radius uniform) or box (v11), docs/physics.md §5.2 and §3.5."""
    if box:
        return _drand(-r_max, r_max, u_r), _drand(-r_max, r_max, u_a)
    radius = _drand(0.0, r_max, u_r)
    if radius == 0.0:  # no noise (radius * cos(angle) would be a signed zero)
        return 0.0, 0.0
    angle = _drand(-math.pi, math.pi, u_a)
    return radius * math.cos(angle), radius * math.sin(angle)


@njit(cache=True, error_model="numpy", inline="always")
def _leg_accel(power: float, direction: float, body: float, effort: float, dash_power_rate: float, k: np.ndarray):
    """Acceleration of a dash (or of one leg) with effective power ``power`` (docs/physics.md §2.3; direction rate §2.2)."""
    rate = 1.0
    if k[K_DASH_DIRECTION] > 0.5:
        d = abs(direction)
        side, back = k[K_SIDE_DASH_RATE], k[K_BACK_DASH_RATE]
        rate = side + (1.0 - side) * (1.0 - d / 90.0) if d <= 90.0 else back - (back - side) * (1.0 - (d - 90.0) / 90.0)
        rate = min(max(rate, 0.0), 1.0)
    magnitude = abs(effort * power * rate * dash_power_rate)
    heading = body + math.radians(direction)
    sign = 1.0 if power >= 0.0 else -1.0
    return sign * magnitude * math.cos(heading), sign * magnitude * math.sin(heading)


@njit(cache=True, error_model="numpy", inline="always")
def _dash(power, direction, body, pvx, pvy, stamina, effort, dash_power_rate, player_size, extra_stamina, u_turn, k):
    """A dash: the player's acceleration (x, y), its body and its stamina after the dash (docs/physics.md §2.3, §2.4)."""
    power = min(max(power, k[K_MIN_DASH_POWER]), k[K_MAX_DASH_POWER])
    if k[K_DASH_DIRECTION] > 0.5:
        direction = min(max(direction, k[K_MIN_DASH_ANGLE]), k[K_MAX_DASH_ANGLE])
        step = k[K_DASH_ANGLE_STEP]
        if step > EPS:
            direction = step * np.rint(direction / step)  # rint: halves to even, like the server
    else:
        direction = 0.0
    available = stamina + extra_stamina

    if k[K_BIPEDAL] < 0.5:  # one leg (v18 and earlier, docs/physics.md §2.3)
        cost = power if power >= 0.0 else -2.0 * power
        cost = min(cost, available)
        effective = cost if power >= 0.0 else -0.5 * cost
        ax, ay = _leg_accel(effective, direction, body, effort, dash_power_rate, k)
        return ax, ay, body, max(0.0, stamina - cost)

    # v19: both legs get (power, direction); the cost split quirk rotates the body when stamina is short (docs/physics.md §2.4)
    leg_cost = 0.5 * power if power >= 0.0 else -power
    total = 2.0 * leg_cost
    if total < 1e-5:
        return 0.0, 0.0, body, stamina
    cost = min(total, available)
    left_cost = cost * leg_cost / total
    right_cost = cost * leg_cost / (left_cost + leg_cost)  # the server uses the already-updated left share
    if power >= 0.0:
        left_power, right_power = 2.0 * left_cost, 2.0 * right_cost
    else:
        left_power, right_power = -left_cost, -right_cost
    left_power = min(max(left_power, k[K_MIN_DASH_POWER]), k[K_MAX_DASH_POWER])
    right_power = min(max(right_power, k[K_MIN_DASH_POWER]), k[K_MAX_DASH_POWER])
    lx, ly = _leg_accel(left_power, direction, body, effort, dash_power_rate, k)
    rx, ry = _leg_accel(right_power, direction, body, effort, dash_power_rate, k)
    ux, uy = math.cos(body), math.sin(body)
    omega = (ux * (pvx + lx) + uy * (pvy + ly) - ux * (pvx + rx) - uy * (pvy + ry)) / (2.0 * player_size)
    rand = k[K_PLAYER_RAND]
    body = normalize_angle(body + (1.0 + _drand(-rand, rand, u_turn)) * omega)
    return 0.5 * (lx + rx), 0.5 * (ly + ry), body, max(0.0, stamina - cost)


@njit(cache=True, error_model="numpy", inline="always")
def _nearest_post(x: float, y: float, goal_width: float) -> tuple[float, float]:
    """The centre of the goal post the server tests an object at (x, y) against: the one in its quadrant."""
    cx = PITCH_HALF_LENGTH - GOAL_POST_RADIUS
    cy = 0.5 * goal_width + GOAL_POST_RADIUS
    return (cx if x > 0.0 else -cx), (cy if y > 0.0 else -cy)


@njit(cache=True, error_model="numpy", inline="always")
def _angle(x: float, y: float) -> float:
    """The direction of (x, y) in radians; 0 for the zero vector (the server's ``PVector::th``)."""
    return 0.0 if x == 0.0 and y == 0.0 else math.atan2(y, x)


@njit(cache=True, error_model="numpy", inline="always")
def _between(px: float, py: float, bx: float, by: float, ex: float, ey: float) -> bool:
    """The server's ``PVector::between``: p lies in the box spanned by b and e (ordered by x first)."""
    if bx > ex:
        bx, by, ex, ey = ex, ey, bx, by
    if not bx <= px <= ex:
        return False
    return by <= py <= ey if by < ey else by >= py >= ey


@njit(cache=True, error_model="numpy")
def _intersect(bx, by, ex, ey, cx, cy, radius):
    """Where the segment b -> e first enters the circle (c, radius), as the server's ``intersect`` decides it
    (docs/physics.md §6.3): returns (hit, x, y)."""
    if bx == ex and by == ey:
        return False, 0.0, 0.0
    if norm(bx - ex, by - ey) < norm(bx - cx, by - cy) - radius:  # too short to reach the circle
        return False, 0.0, 0.0
    bx, by, ex, ey = bx - cx, by - cy, ex - cx, ey - cy  # the circle at the origin
    dx, dy = ex - bx, ey - by
    dr2 = dx * dx + dy * dy
    d = bx * ey - ex * by
    discriminant = radius * radius * dr2 - d * d
    if discriminant <= 0.0:  # misses or touches
        return False, 0.0, 0.0
    root = math.sqrt(discriminant)
    x1, x2 = (d * dy + dx * root) / dr2, (d * dy - dx * root) / dr2
    y1, y2 = (-d * dx + abs(dy) * root) / dr2, (-d * dx - abs(dy) * root) / dr2
    fx, fy, sx, sy = (x2, y1, x1, y2) if dy < 0.0 else (x1, y1, x2, y2)
    first_in, second_in = _between(fx, fy, bx, by, ex, ey), _between(sx, sy, bx, by, ex, ey)
    if not first_in and not second_in:
        return False, 0.0, 0.0
    if not first_in or (second_in and norm(bx - sx, by - sy) <= norm(bx - fx, by - fy)):
        ix, iy, ox, oy = sx, sy, fx, fy
    else:
        ix, iy, ox, oy = fx, fy, sx, sy
    if ix == bx and iy == by and not _between(ox, oy, bx, by, ex, ey):  # tangent and moving away
        return False, 0.0, 0.0
    return True, ix + cx, iy + cy


@njit(cache=True, error_model="numpy")
def _bounce_off_posts(x, y, vx, vy, size, goal_width, u):
    """Goal posts inside ``MPObject::_inc`` (docs/physics.md §6.3) for an object of radius ``size`` at (x, y) about to
    move by (vx, vy): pushed out of a post it overlaps, then reflected elastically where its path meets one.

    Returns (collided with a post, x, y, vx, vy, end x, end y): the velocity keeps its length and takes the
    reflected heading; (end x, end y) is where the object ends this cycle.
    """
    radius = GOAL_POST_RADIUS + size
    cx, cy = _nearest_post(x, y, goal_width)
    collided = False
    for _ in range(8):  # inside a post: onto its edge (the server loops until outside every post; one push does it)
        if norm(x - cx, y - cy) >= radius:
            break
        collided = True
        dx, dy = x - cx, y - cy
        if dx == 0.0 and dy == 0.0:
            angle = _drand(-math.pi, math.pi, u)
            dx, dy = radius * math.cos(angle), radius * math.sin(angle)
        else:
            scale = radius / max(norm(dx, dy), EPS)
            dx, dy = dx * scale, dy * scale
        x, y = cx + dx, cy + dy
        while norm(x - cx, y - cy) < radius:  # rounding left it inside: 1 % further out
            length = norm(dx, dy)
            scale = length * 1.01 / max(length, EPS)
            dx, dy = dx * scale, dy * scale
            x, y = cx + dx, cy + dy
        if vx != 0.0 or vy != 0.0:  # mirror the velocity's component along the line to the centre
            a = _angle(cx - x, cy - y)
            ca, sa = math.cos(a), math.sin(a)
            along, across = vx * ca + vy * sa, -vx * sa + vy * ca
            vx, vy = -along * ca - across * sa, -along * sa + across * ca
        cx, cy = _nearest_post(x, y, goal_width)
    ex, ey = x + vx, y + vy
    sx, sy = _nearest_post(ex, ey, goal_width)
    for _ in range(8):  # the path meets a post: bounce, and test the rest of the path again (the server: no bound)
        if x == ex and y == ey:
            break
        hit, ix, iy = _intersect(x, y, ex, ey, cx, cy, radius)
        hx, hy = cx, cy
        if not hit and (sx != cx or sy != cy):
            hit, ix, iy = _intersect(x, y, ex, ey, sx, sy, radius)
            hx, hy = sx, sy
        if not hit:
            break
        collided = True
        rx, ry = ex - ix, ey - iy  # the rest of the path, reflected about the line to the post's centre
        a = _angle(hx - ix, hy - iy)
        # the server moves the contact point EPS away from the post, adding 180 to an angle in radians
        x, y = ix + EPS * math.cos(a + 180.0), iy + EPS * math.sin(a + 180.0)
        ca, sa = math.cos(a), math.sin(a)
        along, across = rx * ca + ry * sa, -rx * sa + ry * ca
        rx, ry = -along * ca - across * sa, -along * sa + across * ca
        ex, ey = x + rx, y + ry
        cx, cy = _nearest_post(x, y, goal_width)
        sx, sy = _nearest_post(ex, ey, goal_width)
        speed, heading = norm(vx, vy), _angle(rx, ry)
        vx, vy = speed * math.cos(heading), speed * math.sin(heading)
    return collided, x, y, vx, vy, ex, ey


@njit(cache=True, error_model="numpy")
def _move(x, y, vx, vy, ax, ay, accel_max, speed_max, rand, decay, u_r, u_a, box, size, goal_width, u_post):
    """``MPObject::_inc`` (docs/physics.md §5.1, goal posts §6.3) for an object of radius ``size``: returns whether it
    collided with a goal post, the new position and the velocity after decay."""
    if ax != 0.0 or ay != 0.0:  # both caps are skipped when there is no acceleration
        a = norm(ax, ay)
        if a > accel_max:
            ax, ay = ax * accel_max / a, ay * accel_max / a
        vx, vy = vx + ax, vy + ay
        v = norm(vx, vy)
        if v > speed_max:
            vx, vy = vx * speed_max / v, vy * speed_max / v
    nx, ny = _noise(rand * norm(vx, vy), u_r, u_a, box)
    vx, vy = vx + nx, vy + ny
    ex, ey = x + vx, y + vy
    posted = False
    if max(abs(x), abs(ex)) >= PITCH_HALF_LENGTH - 2.0 * GOAL_POST_RADIUS - size:  # a goal post may be in reach
        posted, x, y, vx, vy, ex, ey = _bounce_off_posts(x, y, vx, vy, size, goal_width, u_post)
    return posted, ex, ey, decay * vx, decay * vy


@njit(cache=True, error_model="numpy")
def _collide(px, py, bx, by, reach, u):
    """Resolve a ball-player overlap by the midpoint push-out (docs/physics.md §6.1): returns (collided, px, py, bx, by)."""
    collided = False
    for _ in range(10):
        dx, dy = bx - px, by - py
        distance = norm(dx, dy)
        if distance >= reach:
            break
        collided = True
        mx, my = 0.5 * (bx + px), 0.5 * (by + py)
        if 0.5 * distance < EPS:  # coincident: separate in a random direction
            angle = _drand(-math.pi, math.pi, u)
            ex, ey = math.cos(angle), math.sin(angle)
        else:
            ex, ey = dx / distance, dy / distance
        push = 0.5 * reach + EPS
        for _grow in range(10):  # rounding may leave them overlapping: grow the offsets by 0.01 %
            bx, by = mx + ex * push, my + ey * push
            px, py = mx - ex * push, my - ey * push
            if norm(bx - px, by - py) >= reach:
                break
            push *= 1.0001
    return collided, px, py, bx, by


@njit(cache=True, error_model="numpy", inline="always")
def recover_lane(state: np.ndarray, i: int, types: np.ndarray, ti: int, k: np.ndarray) -> None:
    """The server's ``(recover)`` of lane ``i`` (type row ``ti``): full stamina and capacity, recovery at its initial
    value, effort at the type's maximum (docs/physics.md §2.5)."""
    state[i, S_STAMINA] = k[K_STAMINA_MAX]
    state[i, S_RECOVERY] = k[K_RECOVER_INIT]
    state[i, S_EFFORT] = types[ti, T_EFFORT_MAX]
    state[i, S_CAPACITY] = k[K_STAMINA_CAPACITY]


@njit(cache=True, error_model="numpy")
def _recover_lanes(state, types, lanes, k) -> None:
    for i in lanes:
        recover_lane(state, i, types, i, k)


@njit(cache=True, error_model="numpy", inline="always")
def _tackle(px, py, body, bx, by, bvx, bvy, direction, kick_rand, u_success, u_r, u_a, k):
    """A tackle (docs/physics.md §3.7, the v12+ model): the ball's acceleration (x, y), noise included, or (0, 0)
    when it fails (ball out of reach, behind, or the success draw ``u_success`` above the success probability)."""
    c, s = math.cos(-body), math.sin(-body)
    rx, ry = bx - px, by - py
    lx, ly = rx * c - ry * s, rx * s + ry * c  # the ball in the player's body frame
    reach = k[K_TACKLE_DIST] if lx > 0.0 else k[K_TACKLE_BACK_DIST]
    if abs(reach) <= 1e-5:
        return 0.0, 0.0
    exponent = k[K_TACKLE_EXPONENT]
    fail = (abs(lx) / reach) ** exponent + (abs(ly) / k[K_TACKLE_WIDTH]) ** exponent
    if fail >= 1.0 or u_success >= 1.0 - fail:
        return 0.0, 0.0
    angle = math.radians(min(max(direction, k[K_MIN_MOMENT]), k[K_MAX_MOMENT]))
    back, front = k[K_MAX_BACK_TACKLE_POWER], k[K_MAX_TACKLE_POWER]
    power = (back + (front - back) * (1.0 - abs(angle) / math.pi)) * k[K_TACKLE_POWER_RATE]
    power *= 1.0 - 0.5 * abs(_angle(lx, ly)) / math.pi
    ax, ay = power * math.cos(angle + body), power * math.sin(angle + body)
    position_rate = 0.5 + 0.5 * (1.0 - fail)
    speed_rate = 0.5 + 0.5 * norm(bvx, bvy) / (k[K_BALL_SPEED_MAX] * k[K_BALL_DECAY])
    nx, ny = _noise(kick_rand * k[K_TACKLE_RAND_FACTOR] * (position_rate + speed_rate), u_r, u_a, False)
    return ax + nx, ay + ny


@njit(cache=True, error_model="numpy", inline="always")
def cycle(state, i, types, ti, kind, power, direction, uniforms, ui, k):
    """One server cycle of lane ``i`` of ``state`` with the type in row ``ti`` of ``types`` and the draws in row ``ui``
    of ``uniforms``, given the lane's command (``CMD_*`` kind, power or turn moment, direction in degrees). A frozen
    player's command is refused (docs/physics.md §3.7).

    :return: (a ball-player collision happened, a kick was accepted, the player collided with a goal post).
    """
    px, py, pvx, pvy, body = state[i, P_X], state[i, P_Y], state[i, P_VX], state[i, P_VY], state[i, P_BODY]
    bx, by, bvx, bvy = state[i, B_X], state[i, B_Y], state[i, B_VX], state[i, B_VY]
    stamina, effort, recovery, capacity = state[i, S_STAMINA], state[i, S_EFFORT], state[i, S_RECOVERY], state[i, S_CAPACITY]
    frozen = state[i, S_FROZEN]
    player_size, margin, ball_size = types[ti, T_SIZE], types[ti, T_KICKABLE_MARGIN], k[K_BALL_SIZE]
    box = k[K_BOX_NOISE] > 0.5
    ball_ax = ball_ay = player_ax = player_ay = 0.0
    kick_ok = False
    if frozen > 0.0:
        kind = CMD_NONE

    # 1. the command
    if kind == CMD_TACKLE:
        frozen = k[K_TACKLE_CYCLES]
        ball_ax, ball_ay = _tackle(
            px,
            py,
            body,
            bx,
            by,
            bvx,
            bvy,
            direction,
            types[ti, T_KICK_RAND],
            uniforms[ui, U_TURN],
            uniforms[ui, U_KICK_R],
            uniforms[ui, U_KICK_A],
            k,
        )
    elif kind == CMD_KICK:  # docs/physics.md §3: the ball accelerates at command time
        power = min(max(power, k[K_MIN_POWER]), k[K_MAX_POWER])
        kick_direction = math.radians(min(max(direction, k[K_MIN_MOMENT]), k[K_MAX_MOMENT]))
        rx, ry = bx - px, by - py
        distance = norm(rx, ry)
        reach = kickable_radius(player_size, ball_size, margin)
        if distance * distance <= reach * reach:
            kick_ok = True
            dir_diff = abs(normalize_angle(math.atan2(ry, rx) - body))
            dist_ball = distance - player_size - ball_size
            effective = power * kick_rate(types[ti, T_KICK_POWER_RATE], dir_diff, dist_ball, margin)
            ball_ax = effective * math.cos(body + kick_direction)
            ball_ay = effective * math.sin(body + kick_direction)
            if box:  # v11: box of half-width kick_rand * power / max_power
                max_rand = types[ti, T_KICK_RAND] * power / k[K_MAX_POWER]
            else:  # v12+: grows with the ball's distance, angle and speed
                pos_rate = 0.5 + 0.25 * (dir_diff / math.pi + dist_ball / margin)
                speed_rate = 0.5 + 0.5 * norm(bvx, bvy) / (k[K_BALL_SPEED_MAX] * k[K_BALL_DECAY])
                max_rand = types[ti, T_KICK_RAND] * (power / k[K_MAX_POWER]) * (pos_rate + speed_rate)
            nx, ny = _noise(max_rand, uniforms[ui, U_KICK_R], uniforms[ui, U_KICK_A], box)
            ball_ax, ball_ay = ball_ax + nx, ball_ay + ny
    elif kind == CMD_TURN:  # docs/physics.md §4: the moment over (1 + inertia * speed), with noise
        moment = math.radians(min(max(power, k[K_MIN_MOMENT]), k[K_MAX_MOMENT]))
        rand = k[K_PLAYER_RAND]
        turned = (1.0 + _drand(-rand, rand, uniforms[ui, U_TURN])) * moment / (1.0 + types[ti, T_INERTIA] * norm(pvx, pvy))
        body = normalize_angle(body + turned)
    elif kind == CMD_DASH:
        player_ax, player_ay, body, stamina = _dash(
            power,
            direction,
            body,
            pvx,
            pvy,
            stamina,
            effort,
            types[ti, T_DASH_POWER_RATE],
            player_size,
            types[ti, T_EXTRA_STAMINA],
            uniforms[ui, U_TURN],
            k,
        )

    frozen = max(frozen - 1.0, 0.0)  # the step starts by counting the tackle's cycles down

    # 2. movement (docs/physics.md §5)
    _, bx, by, bvx, bvy = _move(
        bx,
        by,
        bvx,
        bvy,
        ball_ax,
        ball_ay,
        k[K_BALL_ACCEL_MAX],
        k[K_BALL_SPEED_MAX],
        k[K_BALL_RAND],
        k[K_BALL_DECAY],
        uniforms[ui, U_BALL_R],
        uniforms[ui, U_BALL_A],
        box,
        ball_size,
        k[K_GOAL_WIDTH],
        uniforms[ui, U_COLLIDE],
    )
    posted, px, py, pvx, pvy = _move(
        px,
        py,
        pvx,
        pvy,
        player_ax,
        player_ay,
        k[K_PLAYER_ACCEL_MAX],
        types[ti, T_SPEED_MAX],
        k[K_PLAYER_RAND],
        types[ti, T_DECAY],
        uniforms[ui, U_PLAYER_R],
        uniforms[ui, U_PLAYER_A],
        box,
        player_size,
        k[K_GOAL_WIDTH],
        uniforms[ui, U_COLLIDE],
    )

    # 3. collision (docs/physics.md §6.1): push apart, both velocities times -0.1
    collided, px, py, bx, by = _collide(px, py, bx, by, ball_size + player_size, uniforms[ui, U_COLLIDE])
    if collided:
        bvx, bvy, pvx, pvy = -0.1 * bvx, -0.1 * bvy, -0.1 * pvx, -0.1 * pvy

    # 4. Player::updateStamina (docs/physics.md §2.5): recovery and effort decay, effort rise, stamina recovery and capacity
    stamina_max = k[K_STAMINA_MAX]
    if stamina <= k[K_RECOVER_DEC_THR] * stamina_max:
        recovery = max(k[K_RECOVER_MIN], recovery - k[K_RECOVER_DEC])
    if stamina <= k[K_EFFORT_DEC_THR] * stamina_max:
        effort = max(types[ti, T_EFFORT_MIN], effort - k[K_EFFORT_DEC])
    rise_threshold = k[K_EFFORT_DEC_THR] if k[K_EFFORT_BUG] > 0.5 else k[K_EFFORT_INC_THR]
    if stamina >= rise_threshold * stamina_max:
        effort = min(types[ti, T_EFFORT_MAX], effort + k[K_EFFORT_INC])
    increase = min(recovery * types[ti, T_STAMINA_INC_MAX], stamina_max - stamina)
    has_capacity = k[K_STAMINA_CAPACITY] >= 0.0
    if has_capacity:
        increase = min(increase, capacity)
        capacity = max(0.0, capacity - increase)
    stamina = min(stamina_max, stamina + increase)

    state[i, P_X], state[i, P_Y], state[i, P_VX], state[i, P_VY], state[i, P_BODY] = px, py, pvx, pvy, body
    state[i, B_X], state[i, B_Y], state[i, B_VX], state[i, B_VY] = bx, by, bvx, bvy
    state[i, S_STAMINA], state[i, S_EFFORT], state[i, S_RECOVERY], state[i, S_CAPACITY] = stamina, effort, recovery, capacity
    state[i, S_FROZEN] = frozen
    return collided, kick_ok, posted


@njit(cache=True, error_model="numpy")
def step_lane(s: np.ndarray, t: np.ndarray, c: np.ndarray, u: np.ndarray, k: np.ndarray, events: np.ndarray) -> None:
    """:func:`cycle` for one lane given as vectors (a state row, a type row, a command, its draws); writes ``events``."""
    collided, kick_ok, posted = cycle(
        s.reshape((1, STATE_SIZE)),
        0,
        t.reshape((1, TYPE_SIZE)),
        0,
        int(c[C_KIND]),
        c[C_POWER],
        c[C_DIRECTION],
        u.reshape((1, N_UNIFORMS)),
        0,
        k,
    )
    events[E_COLLISION], events[E_KICK_OK], events[E_POST] = collided, kick_ok, posted


@njit(cache=True, error_model="numpy")
def _step_lanes(state, types, commands, uniforms, k, events) -> None:
    for i in range(state.shape[0]):
        events[i, E_COLLISION], events[i, E_KICK_OK], events[i, E_POST] = cycle(
            state, i, types, i, int(commands[i, C_KIND]), commands[i, C_POWER], commands[i, C_DIRECTION], uniforms, i, k
        )
