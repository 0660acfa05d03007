"""RoboCup 2D soccer simulator dribbling with heterogeneous players, as Gymnasium and Stable-Baselines3 environments.

Registered ids: ``RoboCupDribble-v0`` (rcssserver 19 physics) and ``RoboCupDribblePaper-v0`` (the 2007 v11 server of
Uc-Cetina 2013: 7 player types, no dash direction, box noise).

Importing the package needs Gymnasium, numpy and numba only: :class:`DribbleVecEnv` (a Stable-Baselines3 ``VecEnv``,
which imports torch) is loaded on first access.
"""

from typing import TYPE_CHECKING, Any

from gymnasium.envs.registration import register

from robocup_dribble.env import DribbleEnv
from robocup_dribble.params import PROFILES, ServerProfile, make_profile
from robocup_dribble.player_types import PlayerType, generate_player_types
from robocup_dribble.skills import ACTION_NAMES, DASH_MAX, KICK_ALIGN, KICK_POSITION, KICK_VELOCITY, PARAM_NAMES
from robocup_dribble.task import OBSERVATION_NAMES, DribbleTask

if TYPE_CHECKING:
    from robocup_dribble.vec_env import DribbleVecEnv


def __getattr__(name: str) -> Any:
    """Load :class:`DribbleVecEnv` (and with it SB3 and torch) only when it is asked for."""
    if name == "DribbleVecEnv":
        from robocup_dribble.vec_env import DribbleVecEnv

        return DribbleVecEnv
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


ENV_PROFILES: dict[str, str] = {"RoboCupDribble-v0": "v19", "RoboCupDribblePaper-v0": "v11"}
"""The registered env ids and their server profiles (the one table; others should read it)."""

for _env_id, _profile in ENV_PROFILES.items():
    register(id=_env_id, entry_point="robocup_dribble.env:DribbleEnv", kwargs={"profile": _profile})

__all__ = [
    "ACTION_NAMES",
    "DASH_MAX",
    "ENV_PROFILES",
    "KICK_ALIGN",
    "KICK_POSITION",
    "KICK_VELOCITY",
    "OBSERVATION_NAMES",
    "PARAM_NAMES",
    "PROFILES",
    "DribbleEnv",
    "DribbleTask",
    "DribbleVecEnv",
    "PlayerType",
    "ServerProfile",
    "generate_player_types",
    "make_profile",
]
