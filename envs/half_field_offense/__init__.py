"""Half Field Offense 1v0 (HFO, Hausknecht et al. 2016) with low-level features, on the rcssserver physics of
:mod:`robocup_dribble`, as Gymnasium and Stable-Baselines3 environments.

Registered id: ``HalfFieldOffense-v0`` (HFO's rcssserver 15.2.2 physics, the published 1v0 settings). Importing the
package needs Gymnasium, numpy and numba only: :class:`HalfFieldOffenseVecEnv` (which imports SB3 and torch) and the
hand-coded :class:`HandCodedOffense` with :func:`evaluate_offense` are loaded on first access.
"""

import importlib
from typing import TYPE_CHECKING, Any

from gymnasium.envs.registration import register

from half_field_offense.actions import ACTION_NAMES, PARAM_NAMES
from half_field_offense.env import HalfFieldOffenseEnv
from half_field_offense.features import FEATURE_NAMES
from half_field_offense.referee import STATUS_NAMES
from half_field_offense.task import HFOTask

if TYPE_CHECKING:
    from half_field_offense.agent import HandCodedOffense
    from half_field_offense.evaluation import evaluate_offense
    from half_field_offense.vec_env import HalfFieldOffenseVecEnv

_LAZY = {
    "HalfFieldOffenseVecEnv": "half_field_offense.vec_env",
    "HandCodedOffense": "half_field_offense.agent",
    "evaluate_offense": "half_field_offense.evaluation",
}


def __getattr__(name: str) -> Any:
    """Load :data:`_LAZY`'s names (and with them SB3 and torch) only when they are asked for."""
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


ENV_ID = "HalfFieldOffense-v0"
register(id=ENV_ID, entry_point="half_field_offense.env:HalfFieldOffenseEnv")

__all__ = [
    "ACTION_NAMES",
    "ENV_ID",
    "FEATURE_NAMES",
    "PARAM_NAMES",
    "STATUS_NAMES",
    "HFOTask",
    "HalfFieldOffenseEnv",
    "HalfFieldOffenseVecEnv",
    "HandCodedOffense",
    "evaluate_offense",
]
