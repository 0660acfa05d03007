"""One call that plays a world's episodes on a real rcssserver: started here (and always stopped), or already running."""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from robocup_dribble import physics
from robocup_dribble.env import configure
from robocup_dribble.evaluation import DribbleReport
from robocup_dribble.params import ServerProfile
from robocup_dribble.rcss.client import ServerEpisodes, ServerSession, checked_profile, server_options
from robocup_dribble.rcss.perception import PerceivedWorld
from robocup_dribble.rcss.server import DEFAULT_TIMEOUT, Endpoint, Log, ServerError, ServerPorts, ServerProcess, connect

SERVER_VARIABLE = "RCSSSERVER"
"""The environment variable naming the rcssserver binary (else ``rcssserver`` on PATH)."""


def find_server() -> Path | None:
    """The rcssserver binary named by ``$RCSSSERVER``, else ``rcssserver`` on PATH, else None."""
    named = os.environ.get(SERVER_VARIABLE)
    if named:
        return Path(named)
    found = shutil.which("rcssserver")
    return Path(found) if found else None


def play_on_server(
    policy: Any,
    episodes: ServerEpisodes,
    server: str | os.PathLike[str] | None = None,
    address: tuple[str, ServerPorts] | None = None,
    profile: str | ServerProfile = "v19",
    timeout: float = DEFAULT_TIMEOUT,
    transcript: Log | None = None,
    on_episode: Callable[[int, float, bool], None] | None = None,
    deterministic: bool = True,
    perceive: bool = False,
    **env_kwargs: Any,
) -> DribbleReport:
    """Play ``episodes`` with ``policy`` on a real server and return the env's result type.

    :param server: an rcssserver binary to start (loopback only, :class:`ServerProcess`) with
        :func:`server_options` for the episodes' world and the profile's noise; stopped when this returns or raises.
    :param address: instead, ``(host, ports)`` of a running server (started by the caller with those options).
    :param timeout: seconds any receive waits before the server counts as silent.
    :param transcript: called with ``(client, direction, text)`` for every message (recording a session).
    :param on_episode: called with ``(index, distance, ball_lost)`` after each episode.
    :param perceive: the policy acts on the player's own see/sense_body perception (a match's view) instead of the
        exact state (:mod:`robocup_dribble.rcss.perception`).
    :param env_kwargs: ``noise`` and the :class:`robocup_dribble.task.DribbleTask` settings, as for the env.
    :raises ValueError: for no or both of ``server`` and ``address``, or profile v11.
    :raises ServerError: if the server cannot start, does not match the profile, dies or stops answering.
    """
    if (server is None) == (address is None):
        raise ValueError("give either server (a binary to start) or address (host and ports of a running server)")
    checked = checked_profile(profile)
    session_profile, _ = configure(checked, env_kwargs.get("noise", True), None, {})
    if address is not None:
        player, trainer = connect(address[0], address[1], timeout, transcript)
        return _play(player, trainer, policy, episodes, checked, on_episode, deterministic, perceive, env_kwargs)
    assert server is not None
    with ServerProcess(server, server_options(session_profile, episodes.world_seed), timeout) as process:
        player, trainer = process.endpoints(transcript)
        report = _play(player, trainer, policy, episodes, checked, on_episode, deterministic, perceive, env_kwargs)
        if process.missed_cycles():
            raise ServerError(
                f"the client missed {process.missed_cycles()} cycle(s) (the server steps alone after 1.25 s without a "
                "(done)), so the episodes are not the env's; rerun on a less loaded machine"
            )
        return report


def _play(
    player: Endpoint,
    trainer: Endpoint,
    policy: Any,
    episodes: ServerEpisodes,
    profile: ServerProfile,
    on_episode: Callable[[int, float, bool], None] | None,
    deterministic: bool,
    perceive: bool,
    env_kwargs: dict[str, Any],
) -> DribbleReport:
    try:
        session = ServerSession(player, trainer, profile, episodes.world_seed, **env_kwargs)
        # a first call that compiles must not keep the waiting server past its 1.25 s
        policy.predict(session.observe(episodes.start_states[0], episodes.player_types[0]), deterministic=deterministic)
        if perceive:  # so must the world model's first update
            world = PerceivedWorld(profile)
            world.start(episodes.start_states[0])
            world.update(episodes.player_types[0], np.zeros(physics.COMMAND_SIZE), 0.0, (0.0, 0.0, 0.0), None)
        session.open()
        return session.play(policy, episodes, deterministic, on_episode, perceive)
    finally:
        player.close()
        trainer.close()
