"""
What the torch policies' exporters (:mod:`sb3_aac.hppo.export`, :mod:`sb3_aac.pdqn.export`) share: torch layers as the
``.aacp`` format's network layers (``docs/export-format.md``), and the header and arrays around a policy's
``approximators`` section.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from stable_baselines3.common.policies import BasePolicy
from torch import nn

from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.runtime.format import ARRAY_DTYPE, FORMAT_NAME, written_version
from sb3_aac.version import __version__

ACTIVATIONS = {nn.Tanh: "tanh", nn.ReLU: "relu", nn.LeakyReLU: "leaky_relu"}


def array_of(value: Any) -> np.ndarray:
    """A tensor as a C-ordered float64 numpy array (the format's dtype)."""
    return np.ascontiguousarray(value.detach().cpu().numpy().astype(ARRAY_DTYPE))


def network_layers(modules: list[nn.Module], network: int, arrays: dict[str, np.ndarray]) -> list[dict[str, Any]]:
    """
    The ``layers`` of network ``network`` made of ``modules`` (``nn.Sequential`` ones unpacked) in order, adding their
    weights to ``arrays`` as ``net{network}_{j}_weight`` / ``_bias``.

    :raises ValueError: for a layer the format cannot hold (anything but ``Linear`` and the activations tanh, ReLU and
        leaky ReLU)
    """
    flat = [m for module in modules for m in (module if isinstance(module, nn.Sequential) else [module])]
    layers: list[dict[str, Any]] = []
    for j, layer in enumerate(flat):
        if isinstance(layer, nn.Linear):
            layers.append({"type": "linear", "in": layer.in_features, "out": layer.out_features})
            arrays[f"net{network}_{j}_weight"] = array_of(layer.weight)
            arrays[f"net{network}_{j}_bias"] = array_of(layer.bias)
        elif type(layer) in ACTIVATIONS:
            layers.append({"type": "activation", "function": ACTIVATIONS[type(layer)]})
            if isinstance(layer, nn.LeakyReLU):
                layers[-1]["slope"] = float(layer.negative_slope)
        else:
            raise ValueError(
                f"Cannot export a {type(layer).__name__} layer: the format's networks hold Linear layers and the "
                f"activations {sorted(ACTIVATIONS.values())}"
            )
    return layers


def policy_file_contents(
    algorithm: str,
    policy: BasePolicy,
    spec: ParameterizedActionSpec,
    approximators: dict[str, Any],
    arrays: dict[str, np.ndarray],
    action: dict[str, Any],
    metadata: dict[str, Any] | None = None,
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """
    The header (without the arrays table) and the arrays of ``algorithm``'s torch policy's ``.aacp`` file: its
    ``approximators``
    section and arrays (``obs_mid``, ``obs_half`` and the layers'), with the observation bounds, the parameter bounds
    ``spec.low`` / ``spec.high`` and ``action`` as the header's action section
    (:func:`sb3_aac.export.action_header` of ``spec``).
    """
    space = policy.observation_space
    assert isinstance(space, spaces.Box)  # both policies take Box observations only
    size = len(arrays["obs_mid"])
    header = {
        "format": FORMAT_NAME,
        "version": written_version(approximators["head"]),
        "writer": f"sb3-aac {__version__}",
        "algorithm": algorithm,
        "policy_class": type(policy).__name__,
        "observation": {"shape": [int(s) for s in space.shape], "size": size, "dtype": str(space.dtype)},
        "action": action,
        "approximators": approximators,
        "metadata": dict(metadata or {}),
    }
    low = np.broadcast_to(np.asarray(space.low, dtype=ARRAY_DTYPE).ravel(), (size,))
    high = np.broadcast_to(np.asarray(space.high, dtype=ARRAY_DTYPE).ravel(), (size,))
    return header, {
        "obs_low": np.ascontiguousarray(low),
        "obs_high": np.ascontiguousarray(high),
        **arrays,
        "param_low": spec.low.astype(ARRAY_DTYPE),
        "param_high": spec.high.astype(ARRAY_DTYPE),
    }
