"""N independent dribbling lanes: the one code path under both :class:`DribbleEnv` and :class:`DribbleVecEnv`.

A step runs skills -> physics -> task for all lanes at once. Each lane also keeps its heterogeneous player types:
every ``episodes_per_type_set`` episodes it draws a fresh set with the server's generator rules, and each episode of
the set uses a different type of it (in random order).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from robocup_dribble import physics, skills, task
from robocup_dribble.params import ServerProfile
from robocup_dribble.player_types import PlayerType, draw_type_table
from robocup_dribble.task import DribbleTask


class DribbleLanes:
    """State and stepping of ``n_lanes`` dribbling episodes.

    :param n_lanes: number of lanes.
    :param profile: server profile (noise already decided).
    :param task: the task's settings.
    :param rng: the generator every random draw comes from (types, starts, noise), in a fixed order.
    """

    def __init__(self, n_lanes: int, profile: ServerProfile, task_settings: DribbleTask, rng: np.random.Generator) -> None:
        if isinstance(n_lanes, bool) or not isinstance(n_lanes, (int, np.integer)) or n_lanes < 1:
            raise ValueError(f"n_lanes must be an integer >= 1, got {n_lanes!r}")
        self.n_lanes = int(n_lanes)
        self.profile = profile
        self.task = task_settings
        self.rng = rng
        self.observation_space = task.observation_space(profile, task_settings)
        self._bounds = np.stack(skills.parameter_bounds(profile))  # (2, 7): low, high
        self._obs_bounds = np.stack([self.observation_space.low, self.observation_space.high]).astype(np.float64)
        self._constants = physics.profile_constants(profile)
        self._reward_constants = task_settings.constants()
        n_types = profile.player.player_types
        self.state = physics.new_state(self.n_lanes)
        self.types = np.empty((self.n_lanes, physics.TYPE_SIZE))
        self.type_ids = np.zeros(self.n_lanes, dtype=np.int64)
        self.type_sets = np.empty((self.n_lanes, n_types, physics.TYPE_SIZE))
        self.set_order = np.zeros((self.n_lanes, task_settings.episodes_per_type_set), dtype=np.int64)
        self.episodes_in_set = np.zeros(self.n_lanes, dtype=np.int64)
        self.steps = np.zeros(self.n_lanes, dtype=np.int64)
        self.start_x = np.zeros(self.n_lanes)
        self.distance = np.zeros(self.n_lanes)
        self._pool_size = min(1024, max(16, self.n_lanes))  # type sets are drawn in blocks: one call per block
        self._set_pool = np.empty((0, n_types, physics.TYPE_SIZE))

    def reseed(self, rng: np.random.Generator) -> None:
        """Draw everything from ``rng`` from now on and start new type sets in every lane."""
        self.rng = rng
        self.episodes_in_set[:] = 0
        self._set_pool = self._set_pool[:0]

    def reset(self, lanes: np.ndarray) -> np.ndarray:
        """Start new episodes in ``lanes`` (indices); returns their observations ``(len(lanes), 10)``."""
        self._next_player_types(lanes)
        task.start_episodes(self.state, self.types, lanes, self.profile, self.task, self.rng)
        self.steps[lanes] = 0
        self.start_x[lanes] = self.state[lanes, physics.P_X]
        self.distance[lanes] = 0.0
        obs, _, _ = task.evaluate(
            self.state[lanes], self.types[lanes], np.zeros((len(lanes), physics.EVENT_SIZE), dtype=np.bool_),
            self.start_x[lanes], self.start_x[lanes], self.distance[lanes], self._reward_constants,
            self.profile.server.ball_size, self._obs_bounds[0], self._obs_bounds[1],
        )
        return obs

    def step(self, action_types: np.ndarray, params: np.ndarray):
        """Advance every lane by one action (one server cycle).

        :param action_types: ``(N,)`` integers in 0..3.
        :param params: ``(N, 7)`` finite parameters; out-of-range values are clipped to the bounds.
        :return: ``obs (N, 10) float32, reward (N,), terminated (N,), truncated (N,), distance (N,)`` (a copy).
        :raises ValueError: for a wrong shape, an action type outside 0..3 or a non-finite parameter; nothing changes.
        """
        kinds, params = self._checked(action_types, params)
        n = self.n_lanes
        obs = np.empty((n, len(task.OBSERVATION_NAMES)), dtype=np.float32)
        outcome = np.empty((n, 2))  # reward, distance
        ends = np.empty((n, 2), dtype=np.bool_)  # terminated (ball lost), truncated
        uniforms = self.rng.random((n, physics.N_UNIFORMS))
        _advance(self.state, self.types, kinds, params, self._bounds, uniforms, self._constants, self._reward_constants,
                 self._obs_bounds, self.start_x, self.distance, self.steps, self.task.max_actions, obs, outcome, ends)
        return obs, outcome[:, 0], ends[:, 0], ends[:, 1], outcome[:, 1]

    def player_type(self, lane: int) -> PlayerType:
        """The player type of a lane's current episode."""
        return PlayerType(*self.types[lane].tolist())

    def _checked(self, action_types: np.ndarray, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        kinds = np.asarray(action_types)
        params = np.asarray(params, dtype=np.float64)
        if kinds.dtype == np.int64 and kinds.shape == (self.n_lanes,) and params.shape == (self.n_lanes, skills.N_PARAMS):
            if _first_invalid(kinds, params) < 0:  # the common case, checked in one compiled call
                return kinds, params
        if kinds.shape != (self.n_lanes,):
            raise ValueError(f"action types must have shape ({self.n_lanes},), got {kinds.shape}")
        if params.shape != (self.n_lanes, skills.N_PARAMS):
            raise ValueError(f"parameters must have shape ({self.n_lanes}, {skills.N_PARAMS}), got {params.shape}")
        if kinds.dtype.kind not in "iu":
            as_int = kinds.astype(np.int64) if kinds.dtype.kind in "fb" else None
            if as_int is None or kinds.dtype.kind == "b" or not np.array_equal(as_int, kinds):
                raise ValueError(f"action types must be integers in 0..{skills.N_ACTION_TYPES - 1}, got {kinds!r}")
            kinds = as_int
        bad = _first_invalid(kinds.astype(np.int64, copy=False), params)
        if bad >= 0:
            raise ValueError(
                f"lane {bad}: action type {kinds[bad]!r} with parameters {params[bad]!r} is invalid; action types must be "
                f"integers in 0..{skills.N_ACTION_TYPES - 1} and parameters finite"
            )
        return kinds.astype(np.int64, copy=False), params

    def _next_player_types(self, lanes: np.ndarray) -> None:
        """Give each lane the next type of its set, drawing new sets where a set is used up."""
        per_set = self.task.episodes_per_type_set
        fresh = lanes[self.episodes_in_set[lanes] % per_set == 0]
        if len(fresh):
            self.type_sets[fresh] = self._take_type_sets(len(fresh))
            n_types = self.type_sets.shape[1]
            shuffled = np.argsort(self.rng.random((len(fresh), n_types)), axis=1)
            self.set_order[fresh] = shuffled[:, np.arange(per_set) % n_types]  # distinct while per_set <= n_types
        self.type_ids[lanes] = self.set_order[lanes, self.episodes_in_set[lanes] % per_set]
        self.types[lanes] = self.type_sets[lanes, self.type_ids[lanes]]
        self.episodes_in_set[lanes] += 1

    def _take_type_sets(self, count: int) -> np.ndarray:
        """The next ``count`` type sets of the pre-drawn pool (refilled from the lanes' generator when short)."""
        if len(self._set_pool) < count:
            fresh = draw_type_table(self.profile, max(self._pool_size, count - len(self._set_pool)), self._uniform)
            self._set_pool = np.concatenate([self._set_pool, fresh])
        taken, self._set_pool = self._set_pool[:count], self._set_pool[count:]
        return taken

    def _uniform(self, low: float, high: float, size: int) -> np.ndarray:
        return low + (high - low) * self.rng.random(size)


@njit(cache=True)
def _first_invalid(kinds: np.ndarray, params: np.ndarray) -> int:
    """The first lane with an action type outside 0..3 or a non-finite parameter, or -1."""
    for i in range(kinds.shape[0]):
        if kinds[i] < 0 or kinds[i] >= skills.N_ACTION_TYPES:
            return i
        for j in range(params.shape[1]):
            if not math.isfinite(params[i, j]):
                return i
    return -1


@njit(cache=True)
def _advance(state, types, kinds, params, bounds, uniforms, k, reward_constants, obs_bounds, start_x, distance, steps,
             max_actions, obs, outcome, ends) -> None:
    """skills -> physics -> task for every lane, in one compiled loop.

    Writes ``obs``, ``outcome[:, 0]`` (reward), ``outcome[:, 1]`` (distance), ``ends[:, 0]`` (ball lost) and
    ``ends[:, 1]`` (truncated); advances ``state``, ``distance`` and ``steps`` in place.
    """
    command = np.empty(physics.COMMAND_SIZE)
    clipped = np.empty(params.shape[1])
    events = np.empty(physics.EVENT_SIZE, dtype=np.bool_)
    ball_size = k[physics.K_BALL_SIZE]
    for i in range(state.shape[0]):
        s, t = state[i], types[i]
        for j in range(clipped.shape[0]):
            clipped[j] = min(max(params[i, j], bounds[0, j]), bounds[1, j])
        skills.command_lane(s, t, kinds[i], clipped, k, command)
        previous_x = s[physics.P_X]
        physics.step_lane(s, t, command, uniforms[i], k, events)
        reward, lost = task.evaluate_lane(s, t, events, previous_x, start_x[i], distance[i:i + 1], reward_constants,
                                          ball_size, obs_bounds[0], obs_bounds[1], obs[i])
        steps[i] += 1
        outcome[i, 0], outcome[i, 1] = reward, distance[i]
        ends[i, 0], ends[i, 1] = lost, steps[i] >= max_actions and not lost
