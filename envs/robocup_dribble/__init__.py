"""RoboCup 2D soccer simulator dribbling with heterogeneous players, as Gymnasium and Stable-Baselines3 environments.

Registered ids: ``RoboCupDribble-v0`` (rcssserver 19 physics) and ``RoboCupDribblePaper-v0`` (the 2007 v11 server of
Uc-Cetina 2013: 7 player types, no dash direction, box noise).

Importing the package needs Gymnasium, numpy and numba only: :class:`DribbleVecEnv` (a Stable-Baselines3 ``VecEnv``,
which imports torch), the hand-coded :class:`HandCodedDribbler` and :func:`evaluate_dribbling` (both built on it)
are loaded on first access.
"""

import importlib
from typing import TYPE_CHECKING, Any

from gymnasium.envs.registration import register

from robocup_dribble.env import DribbleEnv
from robocup_dribble.params import ServerProfile, make_profile
from robocup_dribble.player_types import PlayerType
from robocup_dribble.skills import DASH_MAX, KICK_ALIGN, KICK_POSITION, KICK_VELOCITY
from robocup_dribble.task import OBSERVATION_NAMES, DribbleTask

if TYPE_CHECKING:
    from robocup_dribble.dribbler import HandCodedDribbler
    from robocup_dribble.evaluation import evaluate_dribbling
    from robocup_dribble.vec_env import DribbleVecEnv

# The names loaded on first access (they import SB3 and torch), and their modules.
_LAZY = {
    "DribbleVecEnv": "robocup_dribble.vec_env",
    "HandCodedDribbler": "robocup_dribble.dribbler",
    "evaluate_dribbling": "robocup_dribble.evaluation",
}


def __getattr__(name: str) -> Any:
    """Load :data:`_LAZY`'s names (and with them SB3 and torch) only when they are asked for."""
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


ENV_PROFILES: dict[str, str] = {"RoboCupDribble-v0": "v19", "RoboCupDribblePaper-v0": "v11"}
"""The registered env ids and their server profiles (the one table; others should read it)."""

for _env_id, _profile in ENV_PROFILES.items():
    register(id=_env_id, entry_point="robocup_dribble.env:DribbleEnv", kwargs={"profile": _profile})

# What users import: the envs and their ids, the task and its observation, the action types, the server profiles,
# and the hand-coded baseline with its evaluation.
__all__ = [
    "DASH_MAX",
    "ENV_PROFILES",
    "KICK_ALIGN",
    "KICK_POSITION",
    "KICK_VELOCITY",
    "OBSERVATION_NAMES",
    "DribbleEnv",
    "DribbleTask",
    "DribbleVecEnv",
    "HandCodedDribbler",
    "PlayerType",
    "ServerProfile",
    "evaluate_dribbling",
    "make_profile",
]
