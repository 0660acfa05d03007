"""What a player in a match knows of the dribble: its own ``(see ...)`` and ``(sense_body ...)``, not fullstate.

The readers below pick the ball out of a see (:func:`read_seen_ball`) and the player's speed out of a sense_body
(:func:`read_speed`); :class:`PerceivedWorld` keeps the player's estimate from them with the env's own world model,
:func:`robocup_dribble.perception.update_estimate` (what the server quantises and when it sends what, and how the
estimate follows: :mod:`robocup_dribble.perception`). The env's ``perception="match"`` computes the same perceptions
from its true state (:func:`robocup_dribble.perception.seen_ball`, :func:`~robocup_dribble.perception.sensed_speed`),
so a policy trained there meets on the server the estimate it was trained on. The client builds the observation from
the estimate as the env builds it, and the episode is still judged on the server's true state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robocup_dribble import perception, physics
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


class PerceivedWorld:
    """A player's estimate of player and ball, kept from its perceptions (:func:`robocup_dribble.perception.update_estimate`).

    :param profile: the server profile; its physics, without noise, predicts each cycle.
    """

    def __init__(self, profile: ServerProfile) -> None:
        self._constants = physics.profile_constants(without_noise(profile))
        self._calm = np.full((1, physics.N_UNIFORMS), 0.5)
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
        amount, direction, head = speed
        sighting, distance, ball_direction, distance_change, direction_change = perception.NOT_SEEN, 0.0, 0.0, 0.0, 0.0
        if ball is not None:
            sighting, distance, ball_direction = perception.SEEN_CLOSE, ball.distance, head + ball.direction
            if ball.distance_change is not None and ball.direction_change is not None:
                sighting, distance_change, direction_change = (
                    perception.SEEN_IN_CONE,
                    ball.distance_change,
                    ball.direction_change,
                )
        self._unseen = perception.update_estimate(
            self.state, 0, types, 0, int(command[physics.C_KIND]), float(command[physics.C_POWER]),
            float(command[physics.C_DIRECTION]), float(body), float(amount), head + direction, sighting, float(distance),
            float(ball_direction), float(distance_change), float(direction_change), self._unseen, self._calm,
            self._constants,
        )  # fmt: skip
        estimate: np.ndarray = self.state[0].copy()
        return estimate
