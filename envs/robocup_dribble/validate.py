"""Replay cases recorded from a real rcssserver and compare them with this package's physics.

Usage::

    python -m robocup_dribble.validate [CASES.jsonl ...] [--verbose]

Without files it replays the rcssserver 19.0.0 recordings shipped in :data:`GOLDEN_DIR` (``robocup_dribble/data/
golden``, provenance and format in its ``README.md``): the dribbling cases and the cases at the goals (goal posts,
tackles, kicks over the goal line). Each line of a file is one recorded case in that format: the server options,
the player type, the exact set-up, one command (or none) per cycle and the state the server printed after each cycle.
The case is replayed from its set-up with a profile built from the recorded ``server::`` options and every printed
number is compared with a tolerance of ``rtol * |recorded| + atol`` (the server prints 6 significant digits); the
ball and post collisions of ``collision`` and, where recorded, the tackle countdown ``tackle_expires`` must agree.
A case with a heterogeneous player type takes the type from :func:`generate_player_types` with the recorded
``player::random_seed`` and ``player::kick_rand_delta_factor``, not from the rounded printed values.

Cases recorded with noise (``runs`` instead of ``states``) cannot be replayed draw by draw: they are listed as
skipped here and checked statistically by the test suite. The exit status is 1 if any case is off, 2 for unreadable
input, 0 otherwise, so a team can record its own server and check this simulator against it.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from robocup_dribble import physics
from robocup_dribble.params import PROFILES, ServerParams, ServerProfile, make_profile
from robocup_dribble.player_types import PlayerType, default_player_type, generate_player_types, stack_player_types

GOLDEN_DIR = Path(__file__).resolve().parent / "data" / "golden"
"""The recorded rcssserver 19.0.0 cases shipped with the package (see its README.md)."""
GOLDEN_FILES = ("rcss-deterministic.jsonl", "rcss-goal.jsonl", "rcss-noise.jsonl")
"""The files replayed when no file is given."""
RTOL = 1e-5  # the server prints 6 significant digits
ATOL = 1e-6
_COMPARED: tuple[tuple[str, Callable[[dict[str, Any]], float], int], ...] = (
    ("player.x", lambda s: s["player"]["x"], physics.P_X),
    ("player.y", lambda s: s["player"]["y"], physics.P_Y),
    ("player.vx", lambda s: s["player"]["vx"], physics.P_VX),
    ("player.vy", lambda s: s["player"]["vy"], physics.P_VY),
    ("ball.x", lambda s: s["ball"]["x"], physics.B_X),
    ("ball.y", lambda s: s["ball"]["y"], physics.B_Y),
    ("ball.vx", lambda s: s["ball"]["vx"], physics.B_VX),
    ("ball.vy", lambda s: s["ball"]["vy"], physics.B_VY),
    ("stamina", lambda s: s["stamina"], physics.S_STAMINA),
    ("effort", lambda s: s["effort"], physics.S_EFFORT),
    ("recovery", lambda s: s["recovery"], physics.S_RECOVERY),
    ("stamina_capacity", lambda s: s["stamina_capacity"], physics.S_CAPACITY),
)
_COMMANDS = {"dash": physics.CMD_DASH, "kick": physics.CMD_KICK, "turn": physics.CMD_TURN, "tackle": physics.CMD_TACKLE}


@dataclasses.dataclass(frozen=True)
class CaseResult:
    """How far a replayed case is from the recording."""

    case_id: str
    cycles: int
    max_abs_error: float
    worst_ratio: float  # the largest error divided by its tolerance; <= 1 passes
    worst_field: str
    worst_cycle: int
    flag_mismatches: tuple[str, ...]

    @property
    def passed(self) -> bool:
        return self.worst_ratio <= 1.0 and not self.flag_mismatches


def read_cases(path: str | Path) -> Iterator[dict[str, Any]]:
    """Yield the JSON records of a ``.jsonl`` file, with a clear error for a malformed line."""
    with open(path) as file:
        for number, line in enumerate(file, start=1):
            if not line.strip():
                continue
            try:
                yield json.loads(line)
            except json.JSONDecodeError as error:
                raise ValueError(f"{path}:{number}: not a JSON record ({error.msg})") from error


def case_profile(case: dict[str, Any]) -> ServerProfile:
    """The server profile a case was recorded with: its version's profile plus its ``server::`` options."""
    version = str(case.get("server_version", "19"))
    base = PROFILES["v11"] if version.startswith("11.") else PROFILES["v19"]
    known = {field.name for field in dataclasses.fields(ServerParams)}
    options = _options(case)
    overrides = {key[8:]: float(value) for key, value in options.items() if key.startswith("server::") and key[8:] in known}
    return make_profile(base, **overrides)


def case_player_type(case: dict[str, Any], profile: ServerProfile) -> PlayerType:
    """Type 0 from the profile; other types regenerated from the recorded ``player::`` options."""
    type_id = int(case.get("player_type_id", 0))
    if type_id == 0:
        return default_player_type(profile)
    options = _options(case)
    if "player::random_seed" not in options:
        raise ValueError(f"case {case.get('id')}: heterogeneous type {type_id} needs player::random_seed in server_options")
    factor = options.get("player::kick_rand_delta_factor")
    types = generate_player_types(
        profile, seed=int(options["player::random_seed"]), kick_rand_delta_factor=None if factor is None else float(factor)
    )
    return types[type_id]


def parse_command(text: str | None) -> tuple[int, float, float]:
    """``"(dash 100 45)"`` -> ``(CMD_DASH, 100.0, 45.0)``; ``"(tackle 30)"`` -> ``(CMD_TACKLE, 0.0, 30.0)`` (the v12+
    tackle's argument is its direction); ``None`` -> no command."""
    if text is None:
        return physics.CMD_NONE, 0.0, 0.0
    words = text.strip().strip("()").split()
    if not words or words[0] not in _COMMANDS or not 2 <= len(words) <= 3:
        raise ValueError(f"unsupported command {text!r}; expected (dash P [D]), (kick P D), (turn M) or (tackle D)")
    values = [float(word) for word in words[1:]]
    if words[0] == "tackle":
        return physics.CMD_TACKLE, 0.0, values[0]
    return _COMMANDS[words[0]], values[0], values[1] if len(values) > 1 else 0.0


def simulate_case(
    case: dict[str, Any], runs: int = 1, rng: np.random.Generator | None = None, profile: ServerProfile | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Run a recorded case's commands from its set-up in ``runs`` independent lanes.

    :param rng: source of the noise draws; None runs noise-free (every draw 0.5, right for zero noise parameters).
    :param profile: the server profile to simulate; default :func:`case_profile` (the recorded server).
    :return: states ``(runs, cycles, STATE_SIZE)`` after each cycle and events ``(runs, cycles, EVENT_SIZE)``.
    """
    profile = profile or case_profile(case)
    types = np.repeat(stack_player_types([case_player_type(case, profile)]), runs, axis=0)
    state = physics.new_state(runs)
    physics.recover(state, types, profile)
    player, ball = case["setup"]["player"], case["setup"]["ball"]
    state[:, [physics.P_X, physics.P_Y, physics.P_VX, physics.P_VY]] = player["x"], player["y"], player["vx"], player["vy"]
    state[:, physics.P_BODY] = math.radians(player["body"])
    state[:, [physics.B_X, physics.B_Y, physics.B_VX, physics.B_VY]] = ball["x"], ball["y"], ball["vx"], ball["vy"]
    constants = physics.profile_constants(profile)
    states, events = [], []
    for command in case["commands"]:
        commands = np.zeros((runs, physics.COMMAND_SIZE))
        commands[:, physics.C_KIND], commands[:, physics.C_POWER], commands[:, physics.C_DIRECTION] = parse_command(command)
        uniforms = np.full((runs, physics.N_UNIFORMS), 0.5) if rng is None else rng.random((runs, physics.N_UNIFORMS))
        events.append(physics.step(state, types, commands, uniforms, constants))
        states.append(state.copy())
    return np.stack(states, axis=1), np.stack(events, axis=1)


def replay_case(
    case: dict[str, Any], rtol: float = RTOL, atol: float = ATOL, profile: ServerProfile | None = None
) -> CaseResult:
    """Replay one deterministic case and measure its largest deviation from the recording.

    :param profile: the server profile to simulate; default :func:`case_profile` (the recorded server).
    """
    states, events = simulate_case(case, profile=profile)
    worst = (0.0, 0.0, "", 0)  # ratio, abs error, field, cycle
    mismatches: list[str] = []
    for cycle, (command, recorded) in enumerate(zip(case["commands"], case["states"], strict=True), start=1):
        state, event = states[0, cycle - 1], events[0, cycle - 1]
        for name, read, column in _COMPARED:
            worst = max(worst, _deviation(state[column], read(recorded), rtol, atol, name, cycle))
        body = math.degrees(state[physics.P_BODY])
        body_error = abs((body - recorded["player"]["body"] + 180.0) % 360.0 - 180.0)
        worst = max(worst, (body_error / (rtol * abs(recorded["player"]["body"]) + 1e-4), body_error, "player.body", cycle))
        for flag, column in (("ball", physics.E_COLLISION), ("post", physics.E_POST)):
            collided = flag in recorded.get("collision", [])
            if bool(event[column]) != collided:
                mismatches.append(f"{flag} collision at cycle {cycle}: recorded {collided}")
        if "tackle_expires" in recorded and state[physics.S_FROZEN] != recorded["tackle_expires"]:
            mismatches.append(f"tackle countdown at cycle {cycle}: recorded {recorded['tackle_expires']}")
        if recorded.get("kick_ok") is not None and command and command.startswith("(kick"):
            if bool(event[physics.E_KICK_OK]) != recorded["kick_ok"]:
                mismatches.append(f"kick_ok at cycle {cycle}: recorded {recorded['kick_ok']}")
    ratio, error, field, cycle = worst
    return CaseResult(case.get("id", "?"), len(case["states"]), error, ratio, field, cycle, tuple(mismatches))


def _deviation(
    simulated: float, recorded: float, rtol: float, atol: float, name: str, cycle: int
) -> tuple[float, float, str, int]:
    error = abs(simulated - recorded)
    return error / (rtol * abs(recorded) + atol), error, name, cycle


def _options(case: dict[str, Any]) -> dict[str, Any]:
    options: dict[str, Any] | str = case.get("server_options", {})
    if isinstance(options, str):  # some recorders store the dict's repr
        raise ValueError(f"case {case.get('id')}: server_options must be a JSON object")
    return options


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m robocup_dribble.validate", description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "files",
        nargs="*",
        type=Path,
        default=[GOLDEN_DIR / name for name in GOLDEN_FILES],
        help="recorded cases, one JSON object per line (.jsonl); default: the shipped rcssserver 19.0.0 recordings",
    )
    parser.add_argument("--rtol", type=float, default=RTOL, help="relative tolerance (default: %(default)s)")
    parser.add_argument("--atol", type=float, default=ATOL, help="absolute tolerance (default: %(default)s)")
    parser.add_argument("--verbose", action="store_true", help="print passing cases too")
    args = parser.parse_args(argv)

    failed = checked = skipped = 0
    for path in args.files:
        if not path.is_file():
            print(f"error: {path} is not a file", file=sys.stderr)
            return 2
        try:
            cases = list(read_cases(path))
        except ValueError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
        for case in cases:
            if "states" not in case:
                skipped += 1
                if args.verbose:
                    print(f"SKIP {case.get('id', '?')}: recorded with noise ({case.get('repetitions', '?')} runs)")
                continue
            result = replay_case(case, args.rtol, args.atol)
            checked += 1
            failed += not result.passed
            if args.verbose or not result.passed:
                status = "OK  " if result.passed else "FAIL"
                detail = "; ".join(result.flag_mismatches)
                print(
                    f"{status} {result.case_id}: {result.cycles} cycles, max error {result.max_abs_error:.2e} "
                    f"({result.worst_ratio:.2f} of tolerance, {result.worst_field} at cycle {result.worst_cycle}) {detail}"
                )
    print(f"{checked - failed} passed, {failed} failed, {skipped} skipped (noise cases)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
