"""What a player in a match knows of the dribble: its own ``(see ...)`` and ``(sense_body ...)``, not fullstate.

The server quantises what a player sees (rcssserver ``src/visualsenderplayer.cpp``): the ball's distance to 0.1 m
after a logarithmic quantisation, its direction to 1 degree, and, only while the ball is inside the view cone, its
distance change and direction change, from which the relative velocity follows; a ball outside the cone but within
``visible_distance`` (3 m) is reported as ``(B) dist dir`` only. In synchronous mode the default view (normal width,
high quality) is a 120-degree cone sent every second cycle (``src/player.cpp``, ``Player::change_view``).
``sense_body`` gives the player's speed to 0.01 m/cycle and its direction to 1 degree.

:class:`PerceivedWorld` is the world model a RoboCup agent keeps from that: the noise-free env physics predicts the
state from the last estimate and the command sent, and what the player perceives replaces the prediction (its own
velocity every cycle; the ball's relative position when the ball was seen; its relative velocity when the ball was in
the view cone). The body angle is taken from the server's state (an agent gets it from the seen field lines to about
a degree; the four skills never turn the player). The observation is then built from the estimate as the env builds
it, and the episode is still judged on the server's true state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robocup_dribble import physics
from robocup_dribble.params import ServerProfile, without_noise
from robocup_dribble.rcss.protocol import ProtocolError, parse


@dataclass(frozen=True)
class SeenBall:
    """The ball in a ``(see ...)``: distance (m), direction (deg, relative to the head), and, when the ball was in the
    view cone, the distance change (m/cycle) and direction change (deg/cycle); else those are None."""

    distance: float
    direction: float
    distance_change: float | None
    direction_change: float | None


def read_seen_ball(message: str) -> SeenBall | None:
    """The ball of a ``(see TIME ...)`` message, or None if the player did not see it.

    :raises ProtocolError: if the message is no see or the ball entry has not 2 or 4 numbers first.
    """
    tree = parse(message)
    if tree[0] != "see":
        raise ProtocolError(f"expected (see TIME ...), got {message[:100]!r}")
    for item in tree[2:]:
        if isinstance(item, list) and item and item[0] in (["b"], ["B"]):
            try:
                values = [float(v) for v in item[1:5] if isinstance(v, str)]
            except ValueError:
                values = []
            if len(values) not in (2, 4):
                raise ProtocolError(f"a seen ball needs distance, direction [and their changes], got {item!r:.100}")
            if len(values) == 2:
                return SeenBall(values[0], values[1], None, None)
            return SeenBall(*values)
    return None


def read_speed(message: str) -> tuple[float, float, float]:
    """``(amount, direction, head_angle)`` of a ``(sense_body ...)``: the player's speed (m/cycle), its direction
    relative to the head and the head's angle relative to the body (degrees)."""
    tree = parse(message)
    if tree[0] != "sense_body":
        raise ProtocolError(f"expected (sense_body TIME ...), got {message[:100]!r}")
    found: dict[str, list[float]] = {}
    for item in tree[2:]:
        if isinstance(item, list) and item and item[0] in ("speed", "head_angle"):
            try:
                found[str(item[0])] = [float(v) for v in item[1:] if isinstance(v, str)]
            except ValueError:
                break
    if len(found.get("speed", [])) != 2 or len(found.get("head_angle", [])) != 1:
        raise ProtocolError(f"sense_body without (speed AMOUNT DIR) and (head_angle A): {message[:200]!r}")
    return found["speed"][0], found["speed"][1], found["head_angle"][0]


VELOCITY_GAIN = 1.0
"""Share of a seen ball's position error (against the prediction) that corrects its estimated velocity."""


class PerceivedWorld:
    """A player's estimate of player and ball, kept from its perceptions (module docstring).

    :param profile: the server profile; its physics, without noise, predicts each cycle.
    """

    def __init__(self, profile: ServerProfile) -> None:
        self._constants = physics.profile_constants(without_noise(profile))
        self._noise_free = np.full((1, physics.N_UNIFORMS), 0.5)
        self.state = physics.new_state(1)
        self._unseen = 0  # cycles since the ball was last seen

    def start(self, state: np.ndarray) -> None:
        """Begin an episode from a known state (the trainer's placement)."""
        self.state = np.asarray(state, dtype=np.float64).reshape(1, physics.STATE_SIZE).copy()
        self._unseen = 0

    def update(
        self,
        player_type: np.ndarray,
        command: np.ndarray,
        body: float,
        speed: tuple[float, float, float],
        ball: SeenBall | None,
    ) -> np.ndarray:
        """The estimate ``(STATE_SIZE,)`` after a cycle with ``command`` (``COMMAND_SIZE``), given the body angle (rad),
        the sense_body speed and the seen ball of the cycle (None when there was no see or no ball in it)."""
        types = np.asarray(player_type, dtype=np.float64).reshape(1, physics.TYPE_SIZE)
        physics.step(self.state, types, command.reshape(1, physics.COMMAND_SIZE), self._noise_free, self._constants)
        s = self.state[0]
        s[physics.P_BODY] = body
        amount, direction, head = speed
        heading = body + math.radians(head + direction)
        s[physics.P_VX], s[physics.P_VY] = amount * math.cos(heading), amount * math.sin(heading)
        self._unseen += 1
        if ball is not None:
            angle = body + math.radians(head + ball.direction)
            ex, ey = math.cos(angle), math.sin(angle)
            seen_x, seen_y = s[physics.P_X] + ball.distance * ex, s[physics.P_Y] + ball.distance * ey
            if ball.distance_change is not None and ball.direction_change is not None:
                across = math.radians(ball.direction_change) * ball.distance
                s[physics.B_VX] = s[physics.P_VX] + ball.distance_change * ex - across * ey
                s[physics.B_VY] = s[physics.P_VY] + ball.distance_change * ey + across * ex
            else:  # the position missed by the prediction is put down to the ball's velocity since the last see
                decay = self._constants[physics.K_BALL_DECAY]
                share = decay / sum(decay**i for i in range(self._unseen))
                s[physics.B_VX] += VELOCITY_GAIN * share * (seen_x - s[physics.B_X])
                s[physics.B_VY] += VELOCITY_GAIN * share * (seen_y - s[physics.B_Y])
            s[physics.B_X], s[physics.B_Y] = seen_x, seen_y
            self._unseen = 0
        estimate: np.ndarray = s.copy()
        return estimate
