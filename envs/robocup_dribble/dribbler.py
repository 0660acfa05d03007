"""A hand-coded dribbler built from the same four skills: the reference a RoboCup team would write instead of learning.

It plans the way a RoboCup agent with a world model does. From the observation it rebuilds the player (at the origin,
facing +x) and the ball, and it simulates the server's own physics, without noise, to choose between dashing now and
kicking now. (The runs of dashes after a kick are computed in closed form; ``tests/test_dribbler.py`` checks them
against the physics kernel.)

Dribbling is a cycle: one kick, then a run of full-power dashes. The kick sends the ball ahead so that it stays in the
kickable area while the player runs after it; when the ball is about to fall behind, the next kick starts the next
cycle. A kick is planned as RoboCup teams plan a dribble kick: choose how many dashes ``n`` follow it and where the ball
should be beside the player when they are done. The player's path (it coasts while it kicks, then dashes) and the
ball's decay then fix the ball velocity the kick must produce, which a ``KICK_VELOCITY`` action asks for. A plan counts
only if the kick is within the player's kick power and, at every cycle of the run, the ball is inside the kickable area
and clear of both its edge and the player's body. For each run length the plan that keeps the most clearance is kept.

The decision looks ahead over a tree. A branch dashes ``m`` times (``m`` = 0 .. ``dash_depth``, as long as the ball
stays safe; a branch may instead start with one dash in another of ``dash_directions`` and kick right after it), then
kicks with the plan for one of the three longest feasible runs, then continues greedily (the longest run each time)
until ``horizon`` cycles have passed. A branch scores the metres it gains along +x per cycle, counting the momentum the
player carries into the next cycle; a branch that loses the ball scores less than any other, more the longer it kept
the ball. The first action of the best branch is played, and the next observation re-plans, which corrects the drift
the server's noise causes.

What the observation does not tell is handled conservatively:

* The player's effort is assumed to be ``effort``. Every plan must also work with the lowest and the highest effort of
  the profile's player types (by default; see ``effort_range``), and a dash must keep the ball inside half the
  clearances below with them.
* The noise is absent from the look-ahead. Instead the ball keeps ``safety`` metres from the kickable edge and
  ``body_safety`` metres from the player's body. After a kick, the edge clearance grows with the kick noise of the
  player's type (``kick_rand``, from the observation, times the share of full power the kick uses), carried along by
  the ball's motion.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from robocup_dribble import physics, skills
from robocup_dribble.params import ServerProfile, make_profile, without_noise
from robocup_dribble.player_types import default_player_type, stack_player_types
from robocup_dribble.task import (
    O_BALL_REL_VX, O_BALL_REL_VY, O_BALL_REL_X, O_BALL_REL_Y, O_DASH_POWER_RATE, O_KICK_RAND, O_KICKABLE_MARGIN,
    O_PLAYER_DECAY, O_PLAYER_VX, O_PLAYER_VY,
)  # fmt: skip

# Where a planned run may leave the ball beside the player: radius as a fraction of the ring between touching and the
# kickable edge, and angle from the running direction (degrees; adding straight ahead and behind changed nothing).
END_RADII = (0.35, 0.65)
END_ANGLES = (-135.0, -90.0, -45.0, 45.0, 90.0, 135.0)
RUNS_TRIED = 3  # a branch's first kick tries the plans of the 3 longest feasible runs (trying more changed nothing)
EXTREME_CLEARANCE = 0.5  # share of the clearances a dash must keep under the lowest and highest effort
LOST = -1e3  # score of a branch that loses the ball (plus the cycles it kept the ball)

# the planner's settings, as one float vector for the compiled code
PLANNER_FIELDS = ("horizon", "max_run", "dash_depth", "safety", "body_safety", "effort_low", "effort_high")
G_HORIZON, G_MAX_RUN, G_DASH_DEPTH, G_EDGE, G_BODY, G_EFFORT_LOW, G_EFFORT_HIGH = (
    PLANNER_FIELDS.index(name) for name in PLANNER_FIELDS
)


class HandCodedDribbler:
    """A dribbling policy over the four skills that looks ahead with kick-and-run plans in the server physics.

    :param profile: the server profile whose physics the look-ahead uses (match the env's).
    :param horizon: the fewest cycles a branch of the look-ahead covers (it ends at the first kick after them).
    :param max_run: the most dashes a planned kick may be followed by.
    :param dash_depth: the most straight dashes a branch tries before its first kick.
    :param dash_directions: directions (deg, relative to the body) the first dash of a branch may take besides 0.
        ``None`` means (±10, ±20) where dashes have a direction (v13+), and none under v11 (there a turned dash is
        only a weaker straight one).
    :param safety: metres the ball keeps from the kickable edge in every planned cycle.
    :param body_safety: metres the ball keeps from touching the player in every planned cycle.
    :param effort: the effort assumed for the player's dashes (the observation does not include it).
    :param effort_range: the lowest and highest effort every plan must also cope with. ``None`` means the range of
        the profile's player types. It is widened to include ``effort``.
    """

    def __init__(
        self,
        profile: str | ServerProfile = "v19",
        horizon: int = 12,
        max_run: int = 8,
        dash_depth: int = 3,
        dash_directions: tuple[float, ...] | None = None,
        safety: float = 0.12,
        body_safety: float = 0.03,
        effort: float = 0.9,
        effort_range: tuple[float, float] | None = None,
    ) -> None:
        if horizon < 1 or max_run < 0 or dash_depth < 0:
            raise ValueError(f"need horizon >= 1, max_run >= 0 and dash_depth >= 0, got {horizon}, {max_run} and {dash_depth}")
        server_profile = make_profile(profile)
        self.profile = without_noise(server_profile)
        if dash_directions is None:
            dash_directions = (-20.0, -10.0, 10.0, 20.0) if server_profile.dash_direction else ()
        if effort_range is None:
            player = server_profile.player
            efforts = [
                server_profile.server.effort_init + player.effort_max_delta_factor * delta
                for delta in (player.extra_stamina_delta_min, player.extra_stamina_delta_max)
            ]
            effort_range = (min(efforts), max(efforts))
        effort_range = (min(effort_range[0], effort), max(effort_range[1], effort))
        self.horizon, self.max_run, self.dash_depth = horizon, max_run, dash_depth
        self.dash_directions = tuple(float(d) for d in dash_directions)
        self.safety, self.body_safety = safety, body_safety
        self.effort, self.effort_range = effort, effort_range
        settings = {
            "horizon": horizon,
            "max_run": max_run,
            "dash_depth": dash_depth,
            "safety": safety,
            "body_safety": body_safety,
            "effort_low": effort_range[0],
            "effort_high": effort_range[1],
        }
        self._settings = np.array([settings[name] for name in PLANNER_FIELDS], dtype=np.float64)
        self._directions = np.array([0.0] + [d for d in self.dash_directions if d != 0.0])
        angles = np.radians(END_ANGLES)
        self._ends = np.array([(r, math.cos(a), math.sin(a)) for r in END_RADII for a in angles])
        self._constants = physics.profile_constants(self.profile)
        self._default_type = stack_player_types([default_player_type(self.profile)])[0]

    def act(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Action types ``(n,)`` and parameters ``(n, 7)`` for a batch of observations ``(n, 10)`` (or one ``(10,)``)."""
        obs = np.atleast_2d(np.asarray(obs, dtype=np.float64))
        state, types = self._rebuild(obs)
        kinds = np.empty(obs.shape[0], dtype=np.int64)
        params = np.zeros((obs.shape[0], skills.N_PARAMS))
        kick_rands = obs[:, O_KICK_RAND].copy()
        _plan(state, types, kick_rands, self._constants, self._settings, self._ends, self._directions, kinds, params)
        return kinds, params

    def predict(self, obs: np.ndarray, state: Any = None, episode_start: Any = None, deterministic: bool = True):
        """SB3-style ``predict``: one Tuple action for one observation, an object array of them for a batch."""
        single = np.asarray(obs).ndim == 1
        actions = skills.as_env_actions(*self.act(obs))
        return (actions[0] if single else actions), None

    def _rebuild(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Physics state and player types from observations (player at the origin facing +x, full stamina)."""
        m = obs.shape[0]
        server = self.profile.server
        types = np.tile(self._default_type, (m, 1))
        types[:, physics.T_DECAY] = obs[:, O_PLAYER_DECAY]
        inertia_factor = self.profile.player.inertia_moment_delta_factor
        types[:, physics.T_INERTIA] = server.inertia_moment + (obs[:, O_PLAYER_DECAY] - server.player_decay) * inertia_factor
        types[:, physics.T_DASH_POWER_RATE] = obs[:, O_DASH_POWER_RATE]
        types[:, physics.T_KICKABLE_MARGIN] = obs[:, O_KICKABLE_MARGIN]
        types[:, physics.T_EFFORT_MAX] = self.effort
        state = physics.new_state(m)
        physics.recover(state, types, self.profile)
        state[:, physics.P_VX], state[:, physics.P_VY] = obs[:, O_PLAYER_VX], obs[:, O_PLAYER_VY]
        state[:, physics.B_X], state[:, physics.B_Y] = obs[:, O_BALL_REL_X], obs[:, O_BALL_REL_Y]
        state[:, physics.B_VX] = obs[:, O_BALL_REL_VX] + obs[:, O_PLAYER_VX]
        state[:, physics.B_VY] = obs[:, O_BALL_REL_VY] + obs[:, O_PLAYER_VY]
        return state, types


# ---------------------------------------------------------------------------------------------------------------------
# Compiled planner. Every helper works on one lane; _plan loops over the observations.
# ---------------------------------------------------------------------------------------------------------------------


@njit(cache=True)
def _gap(s: np.ndarray) -> float:
    """Distance between the centres of ball and player."""
    return math.hypot(s[physics.B_X] - s[physics.P_X], s[physics.B_Y] - s[physics.P_Y])


@njit(cache=True)
def _copy(target: np.ndarray, source: np.ndarray) -> None:
    """``target[:] = source`` for equally long vectors, as a loop (a slice assignment compiles much more slowly)."""
    for c in range(target.shape[0]):
        target[c] = source[c]


@njit(cache=True)
def _act(s, t, kind, p, k, command, uniforms, events) -> bool:
    """Play one action on ``s`` (noise-free physics); True if ball and player collided."""
    skills.command_lane(s, t, kind, p, k, command)
    physics.step_lane(s, t, command, uniforms, k, events)
    return events[physics.E_COLLISION]


@njit(cache=True)
def _kick_params(s, vx, vy, p) -> None:
    """KICK_VELOCITY parameters that aim the ball at velocity (vx, vy)."""
    for c in range(p.shape[0]):
        p[c] = 0.0
    p[skills.PARAM_KICK_SPEED] = math.hypot(vx, vy)
    p[skills.PARAM_KICK_DIRECTION] = math.degrees(physics.normalize_angle(math.atan2(vy, vx) - s[physics.P_BODY]))


@njit(cache=True)
def _kick_reach(s, t, k) -> float:
    """The largest ball-velocity change a kick can make in this state (docs/physics.md §3), 0 if the ball is not kickable."""
    rx, ry = s[physics.B_X] - s[physics.P_X], s[physics.B_Y] - s[physics.P_Y]
    distance = math.hypot(rx, ry)
    if distance > physics.kickable_radius(t[physics.T_SIZE], k[physics.K_BALL_SIZE], t[physics.T_KICKABLE_MARGIN]):
        return 0.0
    dir_diff = abs(physics.normalize_angle(math.atan2(ry, rx) - s[physics.P_BODY]))
    dist_ball = distance - t[physics.T_SIZE] - k[physics.K_BALL_SIZE]
    rate = physics.kick_rate(t[physics.T_KICK_POWER_RATE], dir_diff, dist_ball, t[physics.T_KICKABLE_MARGIN])
    return min(rate * k[physics.K_MAX_POWER], k[physics.K_BALL_ACCEL_MAX])


@njit(cache=True)
def _dash_accel(s, t, k, effort) -> tuple[float, float]:
    """The acceleration of a full-power dash along the body with ``effort`` and enough stamina (docs/physics.md §2.3)."""
    accel = min(effort * k[physics.K_MAX_DASH_POWER] * t[physics.T_DASH_POWER_RATE], k[physics.K_PLAYER_ACCEL_MAX])
    return accel * math.cos(s[physics.P_BODY]), accel * math.sin(s[physics.P_BODY])


@njit(cache=True)
def _player_path(s, t, k, n, effort, path) -> None:
    """The player's positions and velocities over a kick cycle (it coasts) then ``n`` full-power dashes along its
    body with ``effort``, without a ball: ``path[m]`` = (x, y, vx, vy) after ``m`` cycles, ``m`` = 0 .. n + 1.

    docs/physics.md §2.3 and §5.1 without noise, with the stamina of the rebuilt state (full, so a dash gets its full power and
    v19's two legs push equally); ``tests/test_dribbler.py`` checks it against :func:`physics.step_lane`.
    """
    ax, ay = _dash_accel(s, t, k, effort)
    speed_max, decay = t[physics.T_SPEED_MAX], t[physics.T_DECAY]
    x, y, vx, vy = s[physics.P_X], s[physics.P_Y], s[physics.P_VX], s[physics.P_VY]
    path[0, 0], path[0, 1], path[0, 2], path[0, 3] = x, y, vx, vy
    x, y, vx, vy = x + vx, y + vy, decay * vx, decay * vy  # the kick cycle: the player coasts
    path[1, 0], path[1, 1], path[1, 2], path[1, 3] = x, y, vx, vy
    for m in range(2, n + 2):
        vx, vy = vx + ax, vy + ay
        speed = math.sqrt(vx * vx + vy * vy)
        if speed > speed_max:
            vx, vy = vx * speed_max / speed, vy * speed_max / speed
        x, y, vx, vy = x + vx, y + vy, decay * vx, decay * vy
        path[m, 0], path[m, 1], path[m, 2], path[m, 3] = x, y, vx, vy


@njit(cache=True)
def _run(s, t, k, n) -> None:
    """Advance ``s`` by ``n`` full-power dashes along the body while the ball rolls freely (no collision, no kick):
    :func:`_player_path`'s dashes, plus the ball (docs/physics.md §5.1: ``p += v``, ``v *= ball_decay``)."""
    ax, ay = _dash_accel(s, t, k, s[physics.S_EFFORT])
    speed_max, decay, ball_decay = t[physics.T_SPEED_MAX], t[physics.T_DECAY], k[physics.K_BALL_DECAY]
    for _ in range(n):
        vx, vy = s[physics.P_VX] + ax, s[physics.P_VY] + ay
        speed = math.sqrt(vx * vx + vy * vy)
        if speed > speed_max:
            vx, vy = vx * speed_max / speed, vy * speed_max / speed
        s[physics.P_X] += vx
        s[physics.P_Y] += vy
        s[physics.P_VX], s[physics.P_VY] = decay * vx, decay * vy
        s[physics.B_X] += s[physics.B_VX]
        s[physics.B_Y] += s[physics.B_VY]
        s[physics.B_VX] *= ball_decay
        s[physics.B_VY] *= ball_decay


@njit(cache=True)
def _player_paths(s, t, k, g, paths) -> None:
    """:func:`_player_path` with the assumed effort (``paths[0]``) and the lowest and highest a type can have."""
    n = paths.shape[1] - 2
    _player_path(s, t, k, n, s[physics.S_EFFORT], paths[0])
    _player_path(s, t, k, n, g[G_EFFORT_LOW], paths[1])
    _player_path(s, t, k, n, g[G_EFFORT_HIGH], paths[2])


@njit(cache=True)
def _plan_kicks(s, t, kick_rand, k, g, ends, paths, best_v, best_slack, runs) -> int:
    """For the ``runs`` longest feasible run lengths n (of 0 .. max_run), the kick velocity whose ball keeps most
    clearance over the run.

    Fills ``best_v[n]`` (vx, vy) and ``best_slack[n]`` (metres of clearance left; -inf when no kick works or the run
    was not tried) and returns the longest run with a working kick (-1 if none). ``runs`` is a float (a literal int
    argument would compile a second copy of this function).

    ``paths`` holds :func:`_player_paths` of ``s``; ``ends`` the end places of the ball beside the player's assumed
    path: (fraction of the ring between touching and the kickable edge, cos, sin of the angle from the player). The
    ball must keep its clearances from the player on all three paths (on a path between them the distance to the
    ball lies between theirs, except for the closest approach, which the middle path covers).
    """
    max_run = best_v.shape[0] - 1
    touching = t[physics.T_SIZE] + k[physics.K_BALL_SIZE]
    reach = physics.kickable_radius(t[physics.T_SIZE], k[physics.K_BALL_SIZE], t[physics.T_KICKABLE_MARGIN])
    decay = k[physics.K_BALL_DECAY]
    speed_max2 = k[physics.K_BALL_SPEED_MAX] ** 2
    dv_max = _kick_reach(s, t, k)
    bx, by, bvx, bvy = s[physics.B_X], s[physics.B_Y], s[physics.B_VX], s[physics.B_VY]
    edge, near = g[G_EDGE], touching + g[G_BODY]
    longest = -1
    for n in range(max_run + 1):
        best_slack[n] = -np.inf
    if dv_max <= 0.0:
        return longest
    for n in range(max_run, -1, -1):
        total = (1.0 - decay ** (n + 1)) / (1.0 - decay)  # metres the ball covers per m/cycle of kick over n + 1 cycles
        for e in range(ends.shape[0]):
            radius = touching + ends[e, 0] * (reach - touching)
            vx = (paths[0, n + 1, 0] + radius * ends[e, 1] - bx) / total
            vy = (paths[0, n + 1, 1] + radius * ends[e, 2] - by) / total
            if vx * vx + vy * vy > speed_max2:
                continue
            dv = math.sqrt((vx - bvx) ** 2 + (vy - bvy) ** 2)
            if dv > dv_max:
                continue
            # kick noise grows with the power; its error in the ball's position grows with the cycles since the kick
            noise = kick_rand * dv / dv_max
            # clearance left on the assumed path first (most plans fail there), then on the extreme ones
            slack = np.inf
            for j in range(3):
                travelled = 0.0
                weight = 1.0
                for m in range(1, n + 2):
                    travelled += weight
                    weight *= decay
                    gx = bx + vx * travelled - paths[j, m, 0]
                    gy = by + vy * travelled - paths[j, m, 1]
                    gap = math.sqrt(gx * gx + gy * gy)
                    slack = min(slack, reach - edge - noise * travelled - gap, gap - near)
                    if slack < 0.0 or slack <= best_slack[n]:
                        break
                if slack < 0.0 or slack <= best_slack[n]:
                    break
            if slack > best_slack[n] and slack >= 0.0:
                best_slack[n] = slack
                best_v[n, 0], best_v[n, 1] = vx, vy
        if best_slack[n] >= 0.0 and longest < 0:
            longest = n
        if longest >= 0 and n <= longest - runs + 1:
            break
    return longest


@njit(cache=True)
def _safe(s, t, k, edge, body, collided) -> bool:
    """No collision, and the ball at least ``edge`` inside the kickable area and ``body`` clear of the player."""
    touching = t[physics.T_SIZE] + k[physics.K_BALL_SIZE]
    reach = physics.kickable_radius(t[physics.T_SIZE], k[physics.K_BALL_SIZE], t[physics.T_KICKABLE_MARGIN])
    gap = _gap(s)
    return (not collided) and gap <= reach - edge and gap >= touching + body


@njit(cache=True)
def _rollout(s, t, kick_rand, k, g, ends, vx, vy, n, elapsed, x0, work) -> float:
    """Score of a branch from kick state ``s`` (``elapsed`` cycles after the decision): kick at (vx, vy), run ``n``
    dashes, then greedy plans until the horizon. The score is metres along +x per cycle (with the momentum the player
    carries into the next cycle); a branch that loses the ball scores ``LOST`` plus the cycles it kept the ball."""
    command, p, uniforms, events, paths, best_v, best_slack = work
    horizon = int(g[G_HORIZON])
    reach = physics.kickable_radius(t[physics.T_SIZE], k[physics.K_BALL_SIZE], t[physics.T_KICKABLE_MARGIN])
    while True:
        _kick_params(s, vx, vy, p)
        if _act(s, t, skills.KICK_VELOCITY, p, k, command, uniforms, events) or _gap(s) > reach:
            return LOST + elapsed
        elapsed += 1
        _run(s, t, k, n)  # the plan checked that the ball stays clear of the player and kickable
        elapsed += n
        if elapsed >= horizon:
            return (s[physics.P_X] + s[physics.P_VX] - x0) / (elapsed + 1)
        _player_paths(s, t, k, g, paths)
        n = _plan_kicks(s, t, kick_rand, k, g, ends, paths, best_v, best_slack, 1.0)  # the longest run
        if n < 0:
            return LOST + elapsed
        vx, vy = best_v[n, 0], best_v[n, 1]


@njit(cache=True)
def _best_kick(start, t, kick_rand, k, g, ends, elapsed, x0, paths, best_v, best_slack, branch, work):
    """The best branch that kicks in state ``start`` (``elapsed`` cycles after the decision, a float): (score, vx, vy)."""
    _player_paths(start, t, k, g, paths)
    longest = _plan_kicks(start, t, kick_rand, k, g, ends, paths, best_v, best_slack, float(RUNS_TRIED))
    best, best_vx, best_vy = -np.inf, 0.0, 0.0
    for n in range(max(0, longest - RUNS_TRIED + 1), longest + 1):
        if best_slack[n] < 0.0:
            continue
        _copy(branch, start)
        score = _rollout(branch, t, kick_rand, k, g, ends, best_v[n, 0], best_v[n, 1], n, elapsed, x0, work)
        if score > best:
            best, best_vx, best_vy = score, best_v[n, 0], best_v[n, 1]
    return best, best_vx, best_vy


@njit(cache=True)
def _plan(state, types, kick_rands, k, g, ends, directions, kinds, params) -> None:
    """Fill ``kinds`` and ``params`` with the first action of the best branch for every lane of ``state``."""
    max_run = int(g[G_MAX_RUN])
    depth = int(g[G_DASH_DEPTH])
    command = np.zeros(physics.COMMAND_SIZE)
    p = np.zeros(skills.N_PARAMS)
    straight = np.zeros(skills.N_PARAMS)  # DASH_MAX(0)
    first_dash = np.zeros(skills.N_PARAMS)
    uniforms = np.full(physics.N_UNIFORMS, 0.5)  # irrelevant without noise
    events = np.zeros(physics.EVENT_SIZE, dtype=np.bool_)
    work = (command, p, uniforms, events, np.empty((3, max_run + 2, 4)), np.empty((max_run + 1, 2)), np.empty(max_run + 1))
    start = np.empty(physics.STATE_SIZE)
    extremes = np.empty((2, physics.STATE_SIZE))  # the start with the lowest and the highest effort
    extreme_types = np.empty((2, types.shape[1]))
    branch = np.empty(physics.STATE_SIZE)
    paths = np.empty((3, max_run + 2, 4))
    best_v = np.empty((max_run + 1, 2))
    best_slack = np.empty(max_run + 1)
    edge, body = g[G_EDGE], g[G_BODY]
    for i in range(state.shape[0]):
        s, t, kick_rand = state[i], types[i], kick_rands[i]
        x0 = s[physics.P_X]
        # kick now
        best_score, best_vx, best_vy = _best_kick(
            s, t, kick_rand, k, g, ends, 0.0, x0, paths, best_v, best_slack, branch, work
        )
        best_kind, best_direction = skills.KICK_VELOCITY, 0.0
        # or dash now (then maybe more straight dashes) and kick later
        for direction in directions:
            _copy(start, s)
            for j in range(2):
                _copy(extremes[j], s)
                _copy(extreme_types[j], t)
                extremes[j, physics.S_EFFORT] = extreme_types[j, physics.T_EFFORT_MAX] = g[G_EFFORT_LOW + j]
            first_dash[skills.PARAM_DASH_DIRECTION] = direction
            for m in range(1, (depth if direction == 0.0 else 1) + 1):
                # after the dash the ball must be safe with the assumed effort, and inside half the clearances with the
                # lowest and the highest
                dash_p = first_dash if m == 1 else straight
                collided = _act(start, t, skills.DASH_MAX, dash_p, k, command, uniforms, events)
                safe = _safe(start, t, k, edge, body, collided)
                for j in range(2):
                    collided = _act(extremes[j], extreme_types[j], skills.DASH_MAX, dash_p, k, command, uniforms, events)
                    safe = safe and _safe(
                        extremes[j], extreme_types[j], k, EXTREME_CLEARANCE * edge, EXTREME_CLEARANCE * body, collided
                    )
                if not safe:
                    break
                score, _, _ = _best_kick(
                    start, t, kick_rand, k, g, ends, float(m), x0, paths, best_v, best_slack, branch, work
                )
                if score > best_score:
                    best_score, best_kind, best_direction = score, skills.DASH_MAX, direction
        for c in range(params.shape[1]):
            params[i, c] = 0.0
        if best_score == -np.inf:  # no plan keeps the ball: stop it beside the player as well as a kick can
            best_kind = skills.KICK_POSITION
            params[i, skills.PARAM_POSITION_Y] = 0.6 if s[physics.B_Y] >= s[physics.P_Y] else -0.6
        elif best_kind == skills.KICK_VELOCITY:
            _kick_params(s, best_vx, best_vy, p)
            _copy(params[i], p)
        else:
            params[i, skills.PARAM_DASH_DIRECTION] = best_direction
        kinds[i] = best_kind
