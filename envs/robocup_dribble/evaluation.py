"""Measure a dribbling policy on fixed evaluation episodes (common random numbers), and the paper's reliability test.

Any policy with an SB3-style ``predict(obs, deterministic=True) -> (actions, state)`` works (a trained model, or
:class:`robocup_dribble.dribbler.HandCodedDribbler`).

**Episode slots.** An evaluation with ``seed`` plays the episode slots ``j = 0 .. n_episodes - 1``. Everything random
in slot ``j`` comes from its own block of ``B = max_actions * physics.N_UNIFORMS + START_UNIFORMS`` uniforms of the
counter-based generator ``numpy.random.Philox(key=seed)``: the values from counter ``(j * B / 4, 0, 0, 0)`` on (each
counter value gives four; ``numpy.random.Generator.random``), so slot ``j``'s values do not depend on any other slot.
The block holds first the physics uniforms of every cycle, ``max_actions`` rows of ``physics.N_UNIFORMS`` values
(cycle ``t`` of the episode uses row ``t``, columns in ``physics.U_*`` roles), then the episode's start
(:meth:`robocup_dribble.lanes.DribbleLanes.start_from`): a fresh set of heterogeneous player types drawn by the
server's rules, the one type of it the episode plays, and the start state. A start that needs more than
``START_UNIFORMS`` values (a long run of rejected types; a v19 start takes about 145) continues with the values from
counter ``(0, j, 1, 0)`` on, which no block reaches. So slot ``j`` is the same episode (player
type, start state and noise of every cycle) for every policy, whichever lane plays it and whenever: two policies'
``distances[j]`` are paired observations. Slots are handed to lanes in order as lanes free up; results come back in
slot order. Each slot is its own fresh type set (``episodes_per_type_set`` has no effect here), so every episode's
type is a uniformly drawn type of a freshly generated set, as in the paper's reliability test.

**The reference.** :func:`distance_bound` gives, for each slot, an upper bound on the metres any policy can dribble
in that episode (see there why it holds): what a policy leaves below it is the most that could still be gained.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from robocup_dribble import physics
from robocup_dribble.env import configure
from robocup_dribble.lanes import DribbleLanes
from robocup_dribble.perception import SIGHT_INTERVAL
from robocup_dribble.params import EPS, ServerProfile
from robocup_dribble.task import DribbleTask
from robocup_dribble.vec_env import parse_actions

START_UNIFORMS = 256
"""Uniforms of an episode slot's block for its start (module docstring); changing it changes every slot's episode."""


@dataclass(frozen=True)
class DribbleReport:
    """Per-episode results of an evaluation, row ``j`` for episode slot ``j``."""

    distances: np.ndarray  # metres dribbled along +x before the ball was lost or the episode ended
    ball_lost: np.ndarray  # bool: the episode ended by losing the ball (not by the action limit)
    player_types: np.ndarray  # (n, physics.TYPE_SIZE): the slot's player type (player_types.TYPE_FIELDS columns)
    start_states: np.ndarray  # (n, physics.STATE_SIZE): the slot's start state (physics.STATE_FIELDS columns)
    distance_bounds: np.ndarray  # metres no policy can exceed in the slot's episode (distance_bound)

    @property
    def mean_distance(self) -> float:
        return float(np.mean(self.distances))

    @property
    def loss_rate(self) -> float:
        return float(np.mean(self.ball_lost))

    @property
    def mean_distance_bound(self) -> float:
        """The mean of :attr:`distance_bounds`: what no policy can beat on average on these episodes."""
        return float(np.mean(self.distance_bounds))

    def share_reaching(self, metres: float) -> float:
        """The share of episodes that dribbled at least ``metres``."""
        return float(np.mean(self.distances >= metres))

    def summary(self) -> str:
        return (
            f"{len(self.distances)} episodes: mean {self.mean_distance:.2f} m, median {np.median(self.distances):.2f} m, "
            f"max {np.max(self.distances):.2f} m, >= 20 m {100 * self.share_reaching(20):.1f} %, "
            f"ball lost {100 * self.loss_rate:.1f} %, upper bound {self.mean_distance_bound:.2f} m"
        )


def evaluate_dribbling(
    policy: Any,
    n_episodes: int = 1000,
    profile: str | ServerProfile = "v19",
    seed: int = 0,
    n_lanes: int = 100,
    deterministic: bool = True,
    perception: str = "full",
    **env_kwargs: Any,
) -> DribbleReport:
    """Play the episode slots ``0 .. n_episodes - 1`` of ``seed`` (module docstring) with ``policy``.

    :param policy: an object with ``predict(obs, deterministic=...)`` returning ``(actions, state)`` for a batch of
        observations (Tuple actions, as :class:`robocup_dribble.vec_env.DribbleVecEnv` takes them).
    :param n_episodes: episodes to play (slots).
    :param profile: the env's server profile (``"v19"``, ``"v11"``, or a ``ServerProfile``).
    :param seed: the evaluation set (an integer in 0 .. 2**64 - 1): the same seed gives the same episodes to every
        policy.
    :param n_lanes: episodes run side by side (at most ``n_episodes``); the results do not depend on it for a policy
        that acts on each observation alone.
    :param deterministic: passed to ``predict`` (greedy actions by default).
    :param perception: what the policy and the skills read, as for the env: ``"full"`` or ``"match"``
        (:mod:`robocup_dribble.perception`); with ``"match"`` the first see of slot ``j`` follows its first cycle
        for even ``j`` and its second for odd ``j``.
    :param env_kwargs: ``noise`` and the :class:`robocup_dribble.task.DribbleTask` settings of the env
        (``episodes_per_type_set`` is accepted and has no effect: every slot draws its own type set).
    :raises ValueError: for ``n_episodes`` or ``n_lanes`` not an integer >= 1, ``seed`` not an integer in 0 .. 2**64 - 1, or an
        unknown or invalid env setting.
    """
    _check_integer("n_episodes", n_episodes, 1)
    server_profile, task_settings = configure(profile, env_kwargs.pop("noise", True), None, env_kwargs)
    episodes = _Slots(int(n_episodes), _checked_seed(seed), task_settings.max_actions)
    return _evaluate(policy, server_profile, task_settings, episodes, n_lanes, deterministic, perception)


def evaluate_episodes(
    policy: Any,
    player_types: np.ndarray,
    start_states: np.ndarray,
    profile: str | ServerProfile = "v19",
    seed: int = 0,
    n_lanes: int = 100,
    deterministic: bool = True,
    perception: str = "full",
    **env_kwargs: Any,
) -> DribbleReport:
    """Play given episodes (a player type and a start state each, row ``j`` for episode ``j``) with ``policy``.

    Episode ``j`` takes the physics noise of every cycle from episode slot ``j`` of ``seed`` (module docstring;
    the slot's start part is not used), so two policies' ``distances[j]`` are paired observations again. This is
    the env's side of a comparison with a real server on the same episodes
    (:func:`robocup_dribble.rcss.server_episodes`). Arguments as :func:`evaluate_dribbling`; the start states are
    used as they are (a start of :func:`robocup_dribble.task.start_lane` has the player recovered).

    :raises ValueError: for arrays of other shapes, or what :func:`evaluate_dribbling` refuses.
    """
    types = physics.input_array("player_types", player_types, (None, physics.TYPE_SIZE))
    starts = physics.input_array("start_states", start_states, (len(types), physics.STATE_SIZE))
    if len(types) == 0:
        raise ValueError("evaluate_episodes needs at least one episode")
    server_profile, task_settings = configure(profile, env_kwargs.pop("noise", True), None, env_kwargs)
    episodes = _Slots(len(types), _checked_seed(seed), task_settings.max_actions, (types, starts))
    return _evaluate(policy, server_profile, task_settings, episodes, n_lanes, deterministic, perception)


def _checked_seed(seed: Any) -> int:
    _check_integer("seed", seed, 0)
    if seed >= 2**64:
        raise ValueError(f"seed must be below 2**64 (a Philox key word), got {seed!r}")
    return int(seed)


def _evaluate(
    policy: Any, server_profile: ServerProfile, task_settings: DribbleTask, episodes: _Slots, n_lanes: int,
    deterministic: bool, perception: str,
) -> DribbleReport:  # fmt: skip
    """Play every slot of ``episodes``, ``n_lanes`` at a time (handed to lanes in order as they free up)."""
    _check_integer("n_lanes", n_lanes, 1)
    n_episodes = len(episodes.distances)
    n_lanes = min(int(n_lanes), n_episodes)
    lanes = DribbleLanes(n_lanes, server_profile, task_settings, np.random.default_rng(0), perception)  # rng unused
    all_lanes = np.arange(n_lanes)
    slot_of_lane = np.arange(n_lanes)
    noise = np.empty((n_lanes, task_settings.max_actions, physics.N_UNIFORMS))
    obs = episodes.start(lanes, all_lanes, 0, noise)
    next_slot = n_lanes
    last_cycle = task_settings.max_actions - 1
    while (slot_of_lane >= 0).any():
        actions, _ = policy.predict(obs, deterministic=deterministic)
        kinds, params = parse_actions(actions)
        # lanes without a slot (at the end) keep stepping on their last cycle's noise; their results are dropped
        uniforms = noise[all_lanes, np.minimum(lanes.steps, last_cycle)]
        out = lanes.step(kinds, params, autoreset=False, uniforms=uniforms)
        obs = out.observations
        ended = np.flatnonzero((out.terminated | out.truncated) & (slot_of_lane >= 0))
        if len(ended):
            episodes.record(slot_of_lane[ended], out.distances[ended], out.terminated[ended])
            slot_of_lane[ended] = -1
            freed = ended[: n_episodes - next_slot]
            if len(freed):
                slot_of_lane[freed] = np.arange(next_slot, next_slot + len(freed))
                obs[freed] = episodes.start(lanes, freed, next_slot, noise)
                next_slot += len(freed)
    return DribbleReport(
        episodes.distances,
        episodes.ball_lost,
        episodes.player_types,
        episodes.start_states,
        distance_bound(server_profile, task_settings, episodes.player_types, episodes.start_states),
    )


def reliability_test(
    policy: Any, n_players: int = 10_000, profile: str | ServerProfile = "v19", seed: int = 0, **kwargs: Any
) -> DribbleReport:
    """The paper's reliability test: ``n_players`` freshly generated players each dribble once from the centre.

    These are :func:`evaluate_dribbling`'s slots: each draws a new set of player types and plays one type of it.
    """
    return evaluate_dribbling(policy, n_players, profile, seed, **kwargs)


def distance_bound(
    profile: ServerProfile, task_settings: DribbleTask, player_types: np.ndarray, start_states: np.ndarray
) -> np.ndarray:
    """An upper bound on the metres any policy can dribble in episodes of these player types and start states.

    ``player_types`` ``(n, TYPE_SIZE)`` and ``start_states`` ``(n, STATE_SIZE)`` are those of the episodes (a
    :class:`DribbleReport`'s); the bound holds for every action sequence and every noise draw.

    Why it holds (``robocup_dribble.physics.cycle``): the player's x moves only in the movement step and in a
    collision's push-out; kicks and turns do not move it. Let ``S`` bound the player's speed at a cycle's start
    (first the start speed ``|v0|``). A dash accelerates by at most ``A = min(player_accel_max, effort_max *
    max(|max_dash_power|, |min_dash_power|) * dash_power_rate)`` (effort never exceeds the type's ``effort_max``,
    the direction rates are <= 1, a v19 dash averages two legs of at most that power), and with acceleration the
    speed is capped at ``player_speed_max``, so the speed before noise is ``w <= max(S, min(speed_max, S + A))``.
    The noise adds a vector of length <= ``player_rand * w`` (polar; in v11's box each component <= that), so x
    advances by <= ``w (1 + player_rand)`` and the next speed is <= ``decay * w * (1 + r)`` with ``r = player_rand``
    (polar) or ``sqrt(2) player_rand`` (box). A collision pushes the player away from the midpoint to at most
    ``(player_size + ball_size) / 2 + EPS`` (grown by at most 1.0001^10) from it, and multiplies its velocity by
    -0.1. Each of these bounds grows with ``S``, so taking at every cycle the better of "no collision" and "a
    collision" (push added, next speed bounded by the largest after-collision speed) bounds every episode; the
    ball is ignored, which only loosens the bound. The result is x after ``max_actions`` cycles minus the start x
    (the episode's distance is x at some cycle minus the start x, and the bounded gains are never negative).
    With polar noise the bound equals a ballless run of full dashes along +x with the start velocity turned to +x
    and every cycle's noise at full length along +x, plus one push-out; with box noise it is up to about 2 m above.

    :raises ValueError: for arrays of other shapes, or a type whose ``decay * (1 + r) > 1`` (the speed bound would
        not stay below ``max(|v0|, player_speed_max)``; no profile's types come near it).
    """
    types = physics.input_array("player_types", player_types, (None, physics.TYPE_SIZE))
    starts = physics.input_array("start_states", start_states, (len(types), physics.STATE_SIZE))
    server = profile.server
    box = profile.noise_shape == "box"
    advance = 1.0 + server.player_rand
    speed_growth = 1.0 + (math.sqrt(2.0) if box else 1.0) * server.player_rand
    decay, speed_max = types[:, physics.T_DECAY], types[:, physics.T_SPEED_MAX]
    if (decay * speed_growth > 1.0).any():
        raise ValueError(f"distance_bound needs player_decay * {speed_growth:.4g} <= 1 for every type")
    power = max(abs(server.max_dash_power), abs(server.min_dash_power))
    accel = np.minimum(server.player_accel_max, types[:, physics.T_EFFORT_MAX] * power * types[:, physics.T_DASH_POWER_RATE])
    push = (0.5 * (types[:, physics.T_SIZE] + server.ball_size) + EPS) * 1.0001**10
    start_speed = np.hypot(starts[:, physics.P_VX], starts[:, physics.P_VY])
    after_collision = 0.1 * decay * speed_growth * np.maximum(start_speed, speed_max)
    cycles = task_settings.max_actions

    def gains(speed: np.ndarray) -> np.ndarray:
        """``(n, cycles)`` bounds of x's advance in each cycle without a collision, from speed bound ``speed``."""
        out = np.empty((len(speed), cycles))
        for t in range(cycles):
            w = np.maximum(speed, np.minimum(speed_max, speed + accel))
            out[:, t] = w * advance
            speed = decay * w * speed_growth
        return out

    # reached[:, t]: bound on x's advance over the cycles t.. from speed <= after_collision (cycles - t cycles left)
    after = np.concatenate((np.zeros((len(types), 1)), np.cumsum(gains(after_collision), axis=1)), axis=1)
    reached = np.zeros((len(types), cycles + 1))
    for t in range(cycles - 1, -1, -1):
        left = cycles - t  # first collision in cycle t + m (m = 0 .. left - 1), or none
        with_collision = after[:, 1 : left + 1] + push[:, None] + reached[:, t + 1 : cycles + 1]
        reached[:, t] = np.maximum(after[:, left], with_collision.max(axis=1))
    run = np.concatenate((np.zeros((len(types), 1)), np.cumsum(gains(start_speed), axis=1)), axis=1)
    with_collision = run[:, 1:] + push[:, None] + reached[:, 1:]
    bound: np.ndarray = np.maximum(run[:, cycles], with_collision.max(axis=1))
    return bound


class _Slots:
    """The episode slots of one evaluation: their uniforms (module docstring), and the results as they come in."""

    def __init__(
        self, n_episodes: int, seed: int, max_actions: int, given: tuple[np.ndarray, np.ndarray] | None = None
    ) -> None:
        self.max_actions = max_actions
        self.given = given  # (player types, start states) of every slot, or None: drawn from the slot's block
        self.noise_size = max_actions * physics.N_UNIFORMS
        self.block = self.noise_size + START_UNIFORMS
        self._bits = np.random.Philox(key=seed)
        self._key = self._bits.state["state"]["key"]
        self._generator = np.random.Generator(self._bits)
        self.distances = np.zeros(n_episodes)
        self.ball_lost = np.zeros(n_episodes, dtype=bool)
        self.player_types = np.zeros((n_episodes, physics.TYPE_SIZE))
        self.start_states = np.zeros((n_episodes, physics.STATE_SIZE))

    def start(self, lanes: DribbleLanes, lane_ids: np.ndarray, first: int, noise: np.ndarray) -> np.ndarray:
        """Start the slots ``first, first + 1, ...`` in ``lane_ids``, their cycles' uniforms into ``noise[lane]``;
        returns their observations."""
        blocks = self._draw((first * self.block // 4, 0, 0, 0), (len(lane_ids), self.block))
        noise[lane_ids] = blocks[:, : self.noise_size].reshape(len(lane_ids), self.max_actions, physics.N_UNIFORMS)
        slots = np.arange(first, first + len(lane_ids))
        lanes.clock[lane_ids] = slots % SIGHT_INTERVAL  # the sights' phase is the slot's, not the lane's history
        if self.given is not None:
            self.player_types[slots], self.start_states[slots] = self.given[0][slots], self.given[1][slots]
            return lanes.place(lane_ids, self.given[0][slots], self.given[1][slots])
        obs, short = lanes.start_from(lane_ids, blocks[:, self.noise_size :])
        for r in np.flatnonzero(short).tolist():  # a long run of rejected player types: continue on its own counters
            row, extra = blocks[r : r + 1, self.noise_size :], START_UNIFORMS
            while short[r]:
                more = self._draw((0, first + r, 1, 0), (1, extra))
                obs[r : r + 1], short[r : r + 1] = lanes.start_from(lane_ids[r : r + 1], np.concatenate((row, more), axis=1))
                extra *= 2
        self.player_types[slots] = lanes.types[lane_ids]
        self.start_states[slots] = lanes.state[lane_ids]
        return obs

    def record(self, slots: np.ndarray, distances: np.ndarray, ball_lost: np.ndarray) -> None:
        self.distances[slots], self.ball_lost[slots] = distances, ball_lost

    def _draw(self, counter: tuple[int, int, int, int], shape: tuple[int, int]) -> np.ndarray:
        """``shape`` uniforms of Philox(key=seed) from ``counter`` on (each counter value gives four)."""
        self._bits.state = {
            "bit_generator": "Philox",
            "state": {"counter": np.array(counter, dtype=np.uint64), "key": self._key},
            "buffer": np.zeros(4, dtype=np.uint64),
            "buffer_pos": 4,
            "has_uint32": 0,
            "uinteger": 0,
        }
        values: np.ndarray = self._generator.random(shape)
        return values


def _check_integer(name: str, value: Any, minimum: int) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
