"""Record noise-free cycle-level cases at the goals on a real rcssserver, in the golden record format.

Usage::

    RCSSSERVER=/path/to/rcssserver python -m robocup_dribble.rcss.record OUT.jsonl

The cases (:data:`CASES`) exercise what the dribbling recordings keep far from: the goal posts (a ball and a player
bouncing off one, an object placed inside one), the tackle and the cycles it freezes the player for, and kicks into
the goal and over the goal line wide of it. The server runs with :func:`robocup_dribble.rcss.client.server_options`
for the v19 profile without noise and ``player::random_seed = 1`` (the options of ``rcss-deterministic.jsonl``);
without the referee (trainer mode) nothing moves the ball after it crosses a line, so every cycle is physics.
Each case is set up inside one think window by :meth:`ServerSession.place` and its commands are sent one per cycle;
each state is the player's ``(fullstate ...)`` after the cycle, with the collisions and the tackle countdown of its
``(sense_body ...)``. ``python -m robocup_dribble.validate OUT.jsonl`` replays the file.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any


from robocup_dribble import physics
from robocup_dribble.params import GOAL_POST_RADIUS, PITCH_HALF_LENGTH, make_profile, without_noise
from robocup_dribble.player_types import TYPE_FIELDS, default_player_type
from robocup_dribble.rcss import protocol
from robocup_dribble.rcss.client import PROTOCOL_VERSION, ServerSession, Window, server_options
from robocup_dribble.rcss.play import find_server
from robocup_dribble.rcss.server import ServerProcess

WORLD_SEED = 1
POST_X = PITCH_HALF_LENGTH - GOAL_POST_RADIUS
"""x of the right goal posts' centres (the left ones at -POST_X)."""
POST_Y = 0.5 * without_noise(make_profile("v19")).server.goal_width + GOAL_POST_RADIUS
"""|y| of the goal posts' centres."""


@dataclass(frozen=True)
class Case:
    """One recorded case: player (x, y, body in degrees, vx, vy) and ball (x, y, vx, vy) at set-up, then one command
    (or None) per cycle."""

    name: str
    group: str
    description: str
    player: tuple[float, float, float, float, float]
    ball: tuple[float, float, float, float]
    commands: tuple[str | None, ...]


def _idle(n: int) -> tuple[None, ...]:
    return (None,) * n


CASES = (
    Case("ball_rolls_into_post_head_on", "post", "ball rolling +x at the centre of the right-bottom post",
         (40.0, 0.0, 0.0, 0.0, 0.0), (50.0, POST_Y, 1.5, 0.0), _idle(8)),
    Case("ball_glances_off_post", "post", "ball rolling +x, 0.1 m beside the post's centre line (inside the goal)",
         (40.0, 0.0, 0.0, 0.0, 0.0), (50.5, POST_Y - 0.1, 1.2, 0.0), _idle(8)),
    Case("ball_along_goal_line_into_post", "post", "ball rolling +y along the goal line from inside the goal mouth",
         (40.0, 0.0, 0.0, 0.0, 0.0), (POST_X, 4.0, 0.0, 1.6), _idle(8)),
    Case("ball_into_left_top_post", "post", "ball rolling -x, -y at the left goal's top post",
         (-40.0, 0.0, 180.0, 0.0, 0.0), (-49.0, -5.5, -1.4, -0.6), _idle(8)),
    Case("ball_placed_inside_post", "post", "ball placed overlapping the post, moving: pushed out, velocity mirrored",
         (40.0, 0.0, 0.0, 0.0, 0.0), (POST_X - 0.05, POST_Y - 0.05, 0.8, 0.3), _idle(5)),
    Case("ball_fast_outside_post", "post", "ball near full speed, 0.1 m outside the post's centre line, at the post",
         (40.0, 0.0, 0.0, 0.0, 0.0), (49.5, POST_Y + 0.1, 2.9, 0.0), _idle(6)),
    Case("kick_at_post", "post", "kick 100 from 4 m at the right-bottom post, ball in front of the player",
         (48.0, POST_Y, 0.0, 0.0, 0.0), (48.5, POST_Y, 0.0, 0.0), ("(kick 100 0)", *_idle(10))),
    Case("kick_at_post_inward", "post", "kick 80 at the post's inner side from 6 m at 17 degrees: into the goal",
         (46.0, 5.0, 20.0, 0.0, 0.0), (46.5638, 5.2052, 0.0, 0.0), ("(kick 80 -3)", *_idle(10))),
    Case("kick_at_post_outward", "post", "kick 80 at the post's outer side from 6 m at 18 degrees: back and wide",
         (46.0, 5.0, 20.0, 0.0, 0.0), (46.5638, 5.2052, 0.0, 0.0), ("(kick 80 -1.8)", *_idle(10))),
    Case("player_runs_into_post", "player_post", "dash 100 towards the post's centre for 6 cycles",
         (50.5, POST_Y, 0.0, 0.0, 0.0), (30.0, 0.0, 0.0, 0.0), ("(dash 100)",) * 6 + _idle(3)),
    Case("player_runs_past_post", "player_post", "dash 100 along the goal line side, 0.2 m beside the post's centre",
         (50.5, POST_Y - 0.2, 0.0, 0.0, 0.0), (30.0, 0.0, 0.0, 0.0), ("(dash 100)",) * 6 + _idle(3)),
    Case("player_placed_inside_post", "player_post", "player placed overlapping the post, moving into it",
         (POST_X - 0.2, POST_Y - 0.1, 0.0, 0.5, 0.1), (30.0, 0.0, 0.0, 0.0), _idle(4)),
    Case("tackle_ball_in_front", "tackle", "tackle 0 at a ball 0.6 m ahead (success), then dash 100 every cycle",
         (0.0, 0.0, 0.0, 0.0, 0.0), (0.6, 0.0, 0.0, 0.0), ("(tackle 0)",) + ("(dash 100)",) * 12),
    Case("tackle_sideways", "tackle", "tackle 45 at a ball ahead and to the side, then kick and turn (refused)",
         (0.0, 0.0, 30.0, 0.0, 0.0), (0.75, 0.35, 0.0, 0.0), ("(tackle 45)",) + ("(kick 100 0)", "(turn 60)") * 6),
    Case("tackle_moving_ball", "tackle", "tackle -90 at a ball rolling across in front",
         (0.0, 0.0, 0.0, 0.1, 0.0), (0.8, -0.3, 0.0, 0.5), ("(tackle -90)",) + _idle(4) + ("(dash 100)",) * 8),
    Case("tackle_out_of_reach", "tackle", "tackle at a ball 3 m ahead: fails, the player is frozen all the same",
         (0.0, 0.0, 0.0, 0.0, 0.0), (3.0, 0.0, 0.0, 0.0), ("(tackle 0)",) + ("(dash 100)",) * 11),
    Case("tackle_ball_behind", "tackle", "tackle at a ball behind (tackle_back_dist 0): fails, frozen",
         (0.0, 0.0, 0.0, 0.0, 0.0), (-0.5, 0.0, 0.0, 0.0), ("(tackle 0)",) + ("(turn 90)",) * 11),
    Case("kick_into_goal", "goal", "kick 100 from the penalty area straight through the goal and beyond",
         (45.0, 0.0, 0.0, 0.0, 0.0), (45.6, 0.0, 0.0, 0.0), ("(kick 100 0)", *_idle(12))),
    Case("kick_into_goal_corner", "goal", "kick 100 into the goal 0.6 m inside the top post",
         (44.0, -2.0, -28.0, 0.0, 0.0), (44.5298, -2.2817, 0.0, 0.0), ("(kick 100 0)", *_idle(12))),
    Case("kick_wide_of_goal", "goal", "kick 100 over the goal line wide of the goal",
         (45.0, 12.0, 0.0, 0.0, 0.0), (45.6, 12.0, 0.0, 0.0), ("(kick 100 0)", *_idle(12))),
    Case("kick_over_side_line_to_left_goal", "goal", "kick 100 backwards over the left goal line wide of the goal",
         (-45.0, -10.0, 180.0, 0.0, 0.0), (-45.6, -10.0, 0.0, 0.0), ("(kick 100 0)", *_idle(12))),
    Case("dribble_into_goal", "goal", "dash and small kicks carrying the ball over the goal line",
         (48.0, 1.0, 0.0, 0.0, 0.0), (48.6, 1.0, 0.0, 0.0),
         ("(kick 30 0)", "(dash 100)", "(dash 100)", "(kick 30 0)", "(dash 100)", "(dash 100)", "(kick 30 0)",
          "(dash 100)", "(dash 100)", "(dash 100)")),
)  # fmt: skip
"""The recorded cases (POST_X, POST_Y: the right-bottom post's centre; its radius is 0.06 m)."""


def _printed(value: float) -> float:
    """A number as the server printed it (6 significant digits; a value read from its text is unchanged)."""
    return float(f"{value:.6g}")


def _state(window: Window) -> dict[str, Any]:
    s = window.fullstate.state
    return {
        "time": window.fullstate.time,
        "play_mode": window.fullstate.play_mode,
        "player": {
            "x": _printed(s[physics.P_X]),
            "y": _printed(s[physics.P_Y]),
            "vx": _printed(s[physics.P_VX]),
            "vy": _printed(s[physics.P_VY]),
            "body": _printed(math.degrees(s[physics.P_BODY])),
        },
        "ball": {
            "x": _printed(s[physics.B_X]),
            "y": _printed(s[physics.B_Y]),
            "vx": _printed(s[physics.B_VX]),
            "vy": _printed(s[physics.B_VY]),
        },
        "stamina": _printed(s[physics.S_STAMINA]),
        "effort": _printed(s[physics.S_EFFORT]),
        "recovery": _printed(s[physics.S_RECOVERY]),
        "stamina_capacity": _printed(s[physics.S_CAPACITY]),
        "collision": protocol.read_collisions(window.sense_body),
        "kick_ok": None,
        "tackle_expires": protocol.read_tackle_expires(window.sense_body),
    }


def record_case(session: ServerSession, index: int, case: Case, options: dict[str, object]) -> dict[str, Any]:
    """Play ``case`` on a connected session (type 0) and return its record."""
    px, py, body, pvx, pvy = case.player
    start = physics.new_state(1)[0]
    start[[physics.P_X, physics.P_Y, physics.P_VX, physics.P_VY]] = px, py, pvx, pvy
    start[physics.P_BODY] = math.radians(body)
    start[[physics.B_X, physics.B_Y, physics.B_VX, physics.B_VY]] = case.ball
    session.place(0, start)
    states = [_state(session.act(command)) for command in case.commands]
    player_type = dict(zip(TYPE_FIELDS, default_player_type(session.profile), strict=True))
    return {
        "id": f"{index:03d}-{case.name}",
        "index": index,
        "group": case.group,
        "description": case.description,
        "server_version": "19.0.0",
        "protocol_version": PROTOCOL_VERSION,
        "server_options": options,
        "player_type_id": 0,
        "player_type": {"id": 0, **player_type},
        "side": "l",
        "setup": {
            "player": {"x": px, "y": py, "body": body, "vx": pvx, "vy": pvy},
            "ball": dict(zip(("x", "y", "vx", "vy"), case.ball, strict=True)),
        },
        "commands": list(case.commands),
        "states": states,
    }


def record(binary: str | Path, path: Path) -> int:
    """Record every case of :data:`CASES` on the server ``binary`` into ``path``; returns the number of cases."""
    profile = without_noise(make_profile("v19"))
    options = server_options(profile, WORLD_SEED)
    with ServerProcess(binary, options) as process, path.open("w") as out:
        player, trainer = process.endpoints()
        session = ServerSession(player, trainer, profile, WORLD_SEED, noise=False)
        session.open()
        for index, case in enumerate(CASES, start=1):
            out.write(json.dumps(record_case(session, index, case, options), separators=(",", ":")) + "\n")
        if process.missed_cycles():
            raise RuntimeError(f"the recorder missed {process.missed_cycles()} cycle(s): record again on a quieter machine")
    return len(CASES)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m robocup_dribble.rcss.record", description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path, help="the .jsonl file to write")
    args = parser.parse_args(argv)
    binary = find_server()
    if binary is None:
        print("error: no rcssserver binary: set RCSSSERVER or put rcssserver on PATH", file=sys.stderr)
        return 2
    print(f"recorded {record(binary, args.out)} cases into {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
