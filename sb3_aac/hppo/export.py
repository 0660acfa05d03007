"""
A HybridPPO policy in the ``.aacp`` format's ``networks`` head (format version 3, ``docs/export-format.md``).

Three feed-forward networks over the scaled observation write the file's outputs: the discrete actor's type logits
into the Q columns (so the reader's ``argmax`` is the policy's mode), the parameter actor's means into the parameter
columns (the reader clips them to the bounds, as ``predict`` does), and the critic into the value column. Layers the
two actors share are written into both networks. The learned standard deviations are not part of a deterministic
action and are not written.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.torch_layers import FlattenExtractor
from torch import nn

from sb3_aac.common.torch_layers import BoundsScaledFlatten
from sb3_aac.hppo.policies import HybridActorCriticPolicy
from sb3_aac.runtime.format import ARRAY_DTYPE, FORMAT_NAME, output_layout, written_version

ACTIVATIONS = {nn.Tanh: "tanh", nn.ReLU: "relu", nn.LeakyReLU: "leaky_relu"}


def _array(value: Any) -> np.ndarray:
    return np.ascontiguousarray(value.detach().cpu().numpy().astype(ARRAY_DTYPE))


def _observation_scaling(policy: HybridActorCriticPolicy) -> tuple[np.ndarray, np.ndarray]:
    """``obs_mid`` and ``obs_half`` of the features extractor (the format's ``scaled`` features)."""
    extractor = policy.features_extractor
    if isinstance(extractor, BoundsScaledFlatten):
        return _array(extractor.obs_mid), _array(extractor.obs_half)
    if type(extractor) is FlattenExtractor:
        size = int(np.prod(policy.observation_space.shape))  # type: ignore[arg-type]
        return np.zeros(size), np.ones(size)
    raise ValueError(
        f"Cannot export a HybridPPO policy whose features extractor is {type(extractor).__name__}: the format's networks "
        "read the observation scaled affinely (BoundsScaledFlatten, the default, or FlattenExtractor)"
    )


def _layers(modules: list[nn.Module], network: int, arrays: dict[str, np.ndarray]) -> list[dict[str, Any]]:
    """The ``layers`` of one network, adding its weights to ``arrays`` as ``net{network}_{j}_weight/bias``."""
    flat = [m for module in modules for m in (module if isinstance(module, nn.Sequential) else [module])]
    layers: list[dict[str, Any]] = []
    for j, layer in enumerate(flat):
        if isinstance(layer, nn.Linear):
            layers.append({"type": "linear", "in": layer.in_features, "out": layer.out_features})
            arrays[f"net{network}_{j}_weight"] = _array(layer.weight)
            arrays[f"net{network}_{j}_bias"] = _array(layer.bias)
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


def networks_head(policy: HybridActorCriticPolicy) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """
    The ``approximators`` section (``scaled`` features, ``networks`` head) of a HybridPPO policy and its arrays
    (``obs_mid``, ``obs_half`` and each network's layer weights).

    :raises ValueError: for a features extractor other than ``BoundsScaledFlatten`` or ``FlattenExtractor``, or a
        layer the format cannot hold (an activation other than tanh, ReLU, leaky ReLU)
    """
    spec = policy.spec
    n_outputs, outputs = output_layout(spec.n_types, spec.n_params)
    obs_mid, obs_half = _observation_scaling(policy)
    arrays: dict[str, np.ndarray] = {"obs_mid": obs_mid, "obs_half": obs_half}
    networks = []
    for i, (columns, modules) in enumerate(
        (
            (outputs["q"], [policy.shared_net, policy.type_net, policy.type_head]),
            (outputs["params"], [policy.shared_net, policy.params_net, policy.mean_head]),
            ([outputs["value"], outputs["value"] + 1], [policy.value_net, policy.value_head]),
        )
    ):
        networks.append({"columns": list(columns), "layers": _layers(modules, i, arrays)})
    head = {"type": "networks", "networks": networks}
    approximators = {
        "n_outputs": n_outputs,
        "outputs": outputs,
        "features": {"type": "scaled", "n_features": len(obs_mid)},
        "head": head,
    }
    return approximators, arrays


def export_contents(
    policy: HybridActorCriticPolicy, metadata: dict[str, Any] | None = None
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The header (without the arrays table) and the arrays of a HybridPPO policy's ``.aacp`` file (version 3)."""
    from sb3_aac import __version__
    from sb3_aac.export import action_header

    approximators, arrays = networks_head(policy)
    space = policy.observation_space
    size = len(arrays["obs_mid"])
    header = {
        "format": FORMAT_NAME,
        "version": written_version(approximators["head"]),
        "writer": f"sb3-aac {__version__}",
        "algorithm": "HybridPPO",
        "policy_class": type(policy).__name__,
        "observation": {"shape": [int(s) for s in space.shape], "size": size, "dtype": str(space.dtype)},  # type: ignore[union-attr]
        "action": action_header(policy.spec),
        "approximators": approximators,
        "metadata": dict(metadata or {}),
    }
    low = np.broadcast_to(np.asarray(space.low, dtype=ARRAY_DTYPE).ravel(), (size,))  # type: ignore[attr-defined]
    high = np.broadcast_to(np.asarray(space.high, dtype=ARRAY_DTYPE).ravel(), (size,))  # type: ignore[attr-defined]
    arrays = {
        "obs_low": np.ascontiguousarray(low),
        "obs_high": np.ascontiguousarray(high),
        **arrays,
        "param_low": policy.spec.low.astype(ARRAY_DTYPE),
        "param_high": policy.spec.high.astype(ARRAY_DTYPE),
    }
    return header, arrays
