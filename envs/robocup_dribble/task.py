"""The dribbling task on top of the physics: observation, reward, termination and the start of an episode.

The paper (Uc-Cetina 2013, §4) fixes the structure; the constants it used were lost, so ours are chosen by us and
are all fields of :class:`DribbleTask` (constructor arguments of the envs):

* **Observation**, 10 variables: the player type's decay, dash power rate, kickable margin and kick rand; the ball's
  position and velocity relative to the player (x, y); the player's velocity (x, y). Field axes: x toward the
  opponent goal (the running direction), y down the monitor.
* **Reward**, the first case that applies: the ball got in the player's way (a ball-player collision this cycle)
  ``in_the_way_penalty``; else the ball is at the border of the kickable area (within ``border_width`` of its edge,
  or beyond it) ``border_penalty``; else the ball is so close it may collide (within ``close_margin`` of touching)
  ``too_close_penalty``; else ``progress_weight`` times the metres the player advanced along +x this cycle.
* **Termination** when the ball leaves the kickable area; **truncation** after ``max_actions`` actions.
* **Start**: the player at the centre spot facing +x with a velocity of random direction and a speed uniform in
  [0, ``start_player_speed``]; the ball uniform over the ring between ``start_clearance`` outside touching and
  ``start_clearance`` inside the kickable edge, with the player's velocity plus a random one of speed uniform in
  [0, ``start_ball_speed``].

The compiled per-lane functions (:func:`start_lane`, :func:`evaluate`, :func:`observe`) are building blocks for the
compiled loop of :mod:`robocup_dribble.lanes` and do no checks; Python code starts and steps lanes through
:class:`robocup_dribble.lanes.DribbleLanes`, which checks its inputs first.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces
from numba import njit

from robocup_dribble import physics
from robocup_dribble.params import ServerProfile
from robocup_dribble.player_types import next_uniform

OBSERVATION_NAMES = (
    "player_decay",
    "dash_power_rate",
    "kickable_margin",
    "kick_rand",
    "ball_rel_x",
    "ball_rel_y",
    "ball_rel_vx",
    "ball_rel_vy",
    "player_vx",
    "player_vy",
)
"""The observation's columns; the ``O_*`` constants are their indices."""
(
    O_PLAYER_DECAY, O_DASH_POWER_RATE, O_KICKABLE_MARGIN, O_KICK_RAND,
    O_BALL_REL_X, O_BALL_REL_Y, O_BALL_REL_VX, O_BALL_REL_VY, O_PLAYER_VX, O_PLAYER_VY,
) = (OBSERVATION_NAMES.index(name) for name in OBSERVATION_NAMES)  # fmt: skip
N_OBSERVATIONS = len(OBSERVATION_NAMES)


@dataclass(frozen=True)
class DribbleTask:
    """Episode, reward and start settings of the dribbling task (chosen by us where the paper is silent).

    :param max_actions: actions (server cycles) per episode before truncation; the paper's 35.
    :param episodes_per_type_set: a new set of player types is drawn every this many episodes of a lane, and each
        episode of a set uses a different type of it (the paper: 7 episodes, 7 types).
    :param progress_weight: reward per metre advanced along +x; the paper's "weight parameter" 50.
    :param in_the_way_penalty: reward when the ball collides with the player.
    :param border_penalty: reward when the ball is within ``border_width`` of the kickable edge, or lost.
    :param too_close_penalty: reward when the ball is within ``close_margin`` of touching the player.
    :param border_width: width in metres of the kickable area's border zone.
    :param close_margin: metres between ball and player surfaces below which the ball is "too close".
    :param start_player_speed: largest initial player speed (m/cycle, as reported after decay).
    :param start_ball_speed: largest initial ball speed relative to the player (m/cycle).
    :param start_clearance: metres the initial ball keeps from touching the player and from the kickable edge.
    """

    max_actions: int = 35
    episodes_per_type_set: int = 7
    progress_weight: float = 50.0
    in_the_way_penalty: float = -10.0
    border_penalty: float = -10.0
    too_close_penalty: float = -5.0
    border_width: float = 0.1
    close_margin: float = 0.1
    start_player_speed: float = 0.3
    start_ball_speed: float = 0.1
    start_clearance: float = 0.1

    def __post_init__(self) -> None:
        for name in ("max_actions", "episodes_per_type_set"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if not math.isfinite(value):
                raise ValueError(f"{field.name} must be finite, got {value!r}")
        for name in ("border_width", "close_margin", "start_player_speed", "start_ball_speed", "start_clearance"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")

    def constants(self) -> np.ndarray:
        """The settings as the vector the compiled kernel reads (:data:`TASK_FIELDS` order)."""
        return np.array([getattr(self, name) for name in TASK_FIELDS], dtype=np.float64)


TASK_FIELDS = tuple(field.name for field in dataclasses.fields(DribbleTask))
"""The layout of :meth:`DribbleTask.constants`: every field, in declaration order."""
(
    R_MAX_ACTIONS, R_EPISODES_PER_TYPE_SET, R_PROGRESS_WEIGHT, R_IN_THE_WAY_PENALTY, R_BORDER_PENALTY, R_TOO_CLOSE_PENALTY,
    R_BORDER_WIDTH, R_CLOSE_MARGIN, R_START_PLAYER_SPEED, R_START_BALL_SPEED, R_START_CLEARANCE,
) = (TASK_FIELDS.index(name) for name in TASK_FIELDS)  # fmt: skip


def observation_space(profile: ServerProfile, task: DribbleTask) -> spaces.Box:
    """The 10-variable Box with bounds every observation under ``profile`` respects.

    Type parameters span the profile's heterogeneous ranges (docs/physics.md §7.3). Velocities are bounded by the speed caps
    plus the largest movement noise, after decay. The relative ball position of a non-terminal step lies inside the
    largest kickable area; the bound adds 0.25 m, and a terminal observation (ball lost) is clipped to it.
    """
    s, p = profile.server, profile.player

    def spread(base: float, low_delta: float, high_delta: float, factor: float = 1.0) -> tuple[float, float]:
        values = (base, base + factor * low_delta, base + factor * high_delta)
        return min(values), max(values)

    decay = spread(s.player_decay, p.player_decay_delta_min, p.player_decay_delta_max)
    dash_power_rate = spread(s.dash_power_rate, p.new_dash_power_rate_delta_min, p.new_dash_power_rate_delta_max)
    margin = spread(s.kickable_margin, p.kickable_margin_delta_min, p.kickable_margin_delta_max)
    kick_rand = spread(s.kick_rand, p.kickable_margin_delta_min, p.kickable_margin_delta_max, p.kick_rand_delta_factor)
    kick_rand = (max(0.0, kick_rand[0]), max(0.0, kick_rand[1]))
    reach = physics.kickable_radius(s.player_size, s.ball_size, margin[1]) + 0.25
    ball_speed = max(
        s.ball_speed_max * (1 + math.sqrt(2) * s.ball_rand) * s.ball_decay, task.start_player_speed + task.start_ball_speed
    )
    player_speed = max(s.player_speed_max * (1 + math.sqrt(2) * s.player_rand) * decay[1], task.start_player_speed)
    relative_speed = ball_speed + player_speed
    bounds = {
        "player_decay": decay, "dash_power_rate": dash_power_rate, "kickable_margin": margin, "kick_rand": kick_rand,
        "ball_rel_x": (-reach, reach), "ball_rel_y": (-reach, reach),
        "ball_rel_vx": (-relative_speed, relative_speed), "ball_rel_vy": (-relative_speed, relative_speed),
        "player_vx": (-player_speed, player_speed), "player_vy": (-player_speed, player_speed),
    }  # fmt: skip
    low = [bounds[name][0] for name in OBSERVATION_NAMES]
    high = [bounds[name][1] for name in OBSERVATION_NAMES]
    low_array, high_array = np.array(low), np.array(high)
    with np.errstate(over="ignore", invalid="ignore"):  # too large settings are refused below
        pad = 1e-6 * np.maximum(1.0, np.abs(high_array - low_array))  # float32 rounding must not leave the box
        low32, high32 = (low_array - pad).astype(np.float32), (high_array + pad).astype(np.float32)
    finite = np.isfinite(low32) & np.isfinite(high32)
    if not finite.all():
        names = [name for name, ok in zip(OBSERVATION_NAMES, finite, strict=True) if not ok]
        raise ValueError(
            f"the settings give observation bounds beyond float32 for {names}; the start speeds and the profile's sizes, "
            f"speeds and type ranges must stay far below {float(np.finfo(np.float32).max):.3g}"
        )
    return spaces.Box(low32, high32, dtype=np.float32)


@njit(cache=True, error_model="numpy", inline="always")
def _polar(radius: float, unit_angle: float) -> tuple[float, float]:
    """The vector of length ``radius`` at the angle ``2 pi unit_angle - pi``."""
    angle = 2.0 * math.pi * unit_angle - math.pi
    return radius * math.cos(angle), radius * math.sin(angle)


@njit(cache=True, error_model="numpy", inline="always")
def start_lane(state, i, types, ti, uniforms, position, c, k) -> None:
    """Place player and ball of lane ``i`` (type row ``ti``) at the start of an episode and recover the player.

    Takes six uniforms from ``uniforms`` at ``position`` (:func:`robocup_dribble.player_types.next_uniform`) in this
    order: the ball's radius (uniform over the ring's area), the player's speed
    and direction, the ball's extra speed and its direction, the ball's position angle.

    :param c: :meth:`DribbleTask.constants`. :param k: :func:`robocup_dribble.physics.profile_constants`.
    """
    for j in range(physics.STATE_SIZE):
        state[i, j] = 0.0
    touching = types[ti, physics.T_SIZE] + k[physics.K_BALL_SIZE]
    clearance = c[R_START_CLEARANCE]
    inner = touching + clearance
    outer = max(inner, touching + types[ti, physics.T_KICKABLE_MARGIN] - clearance)
    radius = math.sqrt(inner**2 + (outer**2 - inner**2) * next_uniform(uniforms, position))
    player_speed = c[R_START_PLAYER_SPEED] * next_uniform(uniforms, position)
    pvx, pvy = _polar(player_speed, next_uniform(uniforms, position))
    ball_speed = c[R_START_BALL_SPEED] * next_uniform(uniforms, position)
    dvx, dvy = _polar(ball_speed, next_uniform(uniforms, position))
    state[i, physics.P_VX], state[i, physics.P_VY] = pvx, pvy
    state[i, physics.B_VX], state[i, physics.B_VY] = pvx + dvx, pvy + dvy
    state[i, physics.B_X], state[i, physics.B_Y] = _polar(radius, next_uniform(uniforms, position))
    physics.recover_lane(state, i, types, ti, k)


@njit(cache=True, error_model="numpy", inline="always")
def evaluate(state, i, types, ti, collided: bool, previous_x: float, c, k) -> tuple[float, bool]:
    """Reward and ball loss of lane ``i`` after a cycle in which the player was at ``previous_x`` before.

    :param collided: a ball-player collision happened in the cycle.
    """
    rx, ry = state[i, physics.B_X] - state[i, physics.P_X], state[i, physics.B_Y] - state[i, physics.P_Y]
    gap = physics.norm(rx, ry)
    touching = types[ti, physics.T_SIZE] + k[physics.K_BALL_SIZE]
    reach = physics.kickable_radius(types[ti, physics.T_SIZE], k[physics.K_BALL_SIZE], types[ti, physics.T_KICKABLE_MARGIN])
    if collided:
        reward = c[R_IN_THE_WAY_PENALTY]
    elif gap > reach - c[R_BORDER_WIDTH]:
        reward = c[R_BORDER_PENALTY]
    elif gap < touching + c[R_CLOSE_MARGIN]:
        reward = c[R_TOO_CLOSE_PENALTY]
    else:
        reward = c[R_PROGRESS_WEIGHT] * (state[i, physics.P_X] - previous_x)
    return reward, gap > reach


@njit(cache=True, error_model="numpy", inline="always")
def observe(state, i, types, ti, low, high, obs, oi) -> None:
    """Write lane ``i``'s observation (:data:`OBSERVATION_NAMES`, clipped to [low, high]) into row ``oi`` of ``obs``."""
    obs[oi, O_PLAYER_DECAY] = min(max(types[ti, physics.T_DECAY], low[O_PLAYER_DECAY]), high[O_PLAYER_DECAY])
    dpr, margin = O_DASH_POWER_RATE, O_KICKABLE_MARGIN
    obs[oi, dpr] = min(max(types[ti, physics.T_DASH_POWER_RATE], low[dpr]), high[dpr])
    obs[oi, margin] = min(max(types[ti, physics.T_KICKABLE_MARGIN], low[margin]), high[margin])
    obs[oi, O_KICK_RAND] = min(max(types[ti, physics.T_KICK_RAND], low[O_KICK_RAND]), high[O_KICK_RAND])
    px, py, pvx, pvy = state[i, physics.P_X], state[i, physics.P_Y], state[i, physics.P_VX], state[i, physics.P_VY]
    obs[oi, O_BALL_REL_X] = min(max(state[i, physics.B_X] - px, low[O_BALL_REL_X]), high[O_BALL_REL_X])
    obs[oi, O_BALL_REL_Y] = min(max(state[i, physics.B_Y] - py, low[O_BALL_REL_Y]), high[O_BALL_REL_Y])
    obs[oi, O_BALL_REL_VX] = min(max(state[i, physics.B_VX] - pvx, low[O_BALL_REL_VX]), high[O_BALL_REL_VX])
    obs[oi, O_BALL_REL_VY] = min(max(state[i, physics.B_VY] - pvy, low[O_BALL_REL_VY]), high[O_BALL_REL_VY])
    obs[oi, O_PLAYER_VX] = min(max(pvx, low[O_PLAYER_VX]), high[O_PLAYER_VX])
    obs[oi, O_PLAYER_VY] = min(max(pvy, low[O_PLAYER_VY]), high[O_PLAYER_VY])
