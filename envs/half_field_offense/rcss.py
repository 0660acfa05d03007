"""Half Field Offense trials on HFO's own rcssserver (the 15.2.2 fork, ``mhauskn/rcssserver``) in HFO mode, with its
referee ``HFORef`` starting and judging the trials, and the same trials replayed in the env.

Usage::

    HFO_RCSSSERVER=/path/to/hfo/rcssserver python -m half_field_offense.rcss record OUT.jsonl
    HFO_RCSSSERVER=/path/to/hfo/rcssserver python -m half_field_offense.rcss compare --trials 1000

(``HFO_RCSSSERVER``: the rcssserver binary of HFO's fork, built as ``data/README.md`` says; rcssserver 19 has no
HFO mode and refuses the client protocol 15.)

``record`` writes noise-free trials cycle by cycle (the shipped ``data/rcss-hfo.jsonl``, replayed by
``tests/test_half_field_offense.py``): the hand-coded agent's, trials that kick the ball out of bounds, trials that
leave the ball untouched, and (with ``hfo_max_trial_time`` 40) trials ended by the cycle cap. ``compare`` plays the
hand-coded agent on the server with its noise on, then the same start states in the env with the env's noise, and
prints P(goal) and the mean cycles to a goal of both with tests on the differences (``--aim 6.5
--shooting-distance 35``: every shot from 35 m goes 0.5 m inside the post, where the kick noise decides).

The server runs HFO's options (``server::hfo``, ``coach_w_referee``, the trial settings of :class:`HFOTask`) with
:func:`robocup_dribble.rcss.client.server_options` for the ``v15`` profile (synchronous mode, fullstate, a trainer
with eye on, no HFO team binaries: the one offense player is this client, no defense, no goalie). The referee places
ball and player (``resetField``) one cycle after it called a trial's end and reports to the player what it said
(``(hear T referee GOAL-1)``, ``OUT_OF_BOUNDS``, ``OUT_OF_TIME``, ``IN_GAME-L1``); the trial the trainer's
``play_on`` starts is played out unrecorded (it starts inside a think window, one cycle out of the usual step).
The agent acts on the 59 features of the exact state (:func:`half_field_offense.features.observe` on the fullstate)
through the env's command transforms (:func:`half_field_offense.actions.command`).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from half_field_offense import actions, features, referee
from half_field_offense.agent import HandCodedOffense
from half_field_offense.lanes import HFOLanes
from half_field_offense.task import HFOTask
from robocup_dribble import physics
from robocup_dribble.params import PITCH_HALF_LENGTH, make_profile, without_noise
from robocup_dribble.player_types import default_player_type, stack_player_types
from robocup_dribble.rcss import protocol
from robocup_dribble.rcss.client import PROTOCOL_VERSIONS, ServerSession, Window, server_options
from robocup_dribble.rcss.server import ServerError, ServerProcess

SERVER_VARIABLE = "HFO_RCSSSERVER"
"""The environment variable naming the rcssserver binary of HFO's fork."""
SERVER_VERSION = "15.2.2 (HFO's fork, mhauskn/rcssserver@82212ee)"
PROFILE = "v15"
WORLD_SEED = 1
"""``player::random_seed`` (the heterogeneous types; HFO plays the default type 0)."""
RECORDING = Path(__file__).parent / "data" / "rcss-hfo.jsonl"
"""The shipped noise-free trials (``data/README.md``)."""
RECORD_FIELDS = ("px", "py", "pvx", "pvy", "body", "bx", "by", "bvx", "bvy", "stamina", "effort", "recovery", "capacity")
"""A recorded state's numbers, as the fullstate prints them (``body`` in degrees)."""
STATUS_WORDS = {"GOAL": referee.GOAL, "OUT_OF_BOUNDS": referee.OUT_OF_BOUNDS, "OUT_OF_TIME": referee.OUT_OF_TIME}
"""The first word (before ``-``) of what HFORef says at a trial's end, by the env's status code."""

Policy = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
"""Decides actions ``(types (n,), parameters (n, 5))`` from observations ``(n, 59)`` and the exact states
``(n, STATE_SIZE)``."""


def hfo_options(task: HFOTask, noise: bool, seed: int) -> dict[str, object]:
    """The server options of an HFO session: the v15 client options plus HFO mode with ``task``'s trial settings;
    ``server::random_seed = seed`` seeds the referee's start draws (and the noise)."""
    profile = make_profile(PROFILE) if noise else without_noise(make_profile(PROFILE))
    return {
        **server_options(profile, WORLD_SEED),
        "server::coach_w_referee": True,
        "server::hfo": True,
        "server::hfo_max_trial_time": task.frames_per_trial,
        "server::hfo_max_untouched_time": task.untouched_time,
        "server::hfo_min_ball_pos_x": task.ball_x_min,
        "server::hfo_max_ball_pos_x": task.ball_x_max,
        "server::hfo_min_ball_pos_y": task.ball_y_min,
        "server::hfo_max_ball_pos_y": task.ball_y_max,
        "server::hfo_offense_on_ball": int(task.offense_on_ball),
        "server::random_seed": int(seed),
    }


@dataclass
class Trial:
    """One trial on the server: its start state, every action, command and state after each cycle, and the
    referee's call (``status`` a :data:`half_field_offense.referee.STATUS_NAMES` code, after ``cycles`` cycles)."""

    start: np.ndarray  # (STATE_SIZE,)
    kinds: list[int]
    params: list[list[float]]
    commands: list[str | None]
    states: list[np.ndarray]
    status: int
    cycles: int


class HFOServer:
    """A connected player and trainer on HFO's server in HFO mode; plays one trial after another.

    :param session: an unopened :class:`ServerSession` for profile v15 (noise as the server's options).
    :param task: the trial settings the server was started with.
    """

    def __init__(self, session: ServerSession, task: HFOTask) -> None:
        self.session, self.task = session, task
        self.k, self.c = physics.profile_constants(session.profile), task.constants()
        self.types = stack_player_types([default_player_type(session.profile)])
        self.start = physics.new_state(1)[0]
        self.last_ok = False

    def open(self) -> None:
        """Connect, let the referee start its first trial, play it out idle and wait for the next start."""
        self.session.open()
        while not self._said_end(self.session.act(None)):
            pass
        self.start = self._next_start()

    def play(self, policy: Policy) -> Trial:
        """Play the current trial with ``policy`` up to the referee's call; then wait for the next start."""
        state = self.start.copy()
        trial = Trial(self.start.copy(), [], [], [], [], referee.IN_GAME, 0)
        obs = np.empty((1, features.N_FEATURES), dtype=np.float32)
        window: Window | None = None
        while True:
            collided = window is not None and window.collided
            posted = window is not None and "post" in protocol.read_collisions(window.sense_body)
            features.observe(state[None], 0, self.types, 0, collided, posted, self.last_ok, self.c, self.k, obs, 0)
            kinds, batch = policy(obs, state[None])
            kind, params = int(kinds[0]), batch[0]
            clipped = np.clip(params, actions.PARAM_LOW[: len(params)], actions.PARAM_HIGH[: len(params)])
            first = int(actions.PARAM_STARTS[kind])
            b = clipped[first + 1] if actions.PARAM_SIZES[kind] > 1 else 0.0
            code, power, direction, self.last_ok = actions.command(
                state[None], 0, self.types, 0, kind, clipped[first], b, self.k
            )
            text = None if code == physics.CMD_NONE else protocol.player_command(code, power, direction)
            window = self.session.act(text)
            state = window.fullstate.state.copy()
            trial.kinds.append(int(kind))
            trial.params.append([float(v) for v in params])
            trial.commands.append(text)
            trial.states.append(state)
            status = self._said_end(window)
            if status:
                trial.status, trial.cycles = status, len(trial.states)
                break
        self.start = self._next_start()
        return trial

    def _said_end(self, window: Window) -> int:
        """The status code the referee called in ``window`` (0, IN_GAME, when none)."""
        for said in window.referee:
            word = said.split("-", 1)[0]
            if word in STATUS_WORDS:
                return STATUS_WORDS[word]
            if word == "CAPTURED_BY_DEFENSE":
                raise ServerError(f"the referee said {said!r}: there is no defense in a 1v0 session")
        return referee.IN_GAME

    def _next_start(self) -> np.ndarray:
        """Send nothing for the cycle after a call, in which the referee places the next trial; its state."""
        window = self.session.act(None)
        if "play_on" not in window.referee:
            raise ServerError(f"the referee did not restart the trial one cycle after its call: it said {window.referee}")
        start: np.ndarray = window.fullstate.state.copy()
        return start


def _printed_state(state: np.ndarray) -> list[float]:
    values = [float(state[physics.STATE_FIELDS.index(name)]) for name in RECORD_FIELDS]
    values[RECORD_FIELDS.index("body")] = math.degrees(values[RECORD_FIELDS.index("body")])
    return [float(f"{v:.6g}") for v in values]


def read_state(values: Sequence[float]) -> np.ndarray:
    """A recorded state (:data:`RECORD_FIELDS`) as the env's ``(STATE_SIZE,)`` state (not frozen)."""
    state: np.ndarray = physics.new_state(1)[0]
    for name, value in zip(RECORD_FIELDS, values, strict=True):
        state[physics.STATE_FIELDS.index(name)] = value
    state[physics.P_BODY] = math.radians(state[physics.P_BODY])
    return state


def trial_record(trial: Trial, index: int, group: str, task: HFOTask, options: dict[str, object]) -> dict[str, Any]:
    """One trial as a line of the recording."""
    return {
        "id": f"{index:03d}-{group}",
        "group": group,
        "server_version": SERVER_VERSION,
        "protocol_version": PROTOCOL_VERSIONS[PROFILE],
        "profile": PROFILE,
        "server_options": options,
        "task": asdict(task),
        "state_fields": list(RECORD_FIELDS),
        "start": _printed_state(trial.start),
        "actions": [[kind, *params] for kind, params in zip(trial.kinds, trial.params, strict=True)],
        "commands": trial.commands,
        "states": [_printed_state(s) for s in trial.states],
        "status": referee.STATUS_NAMES[trial.status],
        "cycles": trial.cycles,
    }


def hand_coded(agent: HandCodedOffense) -> Policy:
    """``agent`` as a :data:`Policy`."""

    def policy(obs: np.ndarray, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return agent.act(obs)

    return policy


def kick_at(agent: HandCodedOffense, target: tuple[float, float], shots_only: bool = False) -> Policy:
    """``agent``, but each of its kicks (with ``shots_only`` each kick within its shooting distance of the goal
    centre) goes with full power from the ball towards ``target`` (m)."""
    kick = int(actions.PARAM_STARTS[actions.KICK])

    def policy(obs: np.ndarray, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        kinds, params = agent.act(obs)
        px, py = states[:, physics.P_X], states[:, physics.P_Y]
        kicking = kinds == actions.KICK
        if shots_only:
            kicking &= np.hypot(PITCH_HALF_LENGTH - px, py) < agent.shooting_distance
        bx, by = states[:, physics.B_X], states[:, physics.B_Y]
        bearing = np.arctan2(target[1] - by, target[0] - bx) - states[:, physics.P_BODY]
        params[kicking, kick] = 100.0
        params[kicking, kick + 1] = np.degrees(np.remainder(bearing + np.pi, 2.0 * np.pi) - np.pi)[kicking]
        return kinds, params

    return policy


def idle(obs: np.ndarray, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Turn by nothing every cycle (the ball stays untouched)."""
    return np.full(len(obs), actions.TURN, dtype=np.int64), np.zeros((len(obs), actions.n_params(False)))


def record(binary: str | Path, path: Path, hand_coded_trials: int = 10) -> int:
    """Record the noise-free trials (module docstring, with ``hand_coded_trials`` of the hand-coded agent) into
    ``path``; returns their number."""
    task, capped, agent = HFOTask(), HFOTask(frames_per_trial=40), HandCodedOffense()
    plans: list[tuple[HFOTask, list[tuple[str, Policy]]]] = [
        (task, [("hand_coded", hand_coded(agent))] * hand_coded_trials
         + [("kick_out_side", kick_at(agent, (30.0, 40.0))), ("kick_out_back", kick_at(agent, (-10.0, 0.0))),
            ("kick_out_wide", kick_at(agent, (60.0, 20.0))), ("kick_out_side", kick_at(agent, (20.0, -40.0)))]
         + [("untouched", idle)] * 2),
        (capped, [("capped", hand_coded(agent))] * 2),
    ]  # fmt: skip
    index = 0
    with path.open("w") as out:
        for seed, (settings, plan) in enumerate(plans, start=1):
            options = hfo_options(settings, noise=False, seed=seed)
            with ServerProcess(binary, options) as process:
                player, trainer = process.endpoints()
                server = HFOServer(
                    ServerSession(player, trainer, without_noise(make_profile(PROFILE)), WORLD_SEED, noise=False), settings
                )
                server.open()
                for group, policy in plan:
                    index += 1
                    out.write(json.dumps(trial_record(server.play(policy), index, group, settings, options)) + "\n")
                if process.missed_cycles():
                    raise RuntimeError(f"the recorder missed {process.missed_cycles()} cycle(s): record again")
    return index


def read_trials(path: str | Path = RECORDING) -> list[dict[str, Any]]:
    """The trials of a recording, one dict a line."""
    with Path(path).open() as lines:
        return [json.loads(line) for line in lines if line.strip()]


def replay(record_line: dict[str, Any], resync: bool) -> tuple[np.ndarray, list[int], np.ndarray]:
    """Replay a recorded trial in :class:`HFOLanes` (noise-free v15): place its start state and step its actions,
    each from the recorded state before it (``resync``: every cycle checked on its own) or from the env's own (the
    whole trial open loop); returns the env's states ``(cycles, STATE_SIZE)``, its status code per cycle, and the
    recorded states."""
    task = HFOTask(**record_line["task"])
    lanes = HFOLanes(1, without_noise(make_profile(PROFILE)), task, np.random.default_rng(0))
    recorded = np.array([read_state(s) for s in record_line["states"]])
    lanes.place(np.array([0]), read_state(record_line["start"])[None])
    states, codes = [], []
    for cycle, (kind, *params) in enumerate(record_line["actions"]):
        if resync and cycle > 0:
            lanes.state[0] = recorded[cycle - 1]
            lanes.previous_ball[0] = recorded[cycle - 1, [physics.B_X, physics.B_Y]]
        step = lanes.step(np.array([kind]), np.array([params]), autoreset=False)
        states.append(lanes.state[0].copy())
        codes.append(int(step.status[0]))
    return np.array(states), codes, recorded


@dataclass(frozen=True)
class Outcomes:
    """Each trial's status code and cycles."""

    status: np.ndarray
    cycles: np.ndarray

    @property
    def goals(self) -> np.ndarray:
        """``(n,)`` bool: the trial ended in a goal."""
        goals: np.ndarray = self.status == referee.GOAL
        return goals


def server_trials(binary: str | Path, n_trials: int, seed: int, task: HFOTask, policy: Policy) -> tuple[np.ndarray, Outcomes]:
    """``n_trials`` trials of ``policy`` on the server with its noise on: start states ``(n, STATE_SIZE)`` and
    outcomes."""
    options = hfo_options(task, noise=True, seed=seed)
    starts, status, cycles = physics.new_state(n_trials), np.zeros(n_trials, np.int64), np.zeros(n_trials, np.int64)
    with ServerProcess(binary, options) as process:
        player, trainer = process.endpoints()
        server = HFOServer(ServerSession(player, trainer, make_profile(PROFILE), WORLD_SEED, noise=True), task)
        server.open()
        for j in range(n_trials):
            trial = server.play(policy)
            starts[j], status[j], cycles[j] = trial.start, trial.status, trial.cycles
        if process.missed_cycles():
            raise RuntimeError(f"the server missed {process.missed_cycles()} cycle(s): the trials are not the env's")
    return starts, Outcomes(status, cycles)


def env_trials(starts: np.ndarray, seed: int, task: HFOTask, policy: Policy) -> Outcomes:
    """``policy``'s trials in the env (v15 with noise) from the given start states."""
    n = len(starts)
    lanes = HFOLanes(n, make_profile(PROFILE), task, np.random.default_rng(seed))
    obs = lanes.place(np.arange(n), starts)
    status, cycles = np.zeros(n, np.int64), np.zeros(n, np.int64)
    while not status.all():
        kinds, params = policy(obs, lanes.state)
        step = lanes.step(kinds, params, autoreset=False)
        ended = (status == referee.IN_GAME) & (step.status != referee.IN_GAME)
        status[ended], cycles[ended] = step.status[ended], lanes.steps[ended]
        obs = step.observations
    return Outcomes(status, cycles)


def two_proportion_test(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """``(z, two-sided p)`` of the pooled two-proportion z test of the rates of boolean samples ``a`` and ``b``."""
    pooled = (a.sum() + b.sum()) / (len(a) + len(b))
    se = math.sqrt(pooled * (1.0 - pooled) * (1.0 / len(a) + 1.0 / len(b)))
    z = 0.0 if se == 0.0 else (a.mean() - b.mean()) / se
    return z, math.erfc(abs(z) / math.sqrt(2.0))


def welch_test(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """``(t, two-sided p)`` of Welch's test of the means of ``a`` and ``b`` (normal approximation, large samples)."""
    se = math.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b))
    t = (a.mean() - b.mean()) / se
    return t, math.erfc(abs(t) / math.sqrt(2.0))


def paired_test(differences: np.ndarray) -> tuple[float, float]:
    """``(t, two-sided p)`` of the paired test that ``differences`` have mean 0 (normal approximation)."""
    se = differences.std(ddof=1) / math.sqrt(len(differences))
    t = 0.0 if se == 0.0 else differences.mean() / se
    return t, math.erfc(abs(t) / math.sqrt(2.0))


def ks_test(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """``(D, p)`` of the two-sample Kolmogorov-Smirnov test (asymptotic p, Stephens' correction); both samples are
    rounded to 6 significant digits first (as the server prints them) so that values clipped to a bound tie."""
    a, b = (np.sort(np.array([float(f"{v:.6g}") for v in x])) for x in (a, b))
    grid = np.concatenate((a, b))
    d = float(np.abs(np.searchsorted(a, grid, "right") / len(a) - np.searchsorted(b, grid, "right") / len(b)).max())
    n = math.sqrt(len(a) * len(b) / (len(a) + len(b)))
    lam = (n + 0.12 + 0.11 / n) * d
    p = 2.0 * sum((-1) ** (k - 1) * math.exp(-2.0 * k * k * lam * lam) for k in range(1, 101))
    return d, min(max(p, 0.0), 1.0)


def start_tests(starts: np.ndarray, seed: int, task: HFOTask) -> dict[str, tuple[float, float, float, float]]:
    """The server referee's start positions against as many starts of the env's referee (``HFOLanes.reset``): per
    coordinate ``(server mean, env mean, KS D, p)`` of a two-sample KS test."""
    lanes = HFOLanes(len(starts), make_profile(PROFILE), task, np.random.default_rng(seed))
    lanes.reset(np.arange(len(starts)))
    names = {"ball x": physics.B_X, "ball y": physics.B_Y, "player x": physics.P_X, "player y": physics.P_Y}
    return {
        name: (
            float(starts[:, column].mean()),
            float(lanes.state[:, column].mean()),
            *ks_test(starts[:, column], lanes.state[:, column]),
        )
        for name, column in names.items()
    }


def matched_trials(
    binary: str | Path, n_trials: int, seed: int, shooting_distance: float = 25.0, aim: float | None = None
) -> tuple[np.ndarray, Outcomes, Outcomes]:
    """The start states ``(n, STATE_SIZE)`` and the ``(server, env)`` outcomes of ``n_trials`` trials of
    :class:`HandCodedOffense` (shooting from ``shooting_distance``; with ``aim`` every shot goes at (52.5, aim)
    instead of the goal centre) from the server referee's start states (``server::random_seed = seed``), both with
    noise (the env's from ``numpy.random.default_rng(seed)``)."""
    task = HFOTask()
    agent = HandCodedOffense(task.distance_normaliser, task.tackle, shooting_distance=shooting_distance)
    policy = hand_coded(agent) if aim is None else kick_at(agent, (PITCH_HALF_LENGTH, aim), shots_only=True)
    starts, real = server_trials(binary, n_trials, seed, task, policy)
    return starts, real, env_trials(starts, seed, task, policy)


def compare(binary: str | Path, n_trials: int, seed: int, shooting_distance: float = 25.0, aim: float | None = None) -> str:
    """The figures of :func:`matched_trials` as text."""
    starts, real, sim = matched_trials(binary, n_trials, seed, shooting_distance, aim)
    aimed = "the goal centre" if aim is None else f"(52.5, {aim:g})"
    z, p = two_proportion_test(real.goals, sim.goals)
    both = real.goals & sim.goals
    only_real, only_sim = int((real.goals & ~sim.goals).sum()), int((sim.goals & ~real.goals).sum())
    t, p_steps = welch_test(real.cycles[real.goals].astype(float), sim.cycles[sim.goals].astype(float))
    pairs = (real.cycles[both] - sim.cycles[both]).astype(float)
    t_pairs, p_pairs = paired_test(pairs)
    lines = [
        f"{n_trials} matched trials (server seed {seed}): the hand-coded agent shooting from {shooting_distance:g} m "
        f"at {aimed}, HFO 1v0, noise on",
        f"P(goal)   server {real.goals.mean():.4f}   env {sim.goals.mean():.4f}   difference "
        f"{real.goals.mean() - sim.goals.mean():+.4f}   two-proportion z {z:+.2f}, p {p:.3f}",
        f"          goals in both {int(both.sum())}, only on the server {only_real}, only in the env {only_sim}",
        f"steps to goal (mean)   server {real.cycles[real.goals].mean():.2f}   env {sim.cycles[sim.goals].mean():.2f}"
        f"   Welch t {t:+.2f}, p {p_steps:.3f}",
        f"          paired on the {len(pairs)} trials scored in both: server - env {pairs.mean():+.2f} cycles "
        f"(sd {pairs.std(ddof=1):.2f}), t {t_pairs:+.2f}, p {p_pairs:.3f}",
    ]
    for name, outcomes in (("server", real), ("env", sim)):
        counts = {referee.STATUS_NAMES[c]: int((outcomes.status == c).sum()) for c in range(1, len(referee.STATUS_NAMES))}
        lines.append(f"statuses {name}: {counts}")
    for name, (mean_real, mean_sim, d, p_start) in start_tests(starts, seed, HFOTask()).items():
        lines.append(f"start {name}: mean server {mean_real:.3f} env {mean_sim:.3f}, KS D {d:.4f}, p {p_start:.3f}")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m half_field_offense.rcss", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    recording = commands.add_parser("record", help="record the noise-free trials")
    recording.add_argument("out", type=Path, help="the .jsonl file to write")
    matched = commands.add_parser("compare", help="P(goal) and steps to goal, server vs env, on matched trials")
    matched.add_argument("--trials", type=int, default=1000)
    matched.add_argument("--seed", type=int, default=1, help="the server's random_seed and the env's generator seed")
    matched.add_argument("--shooting-distance", type=float, default=25.0, help="the agent's (m; default: %(default)s)")
    matched.add_argument("--aim", type=float, default=None, help="shoot at (52.5, AIM) m (default: the goal centre)")
    args = parser.parse_args(argv)
    binary = os.environ.get(SERVER_VARIABLE)
    if not binary:
        print(f"error: no rcssserver binary: set {SERVER_VARIABLE} to HFO's rcssserver (its 15.2.2 fork)", file=sys.stderr)
        return 2
    if args.command == "record":
        print(f"recorded {record(binary, args.out)} trials into {args.out}")
    else:
        print(compare(binary, args.trials, args.seed, args.shooting_distance, args.aim))
    return 0


if __name__ == "__main__":
    sys.exit(main())
