"""Dribbling episodes on a real rcssserver: one player plus a trainer, synchronous mode, the env's own rules.

:class:`ServerSession` speaks the protocol (docs/pitch.md describes what it relies on):
the trainer connects on the coach port, the player on the player port; the server's ``server_param``,
``player_param`` and ``player_type`` messages are checked against the env's profile and the types
:func:`robocup_dribble.player_types.generate_player_types` makes for the server's ``player::random_seed`` before
anything is played (:func:`check_server`). An episode is set up by the trainer inside one think window
(``change_player_type`` when the type changes, ``recover``, the ball parked, the player and the ball placed, a
``look`` that confirms the placement); then every cycle the player's observation is built from ``(fullstate ...)``
exactly as the env builds it (:func:`robocup_dribble.task.observe`), the policy's action becomes a server command
through the env's skills (:func:`robocup_dribble.skills.command_lane`), and the env's task rules
(:func:`robocup_dribble.task.evaluate`) decide when the ball is lost. The result is a
:class:`robocup_dribble.evaluation.DribbleReport`, so it compares directly with
:func:`robocup_dribble.evaluation.evaluate_episodes` on the same episodes (:func:`server_episodes`).

The ``"v19"`` profile is played on rcssserver 19 (protocol 19), ``"v15"`` on HFO's rcssserver 15.2.2 fork (protocol
15: the fork refuses 19); no rcssserver of the v11 era (2007) can be obtained and built today, so
:func:`checked_profile` refuses ``"v11"`` with that reason.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any, NamedTuple

import numpy as np

from robocup_dribble import physics, skills, task
from robocup_dribble.env import configure
from robocup_dribble.evaluation import DribbleReport, distance_bound
from robocup_dribble.params import ServerProfile, make_profile
from robocup_dribble.player_types import TYPE_FIELDS, generate_player_types, stack_player_types
from robocup_dribble.rcss import protocol
from robocup_dribble.rcss.perception import PerceivedWorld, read_seen_ball, read_speed
from robocup_dribble.rcss.protocol import ProtocolError
from robocup_dribble.rcss.server import Endpoint, ServerError
from robocup_dribble.vec_env import parse_actions

PROTOCOL_VERSION = 19
PROTOCOL_VERSIONS = {"v19": PROTOCOL_VERSION, "v15": 15}
"""The client protocol version each checkable profile's server speaks."""
HETEROGENEOUS_CHECKED = ("v19",)
"""Profiles whose server's heterogeneous player types :func:`generate_player_types` reproduces; for the others
(rcssserver 15.x draws them another way) only the default type 0 is checked, and only it may be played."""
TEAM = "PITCH"
UNUM = 1
PARK_BALL = (0.0, -30.0)
"""Where the ball waits while the player is placed (so that placing the player cannot collide with it)."""
PRINT_RTOL = 1e-5
"""Relative tolerance for numbers the server prints (6 significant digits)."""
_PARAMETER_MESSAGES = ("server_param", "player_param", "player_type")
_MESSAGE_NAMES = {"max_power": "maxpower", "min_power": "minpower", "max_moment": "maxmoment", "min_moment": "minmoment"}
"""The profile's parameters that ``(server_param ...)`` names differently (the server's old spellings)."""


class Window(NamedTuple):
    """What the player got in one think window: its fullstate, the collision flag and text of its sense_body, the
    text of its see (None in a cycle without one) and what it heard the referee say, in order."""

    fullstate: protocol.FullState
    collided: bool
    sense_body: str
    see: str | None
    referee: tuple[str, ...] = ()


def checked_profile(profile: str | ServerProfile) -> ServerProfile:
    """The profile a real server run uses: ``"v19"`` or ``"v15"`` (or a profile named so).

    :raises ValueError: for ``"v11"``: its server (2007) cannot be obtained, so it cannot be checked on a real one.
    """
    server_profile = make_profile(profile)
    if server_profile.name not in PROTOCOL_VERSIONS:
        raise ValueError(
            f"profile {server_profile.name!r} cannot be played on a real server: only rcssserver 19 and HFO's 15.2.2 "
            "fork can be built and checked (no rcssserver of the v11 era, 2007, is obtainable); use profile 'v19' or 'v15'"
        )
    return server_profile


def server_options(profile: ServerProfile, world_seed: int) -> dict[str, object]:
    """The rcssserver options of a session: synchronous trainer mode without referee or logs, fullstate for the
    left team, ``player::random_seed = world_seed`` and the profile's noise."""
    integer = isinstance(world_seed, (int, np.integer)) and not isinstance(world_seed, bool)  # type: ignore[redundant-expr]
    if not integer or not 0 <= world_seed < 2**31:
        raise ValueError(f"world_seed must be an integer in 0 .. 2**31 - 1 (player::random_seed), got {world_seed!r}")
    s = profile.server
    return {
        "server::synch_mode": True,
        "server::auto_mode": False,
        "server::coach": True,
        "server::coach_w_referee": False,
        "server::game_logging": False,
        "server::text_logging": False,
        "server::keepaway_logging": False,
        "server::profile": False,
        "server::fullstate_l": True,
        "server::fullstate_r": False,
        "server::player_rand": s.player_rand,
        "server::ball_rand": s.ball_rand,
        "server::kick_rand": s.kick_rand,
        "player::kick_rand_delta_factor": profile.player.kick_rand_delta_factor,
        "player::random_seed": int(world_seed),
    }


@dataclass(frozen=True)
class ServerEpisodes:
    """Episodes for one server world (``player::random_seed = world_seed``): row ``j`` is episode ``j``."""

    world_seed: int
    type_ids: np.ndarray  # (n,) int64: the server's type id of each episode
    player_types: np.ndarray  # (n, physics.TYPE_SIZE): those types (TYPE_FIELDS columns)
    start_states: np.ndarray  # (n, physics.STATE_SIZE): the start states (the env's start rule)


def server_episodes(
    n_episodes: int, world_seed: int = 1, seed: int = 0, profile: str | ServerProfile = "v19", **env_kwargs: Any
) -> ServerEpisodes:
    """``n_episodes`` episodes of the world ``world_seed``: each plays a type drawn uniformly from the server's
    ``player_types`` (type 0 included, as the env's type sets) from a start drawn by the env's start rule
    (:func:`robocup_dribble.task.start_lane`), all from ``numpy.random.default_rng((seed, world_seed))``: per
    episode one integer for the type, then six uniforms for the start, so the first ``m`` episodes of a longer run
    are the ``m`` episodes of a shorter one.

    :param env_kwargs: ``noise`` and the :class:`DribbleTask` settings, as for the env.
    """
    if isinstance(n_episodes, bool) or not isinstance(n_episodes, (int, np.integer)) or n_episodes < 1:  # type: ignore[redundant-expr]
        raise ValueError(f"n_episodes must be an integer >= 1, got {n_episodes!r}")
    server_profile, task_settings = configure(profile, env_kwargs.pop("noise", True), None, env_kwargs)
    table = stack_player_types(generate_player_types(server_profile, int(world_seed)))
    rng = np.random.default_rng((int(seed), int(world_seed)))
    type_ids = np.empty(int(n_episodes), dtype=np.int64)
    states = physics.new_state(int(n_episodes))
    c, k = task_settings.constants(), physics.profile_constants(server_profile)
    for j in range(int(n_episodes)):  # episode j's draws follow episode j - 1's: a longer run starts the same
        type_ids[j] = rng.integers(0, len(table))
        task.start_lane(states, j, table[type_ids[j : j + 1]], 0, rng.random(6), np.zeros(1, dtype=np.int64), c, k)
    types = table[type_ids]
    return ServerEpisodes(int(world_seed), type_ids, types, states)


def check_server(
    profile: ServerProfile,
    world_seed: int,
    server_param: Mapping[str, Any],
    player_param: Mapping[str, Any],
    player_types: Sequence[Mapping[str, Any]],
) -> None:
    """Check a server's parameter messages against ``profile`` and the types it should have generated.

    :raises ServerError: naming the first differences (a wrong server version or wrong options).
    """
    problems = []
    for name, expected, given in (("server", profile.server, server_param), ("player", profile.player, player_param)):
        for field in fields(expected):
            value = getattr(expected, field.name)
            key = _MESSAGE_NAMES.get(field.name, field.name)
            if key not in given:
                problems.append(f"{name}_param lacks {key}")
            elif not _close(given[key], value):
                problems.append(f"{name}::{key} is {given[key]!r}, the profile has {value!r}")
    expected_types = generate_player_types(profile, world_seed)
    if len(player_types) != len(expected_types):
        problems.append(f"{len(player_types)} player types, the profile has {len(expected_types)}")
    checked = len(expected_types) if profile.name in HETEROGENEOUS_CHECKED else 1
    for type_id, (message, expected_type) in enumerate(zip(player_types[:checked], expected_types, strict=False)):
        if message.get("id") != type_id:
            problems.append(f"player_type number {type_id} has id {message.get('id')!r}")
        for name, value in zip(TYPE_FIELDS, expected_type, strict=True):
            if name not in message or not _close(message[name], value):
                problems.append(f"player type {type_id}: {name} is {message.get(name)!r}, expected {value:.6g}")
    if problems:
        shown = "; ".join(problems[:5]) + (f"; and {len(problems) - 5} more" if len(problems) > 5 else "")
        raise ServerError(f"the server does not match profile {profile.name!r} with player::random_seed={world_seed}: {shown}")


def _close(given: Any, expected: float) -> bool:
    return isinstance(given, float) and math.isclose(given, float(expected), rel_tol=PRINT_RTOL, abs_tol=1e-9)


class ServerSession:
    """A connected player and trainer on an rcssserver in synchronous mode; plays dribbling episodes.

    :param player: the player's endpoint. :param trainer: the trainer's endpoint (the server's coach port).
    :param profile: the env profile to check the server against (``"v19"`` only, :func:`checked_profile`).
    :param world_seed: the server's ``player::random_seed``.
    :param env_kwargs: ``noise`` (must match the server's options) and the :class:`DribbleTask` settings.
    """

    def __init__(
        self,
        player: Endpoint,
        trainer: Endpoint,
        profile: str | ServerProfile = "v19",
        world_seed: int = 1,
        **env_kwargs: Any,
    ) -> None:
        server_profile, self.task = configure(checked_profile(profile), env_kwargs.pop("noise", True), None, env_kwargs)
        self.profile = server_profile
        self.world_seed = int(world_seed)
        self.player, self.trainer = player, trainer
        self.time = -1
        self.player_type = -1
        self._k = physics.profile_constants(self.profile)
        self._c = self.task.constants()
        self._param_low, self._param_high = skills.parameter_bounds(self.profile)
        space = task.observation_space(self.profile, self.task)
        self._obs_low, self._obs_high = space.low.astype(np.float64), space.high.astype(np.float64)

    def open(self) -> None:
        """Connect both clients, check the server (:func:`check_server`), switch to play_on and wait for the first
        think window."""
        version = PROTOCOL_VERSIONS[self.profile.name]
        self.trainer.send(f"(init (version {version}))")
        reply = self._trainer_reply(self.trainer.receive())
        if reply != "(init ok)":
            raise ServerError(f"the trainer's init was answered {reply[:200]!r}, not (init ok)")
        self.player.send(f"(init {TEAM} (version {version}))")
        reply = self._player_message(self.player.receive())
        if not reply.startswith(f"(init l {UNUM} "):
            raise ServerError(f"the player's init was answered {reply[:200]!r}, not (init l {UNUM} ...): is the team full?")
        parameters: dict[str, list[dict[str, Any]]] = {name: [] for name in _PARAMETER_MESSAGES}
        while len(parameters["player_type"]) < self.profile.player.player_types:
            message = self._player_message(self.player.receive())
            if protocol.kind(message) not in parameters:
                raise ServerError(f"expected the server's parameter messages after init, got {message[:200]!r}")
            parameters[protocol.kind(message)].append(protocol.read_parameters(message))
        if len(parameters["server_param"]) != 1 or len(parameters["player_param"]) != 1:
            raise ServerError("the server sent no server_param or player_param message before the player types")
        check_server(
            self.profile, self.world_seed, parameters["server_param"][0], parameters["player_param"][0],
            parameters["player_type"],
        )  # fmt: skip
        self._trainer_command("(eye on)")  # the synchronous server waits for (done) only from a trainer with eye on
        self._trainer_command("(change_mode play_on)")
        self._finish_cycle(catch_up=True)

    def play(
        self,
        policy: Any,
        episodes: ServerEpisodes,
        deterministic: bool = True,
        on_episode: Callable[[int, float, bool], None] | None = None,
        perceive: bool = False,
    ) -> DribbleReport:
        """Play ``episodes`` with ``policy`` (SB3-style ``predict(obs_batch, deterministic=...)``).

        :param on_episode: called after each episode with ``(index, distance, ball_lost)`` (a progress bar).
        :param perceive: the policy decides on the player's own perception (:mod:`robocup_dribble.rcss.perception`)
            instead of the exact state.
        :raises ValueError: if the episodes belong to another world.
        :raises ServerError: if the server dies, stops answering, refuses a command or drifts out of step.
        """
        if episodes.world_seed != self.world_seed:
            raise ValueError(f"the episodes are of world {episodes.world_seed}, the server's is {self.world_seed}")
        n = len(episodes.type_ids)
        distances, lost = np.zeros(n), np.zeros(n, dtype=bool)
        for j in range(n):
            distances[j], lost[j] = self.play_episode(
                policy, int(episodes.type_ids[j]), episodes.player_types[j], episodes.start_states[j], deterministic, perceive
            )
            if on_episode is not None:
                on_episode(j, float(distances[j]), bool(lost[j]))
        bounds = distance_bound(self.profile, self.task, episodes.player_types, episodes.start_states)
        return DribbleReport(distances, lost, episodes.player_types.copy(), episodes.start_states.copy(), bounds)

    def play_episode(
        self,
        policy: Any,
        type_id: int,
        player_type: np.ndarray,
        start: np.ndarray,
        deterministic: bool = True,
        perceive: bool = False,
    ) -> tuple[float, bool]:
        """One episode from ``start`` with the server's type ``type_id`` (whose parameters are ``player_type``);
        returns ``(distance, ball_lost)`` by the env's rules on the server's state. The policy's observation and
        the skills' commands come from that state, or with ``perceive`` from the player's estimate of it
        (:class:`robocup_dribble.rcss.perception.PerceivedWorld`)."""
        self.place(type_id, start)
        state = start.reshape(1, physics.STATE_SIZE).copy()
        believed = state[0].copy()  # what the policy and the skills act on
        world = PerceivedWorld(self.profile)
        world.start(start)
        types = np.asarray(player_type, dtype=np.float64).reshape(1, physics.TYPE_SIZE)
        command = np.empty(physics.COMMAND_SIZE)
        start_x, distance, ball_lost = float(state[0, physics.P_X]), 0.0, False
        for _ in range(self.task.max_actions):
            actions, _ = policy.predict(self.observe(believed, types[0]), deterministic=deterministic)
            kinds, params = parse_actions(actions)
            clipped = np.clip(params[0], self._param_low, self._param_high)
            skills.command_lane(believed, types[0], int(kinds[0]), clipped, self._k, command)
            previous_x = float(state[0, physics.P_X])
            window = self.act(
                protocol.player_command(int(command[physics.C_KIND]), command[physics.C_POWER], command[physics.C_DIRECTION])
            )
            if window.fullstate.player_type != type_id:
                raise ServerError(f"the server reports player type {window.fullstate.player_type}, the episode set {type_id}")
            state[0] = window.fullstate.state
            _, ball_lost = task.evaluate(state, 0, types, 0, window.collided, previous_x, self._c, self._k)
            if ball_lost:
                break
            distance = float(state[0, physics.P_X]) - start_x
            if perceive:
                seen = None if window.see is None else read_seen_ball(window.see)
                body = float(state[0, physics.P_BODY])
                believed = world.update(types[0], command, body, read_speed(window.sense_body), seen)
            else:
                believed = state[0].copy()
        return distance, bool(ball_lost)

    def observe(self, state: np.ndarray, player_type: np.ndarray) -> np.ndarray:
        """The env's observation ``(1, 10)`` of a state ``(STATE_SIZE,)`` for a player type ``(TYPE_SIZE,)``."""
        obs = np.empty((1, task.N_OBSERVATIONS), dtype=np.float32)
        states = np.asarray(state, dtype=np.float64).reshape(1, physics.STATE_SIZE)
        types = np.asarray(player_type, dtype=np.float64).reshape(1, physics.TYPE_SIZE)
        task.observe(states, 0, types, 0, self._obs_low, self._obs_high, obs, 0)
        return obs

    def place(self, type_id: int, start: np.ndarray) -> None:
        """Set an episode up in the current think window: type ``type_id``, recovery, ball parked, player and ball
        placed as in ``start`` ``(STATE_SIZE,)``; the trainer's look must confirm the placement."""
        if type_id != 0 and self.profile.name not in HETEROGENEOUS_CHECKED:
            raise ValueError(f"profile {self.profile.name!r} plays only the default type 0 on a real server, not {type_id}")
        if type_id != self.player_type:
            self._trainer_command(protocol.change_player_type(TEAM, UNUM, type_id))
            self.player_type = type_id
        self._trainer_command("(recover)")
        self._trainer_command(protocol.move_ball(*PARK_BALL))
        p, b = (
            start[[physics.P_X, physics.P_Y, physics.P_VX, physics.P_VY]],
            start[[physics.B_X, physics.B_Y, physics.B_VX, physics.B_VY]],
        )
        self._trainer_command(protocol.move_player(TEAM, UNUM, p[0], p[1], math.degrees(start[physics.P_BODY]), p[2], p[3]))
        self._trainer_command(protocol.move_ball(*b))
        placed = protocol.read_look(self._trainer_command("(look)"), TEAM, UNUM)
        expected = np.concatenate((p, b))
        if not np.allclose(placed, expected, rtol=PRINT_RTOL, atol=1e-5):
            raise ServerError(
                f"the trainer's look shows player and ball at {placed.tolist()}, they were placed at {expected.tolist()}"
            )

    def act(self, command: str | None) -> Window:
        """Send the player's ``command`` (None: none) in the current think window and play one cycle: the next
        :class:`Window`."""
        if command is not None:
            self.player.send(command)
        return self._finish_cycle()

    def _trainer_command(self, command: str) -> str:
        """Send a trainer command and return its ``(ok ...)`` answer."""
        self.trainer.send(command)
        name = command[1:].split(None, 1)[0].rstrip(")")
        while True:
            reply = self._trainer_reply(self.trainer.receive())
            if reply.startswith(f"(ok {name}"):
                return reply
            if protocol.kind(reply) == "ok":
                raise ServerError(f"the trainer's {command!r} was answered {reply[:200]!r}")

    def _trainer_reply(self, message: str, keep_see_global: bool = False) -> str:
        """``message`` unless it is an error; what the trainer also gets (parameters, its view) comes back as ``""``
        (the view ``(see_global ...)`` kept if asked)."""
        head = protocol.kind(message)
        if head in ("error", "warning"):
            raise ServerError(f"the server answered the trainer with {message[:200]!r}")
        if head in _PARAMETER_MESSAGES or head == "hear" or (head == "see_global" and not keep_see_global):
            return ""
        return message

    def _player_message(self, message: str) -> str:
        if protocol.kind(message) in ("error", "warning"):
            raise ServerError(f"the server answered the player with {message[:200]!r}")
        return message

    def _finish_cycle(self, catch_up: bool = False) -> Window:
        """Send ``(done)`` for both clients and read up to both ``(think)``: the player's new :class:`Window`.

        The trainer's ``(see_global TIME ...)`` gives the cycle; the player's fullstate must be of the same cycle.
        With ``catch_up`` (only when connecting: the player's first think window was sent before the trainer
        took part) the player's older windows are read past.
        """
        self.player.send("(done)")
        self.trainer.send("(done)")
        cycle = -1
        while (reply := self._trainer_reply(self.trainer.receive(), keep_see_global=True)) != "(think)":
            if protocol.kind(reply) == "see_global":
                cycle = protocol.read_time(reply)
        if cycle < 0:
            raise ServerError("a think window without the trainer's see_global (is the trainer's eye on?)")
        while True:
            window = self._player_window()
            if window.fullstate.time == cycle:
                break
            if not (catch_up and window.fullstate.time < cycle):
                raise ServerError(
                    f"the player's fullstate is of cycle {window.fullstate.time}, the trainer's of {cycle}: out of step"
                )
        if self.time >= 0 and cycle != self.time + 1:
            raise ServerError(f"the server went from cycle {self.time} to {cycle}; expected one cycle per (done)")
        self.time = cycle
        return window

    def _player_window(self) -> Window:
        """The player's messages up to the next ``(think)``."""
        fullstate: protocol.FullState | None = None
        sense_body: str | None = None
        see: str | None = None
        referee: list[str] = []
        while (message := self._player_message(self.player.receive())) != "(think)":
            head = protocol.kind(message)
            if head == "hear" and (said := protocol.read_referee(message)) is not None:
                referee.append(said)
            elif head == "fullstate":
                fullstate = protocol.read_fullstate(message, "l", UNUM)
            elif head == "sense_body":
                sense_body = message
            elif head == "see":
                see = message
        if fullstate is None or sense_body is None:
            raise ServerError("a think window without the player's fullstate and sense_body (is fullstate_l on?)")
        return Window(fullstate, protocol.read_collision(sense_body), sense_body, see, tuple(referee))


__all__ = [
    "PROTOCOL_VERSION",
    "PROTOCOL_VERSIONS",
    "TEAM",
    "ProtocolError",
    "ServerEpisodes",
    "ServerSession",
    "check_server",
    "checked_profile",
    "server_episodes",
    "server_options",
]
