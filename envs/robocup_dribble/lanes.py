"""N independent dribbling lanes: the one code path under both :class:`DribbleEnv` and :class:`DribbleVecEnv`.

A step runs skills -> physics -> task for all lanes in one compiled loop and then (if asked) starts the next episode
of every lane whose episode ended in a second one: no Python object is made per lane. Each lane also keeps its
heterogeneous player types: every ``episodes_per_type_set`` episodes it draws a fresh set with the server's generator
rules (:func:`robocup_dribble.player_types.draw_type_set`), and each episode of the set uses a different type of it
(in random order).

Random draws come from one numpy Generator, through a buffer of its ``random()`` values (so the order is that of
single draws; values drawn ahead stay in the buffer for the next call and are dropped by :meth:`DribbleLanes.reseed`).
A step takes ``N_UNIFORMS`` values per lane for the physics (lane after lane); then each lane whose episode ended
starts the next one (in lane order), taking, if its type set is used up, a new set (:func:`draw_type_set`) and
``player_types`` values that order it, and then the six values of its start state
(:func:`robocup_dribble.task.start_lane`). This is random stream version 2; version 1 (before the episode starts
moved into the compiled loop) drew the type sets from a separately drawn pool.

With ``perception="match"`` (:mod:`robocup_dribble.perception`) each lane also keeps the player's estimate of its
state: the skills' commands and the observations are computed from the estimate, the physics and the task's rules
run on the true state. A see follows every cycle that makes the lane's :attr:`DribbleLanes.clock` (cycles run since
the lanes were made or reseeded, or as set) odd, as the server's clock does for its sights; an episode starts with
the estimate equal to the start state (the trainer's placement). Perception draws nothing: the stream is the same.

Two ways around that stream, for callers that need each episode's draws to be fixed by something other than the
order of resets (common random numbers, :func:`robocup_dribble.evaluation.evaluate_dribbling`):
:meth:`DribbleLanes.start_from` starts given lanes from caller-given uniforms (a row each), and
:meth:`DribbleLanes.step` takes a cycle's physics uniforms from the caller. Neither touches the stream above.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from robocup_dribble import perception, physics, skills, task
from robocup_dribble.params import ServerProfile, without_noise
from robocup_dribble.perception import check_perception
from robocup_dribble.player_types import PlayerType, TypeRecipe, draw_type_set, next_uniform, type_recipe
from robocup_dribble.task import DribbleTask

RANDOM_STREAM_VERSION = 2
"""Changes whenever the same seed would give other episodes (see the module docstring)."""


class LaneArrays(NamedTuple):
    """Every lane's state, one row per lane (what the compiled loop reads and writes)."""

    state: np.ndarray  # (N, STATE_SIZE) physics state
    types: np.ndarray  # (N, TYPE_SIZE) the player type of the current episode
    set_types: np.ndarray  # (N, M, TYPE_SIZE) the types of the lane's set its episodes use, in order (cyclically);
    # M = min(episodes_per_type_set, player_types): only these are kept, which keeps the lanes' memory small
    set_ids: np.ndarray  # (N, M) int64: their type ids in the set
    episodes_in_set: np.ndarray  # (N,) int64: episodes started since the lane's first set
    type_ids: np.ndarray  # (N,) int64: the current episode's type id in its set
    steps: np.ndarray  # (N,) int64: actions taken in the current episode
    start_x: np.ndarray  # (N,) the player's x at the start of the episode
    distance: np.ndarray  # (N,) metres dribbled along +x (frozen at the last step with the ball)
    returns: np.ndarray  # (N,) the episode's undiscounted return so far


class LaneSettings(NamedTuple):
    """The constants of the compiled loop."""

    k: np.ndarray  # robocup_dribble.physics.profile_constants
    c: np.ndarray  # DribbleTask.constants
    param_low: np.ndarray  # (N_PARAMS,) parameter bounds
    param_high: np.ndarray
    obs_low: np.ndarray  # (N_OBSERVATIONS,) observation bounds
    obs_high: np.ndarray
    recipe: TypeRecipe


class LaneStep(NamedTuple):
    """One step of every lane; rows of the ``episode_*`` and ``terminal_observations`` arrays are meaningful only
    where ``terminated | truncated`` (zero elsewhere)."""

    observations: np.ndarray  # (N, 10) float32; the next episode's first one where an ended lane was reset
    rewards: np.ndarray  # (N,) float64
    terminated: np.ndarray  # (N,) bool: the ball was lost
    truncated: np.ndarray  # (N,) bool: max_actions reached with the ball
    distances: np.ndarray  # (N,) the metres dribbled in the episode so far (before any reset)
    terminal_observations: np.ndarray  # (N, 10) float32: the episode's last observation, where ended (else zero)
    episode_returns: np.ndarray  # (N,) float64
    episode_lengths: np.ndarray  # (N,) int64


class DribbleLanes:
    """State and stepping of ``n_lanes`` dribbling episodes.

    :param n_lanes: number of lanes.
    :param profile: server profile (noise already decided).
    :param task_settings: the task's settings.
    :param rng: the generator of random stream version 2 (types, starts, noise, in the order the module states), for
        all but what :meth:`start_from` and ``step(..., uniforms=...)`` are given.
    :param perception: ``"full"`` (the policy and the skills read the exact state) or ``"match"`` (they read the
        player's estimate from its own perception, module docstring).
    """

    def __init__(
        self,
        n_lanes: int,
        profile: ServerProfile,
        task_settings: DribbleTask,
        rng: np.random.Generator,
        perception: str = "full",
    ) -> None:
        if isinstance(n_lanes, bool) or not isinstance(n_lanes, (int, np.integer)) or n_lanes < 1:  # type: ignore[redundant-expr]
            raise ValueError(f"n_lanes must be an integer >= 1, got {n_lanes!r}")
        self.n_lanes = n = int(n_lanes)
        self.perception = check_perception(perception)
        self.profile = profile
        self.task = task_settings
        self.rng = rng
        self.observation_space = task.observation_space(profile, task_settings)
        low, high = skills.parameter_bounds(profile)
        self._settings = LaneSettings(
            physics.profile_constants(profile), task_settings.constants(), low, high,
            self.observation_space.low.astype(np.float64), self.observation_space.high.astype(np.float64),
            type_recipe(profile),
        )  # fmt: skip
        used_types = min(profile.player.player_types, task_settings.episodes_per_type_set)
        self.arrays = LaneArrays(
            state=physics.new_state(n),
            types=np.zeros((n, physics.TYPE_SIZE)),
            set_types=np.zeros((n, used_types, physics.TYPE_SIZE)),
            set_ids=np.zeros((n, used_types), dtype=np.int64),
            episodes_in_set=np.zeros(n, dtype=np.int64),
            type_ids=np.zeros(n, dtype=np.int64),
            steps=np.zeros(n, dtype=np.int64),
            start_x=np.zeros(n),
            distance=np.zeros(n),
            returns=np.zeros(n),
        )
        # the arrays by name too (they are updated in place, never replaced)
        a = self.arrays
        self.state, self.types, self.set_types, self.set_ids = a.state, a.types, a.set_types, a.set_ids
        self.episodes_in_set, self.type_ids, self.steps = a.episodes_in_set, a.type_ids, a.steps
        self.start_x, self.distance, self.returns = a.start_x, a.distance, a.returns
        g = self._settings
        self._step_arrays = (
            a.state,
            a.types,
            a.steps,
            a.start_x,
            a.distance,
            a.returns,
            g.k,
            g.c,
            g.param_low,
            g.param_high,
            g.obs_low,
            g.obs_high,
        )  # the fixed leading arguments of _step_lanes
        self._uniforms = np.empty(0)  # values drawn from rng and not used yet
        self._position = np.zeros(1, dtype=np.int64)  # the next one to use
        perceiving = self.perception == "match"
        self.estimate = a.state.copy() if perceiving else a.state
        """``(N, STATE_SIZE)``: what the policy and the skills read; the state itself unless ``perception="match"``."""
        self.clock = np.zeros(n, dtype=np.int64)
        """``(N,)`` cycles each lane has run (with ``perception="match"`` a see follows a cycle that makes it odd)."""
        self._unseen = np.zeros(n, dtype=np.int64)  # cycles since each lane's ball was last seen
        self._perception_arrays = (
            perceiving,
            self.estimate,
            self.clock,
            self._unseen,
            np.full((1, physics.N_UNIFORMS), 0.5),
            physics.profile_constants(without_noise(profile)),
        )  # the trailing arguments of _step_lanes

    def reseed(self, rng: np.random.Generator) -> None:
        """Draw everything from ``rng`` from now on and start new type sets in every lane."""
        self.rng = rng
        self.arrays.episodes_in_set[:] = 0
        self.clock[:] = 0
        self._uniforms = np.empty(0)
        self._position[0] = 0

    def reset(self, lanes: np.ndarray) -> np.ndarray:
        """Start new episodes in ``lanes`` (distinct indices in 0..N-1); returns their observations ``(len(lanes), 10)``.

        :raises ValueError: for indices that are not integers in range or repeat; nothing changes.
        """
        index = self._checked_lanes(lanes)
        obs = np.empty((len(index), task.N_OBSERVATIONS), dtype=np.float32)
        self._start(index, obs, by_row=True)
        return obs

    def _checked_lanes(self, lanes: np.ndarray) -> np.ndarray:
        index = np.asarray(lanes)
        if index.ndim != 1 or index.dtype.kind not in "iu":
            raise ValueError(f"lanes must be a 1-D integer array, got {index!r:.200}")
        index = index.astype(np.int64)
        if len(index) and (index.min() < 0 or index.max() >= self.n_lanes):
            raise ValueError(f"lanes must lie in 0..{self.n_lanes - 1}, got {index!r:.200}")
        if len(np.unique(index)) != len(index):
            raise ValueError(f"lanes must be distinct, got {index!r:.200}")
        return index

    def step(
        self, action_types: np.ndarray, params: np.ndarray, autoreset: bool = True, uniforms: np.ndarray | None = None
    ) -> LaneStep:
        """Advance every lane by one action (one server cycle); with ``autoreset`` start the next episode of every
        lane whose episode ended.

        :param action_types: ``(N,)`` integers in 0..3.
        :param params: ``(N, 7)`` finite parameters; out-of-range values are clipped to the bounds.
        :param uniforms: ``(N, physics.N_UNIFORMS)`` values in [0, 1] for this cycle's physics noise (row ``i`` for
            lane ``i``, roles ``physics.U_*``) instead of drawing them from ``rng`` (episode starts still draw from it).
        :raises ValueError: for a wrong shape, an action type outside 0..3, a non-finite parameter or uniforms that
            are not an ``(N, N_UNIFORMS)`` array of values in [0, 1]; nothing changes.
        """
        kinds, params = self._checked(action_types, params)
        given = None if uniforms is None else self._checked_uniforms(uniforms)
        n = self.n_lanes
        out = LaneStep(
            observations=np.empty((n, task.N_OBSERVATIONS), dtype=np.float32),
            rewards=np.empty(n),
            terminated=np.empty(n, dtype=np.bool_),
            truncated=np.empty(n, dtype=np.bool_),
            distances=np.empty(n),
            terminal_observations=np.zeros((n, task.N_OBSERVATIONS), dtype=np.float32),
            episode_returns=np.zeros(n),
            episode_lengths=np.zeros(n, dtype=np.int64),
        )
        physics_uniforms = self._take(n * physics.N_UNIFORMS).reshape(n, physics.N_UNIFORMS) if given is None else given
        # separate arrays, in LaneStep's order for the outputs: numba unpacks them faster than NamedTuples
        ended = _step_lanes(*self._step_arrays, kinds, params, physics_uniforms, *out, *self._perception_arrays)
        if autoreset and len(ended):
            self._start(ended, out.observations, by_row=False)
        return out

    def _take(self, count: int) -> np.ndarray:
        """The next ``count`` uniforms of the buffer (drawing more from ``rng`` first if it holds fewer)."""
        start = int(self._position[0])
        if len(self._uniforms) - start < count:
            fresh = self.rng.random(max(count, _DRAW_BLOCK))
            self._uniforms, start = np.concatenate((self._uniforms[start:], fresh)), 0
        self._position[0] = start + count
        return self._uniforms[start : start + count]

    def _start(self, lanes: np.ndarray, obs: np.ndarray, by_row: bool) -> None:
        """Start the next episode of ``lanes`` (in order); observations to ``obs[row]`` (``by_row``) or ``obs[lane]``."""
        first = 0
        while first < len(lanes):
            first = _start_lanes(
                self.arrays,
                self._settings,
                self.profile.player.player_types,
                lanes,
                first,
                self._uniforms,
                self._position,
                obs,
                by_row,
            )
            if first < len(lanes):  # ran short at lanes[first]: draw more and start it again
                start = int(self._position[0])
                self._uniforms = np.concatenate((self._uniforms[start:], self.rng.random(_DRAW_BLOCK)))
                self._position[0] = 0
        self._begin_estimates(lanes)

    def _begin_estimates(self, lanes: np.ndarray) -> None:
        """With ``perception="match"``: the player of each of ``lanes`` (just started) knows its start state."""
        if self.estimate is not self.state:
            self.estimate[lanes] = self.state[lanes]
            self._unseen[lanes] = 0

    def start_from(self, lanes: np.ndarray, uniforms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Start a new episode in each of ``lanes`` from caller-given uniforms (not from ``rng``).

        Lane ``lanes[r]`` reads row ``uniforms[r]`` from its beginning, in the order of an episode start that begins
        a type set (the module docstring): a fresh set of player types (:func:`draw_type_set`; a v19 set takes about
        120 values, a rare run of rejected types more), ``player_types`` values that order it (the episode plays the
        type with the smallest), and the six values of its start state. The lane's set is that one set (an episode
        it starts later through :meth:`reset` or an autoreset plays the set's next type).

        :param lanes: distinct lane indices.
        :param uniforms: ``(len(lanes), M)`` values in [0, 1].
        :return: the observations ``(len(lanes), 10)`` and ``(len(lanes),)`` bool ``short``: the row ran out before
            the start was drawn; that lane is left as it was (and its observation row is meaningless): start it
            again from a longer row.
        :raises ValueError: for indices that are not integers in range or repeat, or uniforms that are not a
            ``(len(lanes), M)`` array of values in [0, 1]; nothing changes.
        """
        index = self._checked_lanes(lanes)
        rows = physics.input_array("uniforms", uniforms, (len(index), None))
        if not ((rows >= 0.0) & (rows <= 1.0)).all():
            raise ValueError("uniforms must lie in [0, 1]")
        obs = np.empty((len(index), task.N_OBSERVATIONS), dtype=np.float32)
        short = _start_lanes_from_rows(self.arrays, self._settings, self.profile.player.player_types, index, rows, obs)
        self._begin_estimates(index[~short])
        return obs, short

    def place(self, lanes: np.ndarray, player_types: np.ndarray, start_states: np.ndarray) -> np.ndarray:
        """Start a new episode in each of ``lanes`` from a given player type and start state (row ``r`` for
        ``lanes[r]``), as they are: nothing is drawn and the player is not recovered. The lane's type set and type
        id are left as they were (an episode it starts later through :meth:`reset` or an autoreset plays its set).

        :return: the observations ``(len(lanes), 10)``.
        :raises ValueError: for indices that are not distinct integers in range, or arrays of other shapes.
        """
        index = self._checked_lanes(lanes)
        types = physics.input_array("player_types", player_types, (len(index), physics.TYPE_SIZE))
        states = physics.input_array("start_states", start_states, (len(index), physics.STATE_SIZE))
        a, g = self.arrays, self._settings
        a.state[index], a.types[index] = states, types
        a.steps[index], a.start_x[index], a.distance[index], a.returns[index] = 0, states[:, physics.P_X], 0.0, 0.0
        obs = np.empty((len(index), task.N_OBSERVATIONS), dtype=np.float32)
        for row, lane in enumerate(index.tolist()):
            task.observe(a.state, lane, a.types, lane, g.obs_low, g.obs_high, obs, row)
        self._begin_estimates(index)
        return obs

    def _checked_uniforms(self, uniforms: np.ndarray) -> np.ndarray:
        given = physics.input_array("uniforms", uniforms, (self.n_lanes, physics.N_UNIFORMS))
        if not ((given >= 0.0) & (given <= 1.0)).all():
            raise ValueError("uniforms must lie in [0, 1]")
        return given

    def player_type(self, lane: int) -> PlayerType:
        """The player type of a lane's current episode."""
        return PlayerType(*self.arrays.types[lane].tolist())

    def _checked(self, action_types: np.ndarray, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        kinds = np.asarray(action_types)
        params = np.asarray(params)
        if params.dtype.kind not in "iuf":
            raise ValueError(f"parameters must be real numbers, got an array of {params.dtype}")
        params = np.ascontiguousarray(params, dtype=np.float64)
        if kinds.dtype == np.int64 and kinds.shape == (self.n_lanes,) and params.shape == (self.n_lanes, skills.N_PARAMS):
            kinds = np.ascontiguousarray(kinds)
            if _first_invalid(kinds, params) < 0:  # the common case, checked in one compiled call
                return kinds, params
        if kinds.shape != (self.n_lanes,):
            raise ValueError(f"action types must have shape ({self.n_lanes},), got {kinds.shape}")
        if params.shape != (self.n_lanes, skills.N_PARAMS):
            raise ValueError(f"parameters must have shape ({self.n_lanes}, {skills.N_PARAMS}), got {params.shape}")
        if kinds.dtype.kind not in "iu":
            as_int = kinds.astype(np.int64) if kinds.dtype.kind == "f" else None
            if as_int is None or not np.array_equal(as_int, kinds):
                raise ValueError(f"action types must be integers in 0..{skills.N_ACTION_TYPES - 1}, got {kinds!r:.200}")
            kinds = as_int
        kinds = np.ascontiguousarray(kinds, dtype=np.int64)
        bad = _first_invalid(kinds, params)
        if bad >= 0:
            raise ValueError(
                f"lane {bad}: action type {kinds[bad]!r} with parameters {params[bad]!r} is invalid; action types must be "
                f"integers in 0..{skills.N_ACTION_TYPES - 1} and parameters finite"
            )
        return kinds, params


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


# The kernels unpack the NamedTuples once at the top: reading an array out of a tuple costs a reference-count
# update, which per lane and field would cost more than the physics.


_DRAW_BLOCK = 4096  # uniforms drawn from the Generator at least per refill of the buffer


@njit(cache=True, error_model="numpy", inline="always")
def _start_lane(
    state,
    types,
    set_types,
    set_ids,
    episodes_in_set,
    type_ids,
    steps,
    start_x,
    distance,
    returns,
    k,
    c,
    recipe,
    i: int,
    uniforms,
    position,
    type_set,
    order_keys,
) -> bool:
    """Start lane ``i``'s next episode: its next player type (a fresh set when the set is used up), its start state
    and its episode statistics. Returns False, committing nothing, if ``uniforms`` ran short (the caller draws more
    and calls again from the same position). ``type_set`` ``(1, player_types, TYPE_SIZE)`` and ``order_keys``
    ``(player_types,)`` are scratch. (The lane arrays come one by one: unpacking a tuple of them in a function called
    per lane would update their reference counts every time, which cost more than the start itself.)"""
    used_types = set_types.shape[1]
    episode = episodes_in_set[i] % int(c[task.R_EPISODES_PER_TYPE_SET])
    if episode == 0:  # a new set, its types in random order; the lane keeps those its episodes use
        draw_type_set(recipe, uniforms, position, type_set, 0)
        for j in range(order_keys.shape[0]):
            order_keys[j] = next_uniform(uniforms, position)
        order = np.argsort(order_keys)
        for e in range(used_types):
            set_ids[i, e] = order[e]
            for f in range(types.shape[1]):
                set_types[i, e, f] = type_set[0, order[e], f]
    e = episode % used_types  # distinct types while episodes_per_type_set <= player_types
    for f in range(types.shape[1]):
        types[i, f] = set_types[i, e, f]
    task.start_lane(state, i, types, i, uniforms, position, c, k)
    if position[0] > uniforms.shape[0]:
        return False
    type_ids[i] = set_ids[i, e]
    episodes_in_set[i] += 1
    steps[i] = 0
    start_x[i] = state[i, physics.P_X]
    distance[i] = 0.0
    returns[i] = 0.0
    return True


@njit(cache=True, error_model="numpy")
def _start_lanes(
    a: LaneArrays, g: LaneSettings, player_types: int, lanes, first: int, uniforms, position, obs, by_row: bool
) -> int:
    """Start ``lanes[first:]`` in order and write their observations; returns the index in ``lanes`` at which the
    uniforms ran short (that lane is not started), or ``len(lanes)``."""
    k, c, _, _, obs_low, obs_high, recipe = g
    state, types, set_types, set_ids, episodes_in_set, type_ids, steps, start_x, distance, returns = a
    type_set, order_keys = np.empty((1, player_types, a.types.shape[1])), np.empty(player_types)
    for row in range(first, lanes.shape[0]):
        i = lanes[row]
        start = position[0]
        if not _start_lane(
            state,
            types,
            set_types,
            set_ids,
            episodes_in_set,
            type_ids,
            steps,
            start_x,
            distance,
            returns,
            k,
            c,
            recipe,
            i,
            uniforms,
            position,
            type_set,
            order_keys,
        ):
            position[0] = start
            return row
        task.observe(state, i, types, i, obs_low, obs_high, obs, row if by_row else i)
    return int(lanes.shape[0])


@njit(cache=True, error_model="numpy")
def _step_lanes(
    state,
    types,
    steps,
    start_x,
    distance,
    returns,
    k,
    c,
    param_low,
    param_high,
    obs_low,
    obs_high,
    kinds,
    params,
    uniforms,
    obs,
    rewards,
    terminated,
    truncated,
    distances,
    terminal_obs,
    episode_returns,
    episode_lengths,
    perceiving,
    estimate,
    clock,
    unseen,
    calm,
    k0,
) -> np.ndarray:
    """skills -> physics -> task for every lane (lane ``i`` uses ``uniforms[i]``); writes the :class:`LaneStep`
    fields it names and returns the lanes whose episode ended, in order. The skills and the observation read
    ``estimate`` (the state itself unless ``perceiving``), which :func:`robocup_dribble.perception.perceive_lane`
    then keeps (``calm``, ``k0``: its noise-free prediction)."""
    ended = np.empty(state.shape[0], dtype=np.int64)
    n_ended = 0
    max_actions = c[task.R_MAX_ACTIONS]
    for i in range(state.shape[0]):
        kind = kinds[i]
        first = skills.PARAM_STARTS[kind]
        p0 = min(max(params[i, first], param_low[first]), param_high[first])
        p1 = 0.0
        if skills.PARAM_WIDTHS[kind] > 1:
            p1 = min(max(params[i, first + 1], param_low[first + 1]), param_high[first + 1])
        c_kind, power, direction = skills.command(estimate, i, types, i, kind, p0, p1, k)
        previous_x = state[i, physics.P_X]
        collided, _, _ = physics.cycle(state, i, types, i, c_kind, power, direction, uniforms, i, k)
        reward, lost = task.evaluate(state, i, types, i, collided, previous_x, c, k)
        if not lost:
            distance[i] = state[i, physics.P_X] - start_x[i]
        steps[i] += 1
        returns[i] += reward
        ended_by_limit = steps[i] >= max_actions and not lost
        rewards[i], terminated[i], truncated[i], distances[i] = reward, lost, ended_by_limit, distance[i]
        clock[i] += 1
        if perceiving:
            sees = clock[i] % perception.SIGHT_INTERVAL == 1
            unseen[i] = perception.perceive_lane(
                state, estimate, i, types, i, c_kind, power, direction, sees, unseen[i], calm, k0
            )
        task.observe(estimate, i, types, i, obs_low, obs_high, obs, i)
        if lost or ended_by_limit:
            episode_returns[i], episode_lengths[i] = returns[i], steps[i]
            for j in range(obs.shape[1]):
                terminal_obs[i, j] = obs[i, j]
            ended[n_ended] = i
            n_ended += 1
    return ended[:n_ended]


@njit(cache=True, error_model="numpy")
def _start_lanes_from_rows(a: LaneArrays, g: LaneSettings, player_types: int, lanes, rows, obs) -> np.ndarray:
    """Start each ``lanes[r]`` with a fresh type set from the uniforms ``rows[r]`` and write its observation to
    ``obs[r]``; returns ``short``: the row ran out (that lane is left as it was)."""
    k, c, _, _, obs_low, obs_high, recipe = g
    state, types, set_types, set_ids, episodes_in_set, type_ids, steps, start_x, distance, returns = a
    type_set, order_keys = np.empty((1, player_types, a.types.shape[1])), np.empty(player_types)
    # each start is drawn in lane 0 of scratch arrays and copied to its lane only if its row sufficed
    s_state, s_types = np.empty((1, state.shape[1])), np.empty((1, types.shape[1]))
    s_set_types = np.empty((1, set_types.shape[1], set_types.shape[2]))
    s_set_ids = np.empty((1, set_ids.shape[1]), dtype=np.int64)
    s_episodes, s_type_ids, s_steps = np.zeros(1, dtype=np.int64), np.empty(1, dtype=np.int64), np.empty(1, dtype=np.int64)
    s_start_x, s_distance, s_returns = np.empty(1), np.empty(1), np.empty(1)
    position = np.zeros(1, dtype=np.int64)
    short = np.zeros(lanes.shape[0], dtype=np.bool_)
    for r in range(lanes.shape[0]):
        s_episodes[0] = 0
        position[0] = 0
        short[r] = not _start_lane(
            s_state,
            s_types,
            s_set_types,
            s_set_ids,
            s_episodes,
            s_type_ids,
            s_steps,
            s_start_x,
            s_distance,
            s_returns,
            k,
            c,
            recipe,
            0,
            rows[r],
            position,
            type_set,
            order_keys,
        )
        if short[r]:
            continue
        i = lanes[r]
        state[i], types[i], set_types[i], set_ids[i] = s_state[0], s_types[0], s_set_types[0], s_set_ids[0]
        episodes_in_set[i], type_ids[i], steps[i] = s_episodes[0], s_type_ids[0], s_steps[0]
        start_x[i], distance[i], returns[i] = s_start_x[0], s_distance[0], s_returns[0]
        task.observe(state, i, types, i, obs_low, obs_high, obs, r)
    return short
