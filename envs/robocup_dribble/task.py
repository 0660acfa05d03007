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

OBSERVATION_NAMES = (
    "player_decay", "dash_power_rate", "kickable_margin", "kick_rand",
    "ball_rel_x", "ball_rel_y", "ball_rel_vx", "ball_rel_vy", "player_vx", "player_vy",
)


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
        """The reward constants as the vector the compiled kernel reads."""
        return np.array(
            [self.progress_weight, self.in_the_way_penalty, self.border_penalty, self.too_close_penalty,
             self.border_width, self.close_margin],
            dtype=np.float64,
        )


def observation_space(profile: ServerProfile, task: DribbleTask) -> spaces.Box:
    """The 10-variable Box with bounds every observation under ``profile`` respects.

    Type parameters span the profile's heterogeneous ranges (spec §7.3). Velocities are bounded by the speed caps
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
    reach = s.player_size + s.ball_size + margin[1] + 0.25
    ball_speed = max(s.ball_speed_max * (1 + math.sqrt(2) * s.ball_rand) * s.ball_decay, task.start_player_speed + task.start_ball_speed)
    player_speed = max(s.player_speed_max * (1 + math.sqrt(2) * s.player_rand) * decay[1], task.start_player_speed)
    low = [decay[0], dash_power_rate[0], margin[0], kick_rand[0], -reach, -reach]
    high = [decay[1], dash_power_rate[1], margin[1], kick_rand[1], reach, reach]
    low += [-(ball_speed + player_speed)] * 2 + [-player_speed] * 2
    high += [ball_speed + player_speed] * 2 + [player_speed] * 2
    low_array, high_array = np.array(low), np.array(high)
    pad = 1e-6 * np.maximum(1.0, np.abs(high_array - low_array))  # float32 rounding must not leave the box
    return spaces.Box((low_array - pad).astype(np.float32), (high_array + pad).astype(np.float32), dtype=np.float32)


def start_episodes(
    state: np.ndarray, types: np.ndarray, lanes: np.ndarray, profile: ServerProfile, task: DribbleTask, rng: np.random.Generator
) -> None:
    """Place player and ball of the given lanes at the start of an episode (and recover the player's stamina)."""
    s = profile.server
    settings = np.array([task.start_player_speed, task.start_ball_speed, task.start_clearance, s.ball_size, s.stamina_max,
                         s.recover_init, s.stamina_capacity])
    _start_lanes(state, types, lanes, rng.random((len(lanes), 6)), settings)


@njit(cache=True)
def _start_lanes(state, types, lanes, draws, c) -> None:
    player_speed, ball_speed, clearance, ball_size = c[0], c[1], c[2], c[3]
    for row in range(lanes.shape[0]):
        s, t, u = state[lanes[row]], types[lanes[row]], draws[row]
        s[:] = 0.0
        touching = t[physics.T_SIZE] + ball_size
        inner = touching + clearance
        outer = max(inner, touching + t[physics.T_KICKABLE_MARGIN] - clearance)
        radius = math.sqrt(inner**2 + (outer**2 - inner**2) * u[0])  # uniform over the ring's area
        s[physics.P_VX], s[physics.P_VY] = _polar(player_speed * u[1], u[2])
        dvx, dvy = _polar(ball_speed * u[3], u[4])
        s[physics.B_VX], s[physics.B_VY] = s[physics.P_VX] + dvx, s[physics.P_VY] + dvy
        s[physics.B_X], s[physics.B_Y] = _polar(radius, u[5])
        s[physics.S_STAMINA], s[physics.S_RECOVERY], s[physics.S_CAPACITY] = c[4], c[5], c[6]  # the server's (recover)
        s[physics.S_EFFORT] = t[physics.T_EFFORT_MAX]


@njit(cache=True, inline="always")
def _polar(radius: float, unit_angle: float) -> tuple[float, float]:
    angle = 2.0 * math.pi * unit_angle - math.pi
    return radius * math.cos(angle), radius * math.sin(angle)


def evaluate(
    state: np.ndarray,
    types: np.ndarray,
    events: np.ndarray,
    previous_x: np.ndarray,
    start_x: np.ndarray,
    distance: np.ndarray,
    reward_constants: np.ndarray,
    ball_size: float,
    obs_low: np.ndarray,
    obs_high: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Observation, reward and ball loss of every lane after a physics step; updates ``distance`` in place.

    ``distance`` is the metres dribbled along +x since the start of the episode; on the step that loses the ball it
    keeps the value of the last step with the ball.

    :return: ``obs`` ``(N, 10)`` float32, ``reward`` ``(N,)`` float64, ``ball_lost`` ``(N,)`` bool.
    """
    n = state.shape[0]
    obs = np.empty((n, len(OBSERVATION_NAMES)), dtype=np.float32)
    reward = np.empty(n, dtype=np.float64)
    lost = np.empty(n, dtype=np.bool_)
    _evaluate(state, types, events, previous_x, start_x, distance, reward_constants, ball_size, obs_low, obs_high, obs, reward, lost)
    return obs, reward, lost


@njit(cache=True)
def _evaluate(state, types, events, previous_x, start_x, distance, c, ball_size, low, high, obs, reward, lost) -> None:
    for i in range(state.shape[0]):
        reward[i], lost[i] = evaluate_lane(state[i], types[i], events[i], previous_x[i], start_x[i], distance[i:i + 1], c,
                                           ball_size, low, high, obs[i])


@njit(cache=True)
def evaluate_lane(s, t, events, previous_x, start_x, distance, c, ball_size, low, high, obs):
    """Reward and ball loss of one lane; writes its observation into ``obs`` and its distance into ``distance[0]``."""
    weight, in_the_way, border, too_close, border_width, close_margin = c[0], c[1], c[2], c[3], c[4], c[5]
    rx, ry = s[physics.B_X] - s[physics.P_X], s[physics.B_Y] - s[physics.P_Y]
    gap = math.hypot(rx, ry)
    touching = t[physics.T_SIZE] + ball_size
    reach = touching + t[physics.T_KICKABLE_MARGIN]
    lost = gap > reach
    if events[physics.E_COLLISION]:
        reward = in_the_way
    elif gap > reach - border_width:
        reward = border
    elif gap < touching + close_margin:
        reward = too_close
    else:
        reward = weight * (s[physics.P_X] - previous_x)
    if not lost:
        distance[0] = s[physics.P_X] - start_x
    values = (
        t[physics.T_DECAY], t[physics.T_DASH_POWER_RATE], t[physics.T_KICKABLE_MARGIN], t[physics.T_KICK_RAND],
        rx, ry, s[physics.B_VX] - s[physics.P_VX], s[physics.B_VY] - s[physics.P_VY], s[physics.P_VX], s[physics.P_VY],
    )
    for j in range(len(values)):
        obs[j] = min(max(values[j], low[j]), high[j])
    return reward, lost
