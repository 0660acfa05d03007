"""N independent Half Field Offense 1v0 trials: the one code path under :class:`HalfFieldOffenseEnv` and
:class:`HalfFieldOffenseVecEnv`.

A step runs, for every lane in one compiled loop, the agent's command transform (:mod:`half_field_offense.actions`),
one server cycle (:func:`robocup_dribble.physics.cycle`), the referee (:func:`half_field_offense.referee.judge`),
the features and the reward; then (if asked) starts the next trial of every lane whose trial ended. The agent is the
server's default player type.

Random draws come from one numpy Generator: per step an ``(N, physics.N_UNIFORMS)`` block for the physics noise
(row ``i`` for lane ``i``), then per start (in lane order) the referee's five values. As in HFO, a lane's body
direction and its last-action flag carry over from one trial to the next; :meth:`HFOLanes.reseed` starts them afresh
(body 0, last action failed), as a new server and agent would.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from half_field_offense import actions, features, referee, reward, task
from half_field_offense.task import HFOTask
from robocup_dribble import physics
from robocup_dribble.params import ServerProfile
from robocup_dribble.player_types import default_player_type, stack_player_types

RANDOM_STREAM_VERSION = 1
"""Changes whenever the same seed would give other trials (see the module docstring)."""


class LaneStep(NamedTuple):
    """One step of every lane; the ``terminal_observations`` and ``episode_*`` rows are meaningful only where
    ``terminated | truncated`` (zero elsewhere)."""

    observations: np.ndarray  # (N, 59) float32; the next trial's first one where an ended lane was restarted
    rewards: np.ndarray  # (N,) float64
    terminated: np.ndarray  # (N,) bool: GOAL, OUT_OF_BOUNDS, or OUT_OF_TIME by an untouched ball
    truncated: np.ndarray  # (N,) bool: OUT_OF_TIME by the frames_per_trial cap
    status: np.ndarray  # (N,) int64 referee.STATUS_NAMES codes of this step (before any restart)
    terminal_observations: np.ndarray  # (N, 59) float32
    episode_returns: np.ndarray  # (N,) float64
    episode_lengths: np.ndarray  # (N,) int64


class HFOLanes:
    """State and stepping of ``n_lanes`` Half Field Offense trials.

    :param n_lanes: number of lanes.
    :param profile: server profile (noise already decided).
    :param task_settings: the trial settings.
    :param rng: the generator every draw comes from (module docstring).
    """

    def __init__(self, n_lanes: int, profile: ServerProfile, task_settings: HFOTask, rng: np.random.Generator) -> None:
        if isinstance(n_lanes, bool) or not isinstance(n_lanes, (int, np.integer)) or n_lanes < 1:  # type: ignore[redundant-expr]
            raise ValueError(f"n_lanes must be an integer >= 1, got {n_lanes!r}")
        self.n_lanes = n = int(n_lanes)
        self.profile, self.task, self.rng = profile, task_settings, rng
        self.n_actions, self.n_params = actions.n_actions(task_settings.tackle), actions.n_params(task_settings.tackle)
        self.k, self.c = physics.profile_constants(profile), task_settings.constants()
        self.state = physics.new_state(n)
        self.types = np.repeat(stack_player_types([default_player_type(profile)]), n, axis=0)
        self.steps = np.zeros(n, dtype=np.int64)
        """``(N,)`` cycles of each lane's current trial."""
        self.untouched = np.zeros(n, dtype=np.int64)
        """``(N,)`` cycles since the ball was last in the agent's kickable area (the referee's count)."""
        self.holds = np.zeros(n, dtype=np.bool_)
        """``(N,)`` the agent has held the ball in this trial (HFO's ball holder is the agent)."""
        self.previous_ball = np.zeros((n, 2))
        """``(N, 2)`` the ball's position at the end of the last cycle (what the referee's checks read)."""
        self.last_action_ok = np.zeros(n, dtype=np.bool_)
        self.memory = np.zeros((n, len(reward.MEMORY_FIELDS)))
        self.returns = np.zeros(n)
        self._step_arrays = (
            self.state, self.types, self.steps, self.untouched, self.holds, self.previous_ball, self.last_action_ok,
            self.memory, self.returns, self.k, self.c, actions.PARAM_LOW, actions.PARAM_HIGH,
        )  # fmt: skip

    def reseed(self, rng: np.random.Generator) -> None:
        """Draw everything from ``rng`` from now on; every lane's player starts afresh (body 0, last action failed)."""
        self.rng = rng
        self.state[:, physics.P_BODY] = 0.0
        self.last_action_ok[:] = False

    def reset(self, lanes: np.ndarray) -> np.ndarray:
        """Start new trials in ``lanes`` (distinct indices in 0..N-1); returns their observations ``(len(lanes), 59)``.

        :raises ValueError: for indices that are not distinct integers in range; nothing changes.
        """
        index = self._checked_lanes(lanes)
        obs = np.empty((len(index), features.N_FEATURES), dtype=np.float32)
        self._start(index, obs, by_row=True)
        return obs

    def place(self, lanes: np.ndarray, start_states: np.ndarray) -> np.ndarray:
        """Start a trial in each of ``lanes`` from a given start state (row ``r`` for ``lanes[r]``), as it is:
        nothing is drawn and the player is not recovered (a replay of a server's trial). Returns the observations
        ``(len(lanes), 59)``.

        :raises ValueError: for indices that are not distinct integers in range, or states of another shape.
        """
        index = self._checked_lanes(lanes)
        states = physics.input_array("start_states", start_states, (len(index), physics.STATE_SIZE))
        self.state[index] = states
        obs = np.empty((len(index), features.N_FEATURES), dtype=np.float32)
        _begin_lanes(*self._step_arrays[:11], index, obs)
        return obs

    def _checked_lanes(self, lanes: np.ndarray) -> np.ndarray:
        index = np.asarray(lanes)
        if index.ndim != 1 or index.dtype.kind not in "iu":
            raise ValueError(f"lanes must be a 1-D integer array, got {index!r:.200}")
        index = index.astype(np.int64)
        if len(index) and (index.min() < 0 or index.max() >= self.n_lanes or len(np.unique(index)) != len(index)):
            raise ValueError(f"lanes must be distinct indices in 0..{self.n_lanes - 1}, got {index!r:.200}")
        return index

    def _start(self, lanes: np.ndarray, obs: np.ndarray, by_row: bool) -> None:
        uniforms = self.rng.random((len(lanes), referee.N_START_UNIFORMS))
        _start_lanes(*self._step_arrays[:11], lanes, uniforms, obs, by_row)

    def step(self, action_types: np.ndarray, params: np.ndarray, autoreset: bool = True) -> LaneStep:
        """Advance every lane by one action (one server cycle); with ``autoreset`` start the next trial of every lane
        whose trial ended.

        :param action_types: ``(N,)`` integers in 0..K-1 (K = 3, or 4 with Tackle).
        :param params: ``(N, P)`` finite parameters (P = 5, or 6 with Tackle), columns in
            :data:`half_field_offense.actions.PARAM_NAMES` order; out-of-range values are clipped to the ranges.
        :raises ValueError: for a wrong shape, an action type out of range or a non-finite parameter; nothing changes.
        """
        kinds, params = self._checked(action_types, params)
        n = self.n_lanes
        out = LaneStep(
            observations=np.empty((n, features.N_FEATURES), dtype=np.float32),
            rewards=np.empty(n),
            terminated=np.empty(n, dtype=np.bool_),
            truncated=np.empty(n, dtype=np.bool_),
            status=np.empty(n, dtype=np.int64),
            terminal_observations=np.zeros((n, features.N_FEATURES), dtype=np.float32),
            episode_returns=np.zeros(n),
            episode_lengths=np.zeros(n, dtype=np.int64),
        )
        uniforms = self.rng.random((n, physics.N_UNIFORMS))
        ended = _step_lanes(*self._step_arrays, kinds, params, uniforms, *out)
        if autoreset and len(ended):
            self._start(ended, out.observations, by_row=False)
        return out

    def _checked(self, action_types: np.ndarray, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        kinds, values = np.asarray(action_types), np.asarray(params)
        if kinds.shape != (self.n_lanes,):
            raise ValueError(f"action types must have shape ({self.n_lanes},), got {kinds.shape}")
        if values.shape != (self.n_lanes, self.n_params) or values.dtype.kind not in "iuf":
            shape = (self.n_lanes, self.n_params)
            raise ValueError(f"parameters must be a real array of shape {shape}, got {values.dtype} {values.shape}")
        if kinds.dtype.kind not in "iu":
            as_int = kinds.astype(np.int64) if kinds.dtype.kind == "f" and np.isfinite(kinds).all() else None
            if as_int is None or not np.array_equal(as_int, kinds):
                raise ValueError(f"action types must be integers in 0..{self.n_actions - 1}, got {kinds!r:.200}")
            kinds = as_int
        kinds = np.ascontiguousarray(kinds, dtype=np.int64)
        values = np.ascontiguousarray(values, dtype=np.float64)
        bad = _first_invalid(kinds, values, self.n_actions)
        if bad >= 0:
            raise ValueError(
                f"lane {bad}: action type {kinds[bad]!r} with parameters {values[bad]!r} is invalid; action types must "
                f"be integers in 0..{self.n_actions - 1} and parameters finite"
            )
        return kinds, values


@njit(cache=True)
def _first_invalid(kinds: np.ndarray, params: np.ndarray, n_kinds: int) -> int:
    """The first lane with an action type outside 0..n_kinds-1 or a non-finite parameter, or -1."""
    for i in range(kinds.shape[0]):
        if kinds[i] < 0 or kinds[i] >= n_kinds:
            return i
        for j in range(params.shape[1]):
            if not math.isfinite(params[i, j]):
                return i
    return -1


@njit(cache=True, error_model="numpy")
def _start_lanes(
    state, types, steps, untouched, holds, previous_ball, last_action_ok, memory, returns, k, c, lanes, uniforms, obs, by_row
) -> None:
    """Start a trial in each of ``lanes`` from row ``r`` of ``uniforms`` and write its first observation to
    ``obs[r]`` (``by_row``) or ``obs[lane]``."""
    for r in range(lanes.shape[0]):
        referee.place(state, lanes[r], types, lanes[r], uniforms, r, c, k)
    _begin_lanes(
        state, types, steps, untouched, holds, previous_ball, last_action_ok, memory, returns, k, c, lanes, obs, by_row
    )


@njit(cache=True, error_model="numpy")
def _begin_lanes(
    state, types, steps, untouched, holds, previous_ball, last_action_ok, memory, returns, k, c, lanes, obs, by_row=True
) -> None:
    """Begin the trial whose start state ``lanes[r]`` holds: counts, memory and the referee's last ball reset, its
    first observation written to ``obs[r]`` (``by_row``) or ``obs[lane]``."""
    for r in range(lanes.shape[0]):
        i = lanes[r]
        steps[i], untouched[i], holds[i], returns[i] = 0, 0, False, 0.0
        previous_ball[i, 0], previous_ball[i, 1] = state[i, physics.B_X], state[i, physics.B_Y]
        memory[i, :] = 0.0
        features.observe(state, i, types, i, False, False, last_action_ok[i], c, k, obs, r if by_row else i)


@njit(cache=True, error_model="numpy")
def _step_lanes(
    state, types, steps, untouched, holds, previous_ball, last_action_ok, memory, returns, k, c, param_low, param_high,
    kinds, params, uniforms, obs, rewards, terminated, truncated, status, terminal_obs, episode_returns, episode_lengths,
) -> np.ndarray:  # fmt: skip
    """Agent -> physics -> referee -> features -> reward for every lane (lane ``i`` uses ``uniforms[i]``); writes
    the :class:`LaneStep` fields and returns the lanes whose trial ended, in order."""
    ended = np.empty(state.shape[0], dtype=np.int64)
    n_ended = 0
    frames_per_trial = c[task.R_FRAMES_PER_TRIAL]
    for i in range(state.shape[0]):
        kind = kinds[i]
        first = actions.PARAM_STARTS[kind]
        a = min(max(params[i, first], param_low[first]), param_high[first])
        b = 0.0
        if actions.PARAM_SIZES_ARRAY[kind] > 1:
            b = min(max(params[i, first + 1], param_low[first + 1]), param_high[first + 1])
        command, power, direction, ok = actions.command(state, i, types, i, kind, a, b, k)
        prev_x, prev_y = previous_ball[i, 0], previous_ball[i, 1]
        collided, _, posted = physics.cycle(state, i, types, i, command, power, direction, uniforms, i, k)
        steps[i] += 1
        code, untouched[i] = referee.judge(state, i, types, i, prev_x, prev_y, untouched[i], steps[i], c, k)
        if code == referee.IN_GAME and untouched[i] == 0:
            holds[i] = True
        previous_ball[i, 0], previous_ball[i, 1] = state[i, physics.B_X], state[i, physics.B_Y]
        last_action_ok[i] = ok
        features.observe(state, i, types, i, collided, posted, ok, c, k, obs, i)
        over = code != referee.IN_GAME
        capped = code == referee.OUT_OF_TIME and steps[i] > frames_per_trial
        r = reward.reward(obs, i, memory, i, holds[i], not holds[i], code == referee.GOAL, over, c)
        returns[i] += r
        rewards[i], terminated[i], truncated[i], status[i] = r, over and not capped, capped, code
        if over:
            episode_returns[i], episode_lengths[i] = returns[i], steps[i]
            for j in range(obs.shape[1]):
                terminal_obs[i, j] = obs[i, j]
            ended[n_ended] = i
            n_ended += 1
    return ended[:n_ended]
