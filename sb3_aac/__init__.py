"""
sb3-aac: parameterized-action reinforcement learning for Stable-Baselines3.

The algorithms, policies, wrappers and :func:`export_policy` need torch, Stable-Baselines3 and Gymnasium; they are
imported on first use (PEP 562), so ``from sb3_aac.runtime import RuntimePolicy`` imports numpy alone.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from sb3_aac.runtime import RuntimePolicy
from sb3_aac.version import __version__

if TYPE_CHECKING:
    from sb3_aac.export import export_policy
    from sb3_aac.hppo import HybridActorCriticPolicy, HybridPPO
    from sb3_aac.pdqn import MPDQN, PDQN, PDQNPolicy
    from sb3_aac.sarsa_aac import DeepPolicy, MlpPolicy, RbfMlpPolicy, RbfPolicy, SarsaAAC, SarsaAACPolicy, TilePolicy
    from sb3_aac.wrappers import DiscretizeParameterizedAction, FlattenParameterizedAction, SelectObservation

# Public name -> the module that defines it, imported by __getattr__ when the name is first used.
LAZY_NAMES = {
    "export_policy": "sb3_aac.export",
    **dict.fromkeys(("HybridActorCriticPolicy", "HybridPPO"), "sb3_aac.hppo"),
    **dict.fromkeys(("MPDQN", "PDQN", "PDQNPolicy"), "sb3_aac.pdqn"),
    **dict.fromkeys(
        ("DeepPolicy", "MlpPolicy", "RbfMlpPolicy", "RbfPolicy", "SarsaAAC", "SarsaAACPolicy", "TilePolicy"),
        "sb3_aac.sarsa_aac",
    ),
    **dict.fromkeys(("DiscretizeParameterizedAction", "FlattenParameterizedAction", "SelectObservation"), "sb3_aac.wrappers"),
}


def __getattr__(name: str) -> Any:
    """The torch/SB3/Gymnasium-dependent public ``name``, imported from its module on first access."""
    if name not in LAZY_NAMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(LAZY_NAMES[name]), name)
    globals()[name] = value  # later accesses skip __getattr__
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *LAZY_NAMES})


__all__ = [
    "MPDQN",
    "PDQN",
    "DeepPolicy",
    "DiscretizeParameterizedAction",
    "FlattenParameterizedAction",
    "HybridActorCriticPolicy",
    "HybridPPO",
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
