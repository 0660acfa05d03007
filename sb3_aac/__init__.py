"""sb3-aac: parameterized-action reinforcement learning for Stable-Baselines3."""

import os

from sb3_aac.export import export_policy
from sb3_aac.pdqn import MPDQN, PDQN, PDQNPolicy
from sb3_aac.runtime import RuntimePolicy
from sb3_aac.sarsa_aac import MlpPolicy, RbfMlpPolicy, RbfPolicy, SarsaAAC, SarsaAACPolicy, TilePolicy
from sb3_aac.wrappers import DiscretizeParameterizedAction, FlattenParameterizedAction, SelectObservation

with open(os.path.join(os.path.dirname(__file__), "version.txt")) as file_handler:
    __version__ = file_handler.read().strip()

__all__ = [
    "MPDQN",
    "PDQN",
    "DiscretizeParameterizedAction",
    "FlattenParameterizedAction",
    "MlpPolicy",
    "PDQNPolicy",
    "RbfMlpPolicy",
    "RbfPolicy",
    "RuntimePolicy",
    "SarsaAAC",
    "SarsaAACPolicy",
    "SelectObservation",
    "TilePolicy",
    "__version__",
    "export_policy",
]
