"""rcssserver's text protocol (version 19) for one player and a trainer: reading its messages, writing commands.

A message is an S-expression, e.g. ``(fullstate 3 (pmode play_on) ... ((b) 0.50 0.16 -0.01 0) ((p l 1 0) 0.89 0.11
-0.03 0 0 0 (focus_point 0 0) (stamina 7945 1 1 130555)))``. :func:`parse` turns one into nested lists of words
(strings); the readers below pick out what the client needs and raise :class:`ProtocolError` saying what was
missing. Commands are written with numbers that read back to the same double (:func:`number`), never in exponent
notation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np

from robocup_dribble import physics

Expression: TypeAlias = "str | list[Expression]"


class ProtocolError(ValueError):
    """A server message that does not have the form the protocol gives it."""


def parse(message: str) -> list[Expression]:
    """The S-expression ``message`` as nested lists of words (a quoted word keeps its quotes).

    :raises ProtocolError: for unbalanced parentheses or text outside the one outer expression.
    """
    stack: list[list[Expression]] = [[]]
    word: list[str] = []
    quoted = False
    for char in message:
        if quoted:
            word.append(char)
            quoted = char != '"'
        elif char == '"':
            word.append(char)
            quoted = True
        elif char in "() \t\n\r":
            if word:
                stack[-1].append("".join(word))
                word = []
            if char == "(":
                stack.append([])
            elif char == ")":
                if len(stack) == 1:
                    raise ProtocolError(f"unbalanced ')' in {message[:200]!r}")
                closed = stack.pop()
                stack[-1].append(closed)
        else:
            word.append(char)
    if word:
        stack[-1].append("".join(word))
    if len(stack) != 1 or len(stack[0]) != 1 or not isinstance(stack[0][0], list) or not stack[0][0]:
        raise ProtocolError(f"expected one parenthesised message, got {message[:200]!r}")
    return stack[0][0]


def kind(message: str) -> str:
    """The first word of a message: ``"fullstate"``, ``"sense_body"``, ``"ok"``, ``"think"``, ..."""
    head = message.lstrip("(").split(None, 1)
    return head[0].rstrip(")") if head else ""


def read_time(message: str) -> int:
    """The cycle number of a timed message: ``(see_global 12 ...)``, ``(fullstate 12 ...)``, ``(sense_body 12 ...)``."""
    words = message.lstrip("(").split(None, 2)
    try:
        return int(words[1])
    except (IndexError, ValueError):
        raise ProtocolError(f"expected (KIND TIME ...), got {message[:100]!r}") from None


def read_parameters(message: str) -> dict[str, float | str]:
    """``(server_param (name value) ...)``, ``(player_param ...)`` or ``(player_type (id 3) ...)`` as a dict; numeric
    values as floats, the others (paths, quoted words) as text."""
    tree = parse(message)
    values: dict[str, float | str] = {}
    for item in tree[1:]:
        if not isinstance(item, list) or len(item) != 2 or not all(isinstance(part, str) for part in item):
            raise ProtocolError(f"expected (name value) pairs in {kind(message)}, got {item!r:.100}")
        name, text = item
        assert isinstance(name, str) and isinstance(text, str)
        try:
            values[name] = float(text)
        except ValueError:
            values[name] = text
    return values


@dataclass(frozen=True)
class FullState:
    """What ``(fullstate ...)`` tells of the ball and the left team's player 1 (exact state, 6 printed digits)."""

    time: int
    play_mode: str
    player_type: int
    state: np.ndarray  # (physics.STATE_SIZE,): positions, velocities (after decay), body (rad), stamina model


def read_fullstate(message: str, side: str = "l", unum: int = 1) -> FullState:
    """The ball and player ``side unum`` of a ``(fullstate ...)`` message.

    :raises ProtocolError: if the message is not a fullstate or lacks the ball, the player or its stamina.
    """
    tree = parse(message)
    if tree[0] != "fullstate" or len(tree) < 3:
        raise ProtocolError(f"expected (fullstate TIME ...), got {message[:100]!r}")
    state = np.zeros(physics.STATE_SIZE)
    play_mode, player_type, found = "", -1, set()
    for item in tree[2:]:
        if not isinstance(item, list) or not item:
            continue
        head = item[0]
        if head == "pmode" and len(item) == 2:
            play_mode = str(item[1])
        elif head == ["b"]:
            state[[physics.B_X, physics.B_Y, physics.B_VX, physics.B_VY]] = _numbers(item[1:5], "ball")
            found.add("ball")
        elif isinstance(head, list) and head[:3] == ["p", side, str(unum)]:
            player_type = int(_numbers([head[-1]], "player type")[0])
            x, y, vx, vy, body = _numbers(item[1:6], "player")
            state[[physics.P_X, physics.P_Y, physics.P_VX, physics.P_VY]] = x, y, vx, vy
            state[physics.P_BODY] = math.radians(body)
            for part in item[6:]:
                if isinstance(part, list) and part and part[0] == "stamina":
                    columns = [physics.S_STAMINA, physics.S_EFFORT, physics.S_RECOVERY, physics.S_CAPACITY]
                    state[columns] = _numbers(part[1:5], "stamina")
                    found.add("stamina")
            found.add("player")
    missing = {"ball", "player", "stamina"} - found
    if missing:
        raise ProtocolError(f"fullstate without {', '.join(sorted(missing))} (player {side} {unum}): {message[:200]!r}")
    return FullState(int(_numbers([tree[1]], "time")[0]), play_mode, player_type, state)


def read_referee(message: str) -> str | None:
    """What the referee said in a ``(hear TIME referee MESSAGE)``, or None for what another speaker said."""
    words = message.strip().lstrip("(").rstrip(")").split()
    if len(words) != 4 or words[0] != "hear":
        return None
    return words[3] if words[2] == "referee" else None


def read_look(message: str, team: str, unum: int) -> np.ndarray:
    """Player ``team unum`` and ball in the trainer's ``(ok look TIME ...)``: ``[px, py, pvx, pvy, bx, by, bvx, bvy]``.

    :raises ProtocolError: if the message is no look answer or lacks the player or the ball.
    """
    tree = parse(message)
    if tree[:2] != ["ok", "look"]:
        raise ProtocolError(f"expected (ok look TIME ...), got {message[:100]!r}")
    player: list[float] | None = None
    ball: list[float] | None = None
    for item in tree[3:]:
        if isinstance(item, list) and item:
            if item[0] == ["b"]:
                ball = _numbers(item[1:5], "ball")
            elif isinstance(item[0], list) and item[0][:3] == ["p", f'"{team}"', str(unum)]:
                player = _numbers(item[1:5], "player")
    if player is None or ball is None:
        raise ProtocolError(f"look answer without {'the player' if player is None else 'the ball'}: {message[:200]!r}")
    return np.array(player + ball)


def read_collision(message: str) -> bool:
    """Whether a ``(sense_body ...)`` reports a ball-player collision in the last cycle (``(collision (ball))``)."""
    return "ball" in read_collisions(message)


def read_collisions(message: str) -> list[str]:
    """What the player collided with in the last cycle by its ``(sense_body ...)``: ``[]`` for ``(collision none)``,
    else the names of ``(collision (ball) (player) (post))`` in the message's order."""
    item = _sense_body_item(message, "collision")
    return [str(part[0]) for part in item[1:] if isinstance(part, list) and len(part) == 1]


def read_tackle_expires(message: str) -> int:
    """The cycles the player's last tackle still freezes it for, by its ``(sense_body ...)``
    (``(tackle (expires N) (count C))``; 0 when not frozen)."""
    for part in _sense_body_item(message, "tackle")[1:]:
        if isinstance(part, list) and len(part) == 2 and part[0] == "expires":
            return int(_numbers([part[1]], "tackle expires")[0])
    raise ProtocolError(f"sense_body without (tackle (expires N) ...): {message[:200]!r}")


def _sense_body_item(message: str, name: str) -> list[Expression]:
    tree = parse(message)
    if tree[0] != "sense_body":
        raise ProtocolError(f"expected (sense_body TIME ...), got {message[:100]!r}")
    for item in tree[2:]:
        if isinstance(item, list) and item and item[0] == name:
            return item
    raise ProtocolError(f"sense_body without ({name} ...): {message[:200]!r}")


def _numbers(items: list[Expression], what: str) -> list[float]:
    try:
        values = [float(item) for item in items if isinstance(item, str)]
    except ValueError:
        values = []
    if len(values) != len(items) or not all(math.isfinite(v) for v in values):
        raise ProtocolError(f"expected {len(items)} numbers for the {what}, got {items!r:.100}")
    return values


def number(value: float) -> str:
    """``value`` as the shortest decimal that reads back to the same double, without an exponent."""
    if not math.isfinite(value):
        raise ValueError(f"a command number must be finite, got {value!r}")
    return np.format_float_positional(float(value), unique=True, trim="-")


def player_command(command_kind: int, power: float, direction: float) -> str:
    """The player command of a ``(physics.CMD_* kind, power or moment, direction)``: ``(dash P D)``, ``(kick P D)``,
    ``(turn M)`` or ``(tackle D)``."""
    if command_kind == physics.CMD_DASH:
        return f"(dash {number(power)} {number(direction)})"
    if command_kind == physics.CMD_KICK:
        return f"(kick {number(power)} {number(direction)})"
    if command_kind == physics.CMD_TURN:
        return f"(turn {number(power)})"
    if command_kind == physics.CMD_TACKLE:
        return f"(tackle {number(direction)})"
    raise ValueError(f"a command is a dash, kick, turn or tackle (kinds 1 to 4), got {command_kind!r}")


def move_player(team: str, unum: int, x: float, y: float, body_deg: float, vx: float, vy: float) -> str:
    """The trainer command placing a player with a body angle (degrees) and a velocity."""
    return f"(move (player {team} {unum}) {number(x)} {number(y)} {number(body_deg)} {number(vx)} {number(vy)})"


def move_ball(x: float, y: float, vx: float = 0.0, vy: float = 0.0) -> str:
    """The trainer command placing the ball with a velocity."""
    return f"(move (ball) {number(x)} {number(y)} 0 {number(vx)} {number(vy)})"


def change_player_type(team: str, unum: int, type_id: int) -> str:
    return f"(change_player_type {team} {unum} {int(type_id)})"
