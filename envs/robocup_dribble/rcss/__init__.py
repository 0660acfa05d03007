"""Play the dribbling task on a real rcssserver (19): start one on loopback only or reach a running one
(:mod:`~robocup_dribble.rcss.server`), speak its protocol (:mod:`~robocup_dribble.rcss.protocol`) and play
episodes through the env's observation, skills and rules (:mod:`~robocup_dribble.rcss.client`).

:func:`play_on_server` is the one-call entry: the episodes of one server world on a server binary it starts and
stops, returning a :class:`robocup_dribble.evaluation.DribbleReport` comparable with the env's
(:func:`robocup_dribble.evaluation.evaluate_episodes` on the same :class:`ServerEpisodes`).
``python -m robocup_dribble.rcss.record`` records the golden cases at the goals (:mod:`~robocup_dribble.rcss.record`).
"""

from robocup_dribble.rcss.client import (
    ServerEpisodes,
    ServerSession,
    check_server,
    checked_profile,
    server_episodes,
    server_options,
)
from robocup_dribble.rcss.play import find_server, play_on_server
from robocup_dribble.rcss.protocol import ProtocolError
from robocup_dribble.rcss.server import Endpoint, ServerError, ServerPorts, ServerProcess, connect

__all__ = [
    "Endpoint",
    "ProtocolError",
    "ServerEpisodes",
    "ServerError",
    "ServerPorts",
    "ServerProcess",
    "ServerSession",
    "check_server",
    "checked_profile",
    "connect",
    "find_server",
    "play_on_server",
    "server_episodes",
    "server_options",
]
