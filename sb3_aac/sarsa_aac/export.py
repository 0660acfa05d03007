"""
A SarsaAAC policy in the ``.aacp`` format (``docs/export-format.md``): a dense bank's ``scaled`` or ``rbf`` features
with a ``linear`` or ``tanh_mlp`` head (version 2), tile coding's ``tiles`` features (version 2), or DeepPolicy's
``networks`` head (version 3).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from sb3_aac.runtime.format import ARRAY_DTYPE, FORMAT_NAME, TILE_ARRAYS, output_layout, written_version
from sb3_aac.runtime.forward import network_array_shapes
from sb3_aac.sarsa_aac.policies import DeepPolicy, DenseBankPolicy, TilePolicy
from sb3_aac.version import __version__

EXPORTABLE = (DenseBankPolicy, TilePolicy, DeepPolicy)
ExportablePolicy = DenseBankPolicy | TilePolicy | DeepPolicy
"""The policies the format describes: the numpy banks of the dense families and of tile coding, and the deep
policy's networks."""


def policy_arrays(policy: ExportablePolicy) -> dict[str, np.ndarray]:
    """The arrays of the file format, as float64 numpy arrays, from a dense-bank, tile or deep policy."""
    box = policy.observation_space
    assert isinstance(box, spaces.Box)  # SarsaAAC policies take Box observations only
    bank = policy.approximators.arrays()
    d = policy.approximators.n_inputs
    arrays = {
        "obs_low": np.broadcast_to(np.asarray(box.low, dtype=np.float64).ravel(), (d,)),
        "obs_high": np.broadcast_to(np.asarray(box.high, dtype=np.float64).ravel(), (d,)),
        "obs_mid": bank["obs_mid"],
        "obs_half": bank["obs_half"],
        "param_low": policy.spec.low,
        "param_high": policy.spec.high,
    }
    if isinstance(policy, TilePolicy):
        names = [name for name in TILE_ARRAYS if name not in arrays]
    elif isinstance(policy, DeepPolicy):
        names = list(network_array_shapes(policy.approximators.networks))
    else:
        names = ["rbf_centers", "rbf_widths"] if policy.n_rbf is not None else []
        names += ["weight", "bias"] if policy.hidden_units is None else ["weight1", "bias1", "weight2", "bias2"]
    arrays.update((name, bank[name]) for name in names)
    return {name: np.ascontiguousarray(np.asarray(v).astype(ARRAY_DTYPE)) for name, v in arrays.items()}


def policy_header(policy: ExportablePolicy, action: dict[str, Any], metadata: dict[str, Any] | None = None) -> dict[str, Any]:
    """The JSON header (without the arrays table) describing a dense-bank, tile or deep policy, with ``action`` as its
    action section (:func:`sb3_aac.export.action_header` of the policy's spec)."""
    bank, spec = policy.approximators, policy.spec
    k, n_params = spec.n_types, spec.n_params
    n_outputs, outputs = output_layout(k, n_params)
    head = _head_header(policy)
    obs_shape = policy.observation_space.shape
    assert obs_shape is not None  # SarsaAAC policies take Box observations only
    return {
        "format": FORMAT_NAME,
        "version": written_version(head),
        "writer": f"sb3-aac {__version__}",
        "algorithm": "SarsaAAC",
        "policy_class": type(policy).__name__,
        "observation": {
            "shape": [int(s) for s in obs_shape],
            "size": int(bank.n_inputs),
            "dtype": str(policy.observation_space.dtype),
        },
        "action": action,
        "approximators": {
            "n_outputs": n_outputs,
            "outputs": outputs,
            "features": _features_header(policy),
            "head": head,
        },
        "metadata": dict(metadata or {}),
    }


def _head_header(policy: ExportablePolicy) -> dict[str, Any]:
    if isinstance(policy, DeepPolicy):
        return {"type": "networks", "networks": policy.approximators.networks}
    if isinstance(policy, TilePolicy) or policy.hidden_units is None:
        return {"type": "linear"}
    return {"type": "tanh_mlp", "hidden_units": policy.hidden_units}


def _features_header(policy: ExportablePolicy) -> dict[str, Any]:
    if isinstance(policy, TilePolicy):
        bank = policy.approximators
        return {
            "type": "tiles",
            "groups": [list(group) for group in bank.groups],
            "tiles_per_input": bank.tiles_per_input,
            "n_tilings": bank.n_tilings,
            "n_codings": bank.n_active,
            "group_size": int(np.shape(bank.tile_inputs)[1]),
            "n_features": bank.n_features,
        }
    if isinstance(policy, DeepPolicy):
        return {"type": "scaled", "n_features": policy.approximators.n_inputs}
    dense = policy.approximators
    if policy.n_rbf is None:
        return {"type": "scaled", "n_features": dense.n_features}
    window = None if policy.rbf_window is None else float(policy.rbf_window)
    return {
        "type": "rbf",
        "n_rbf": policy.n_rbf,
        "rbf_width": float(policy.rbf_width),
        "rbf_window": window,
        "n_features": dense.n_features,
    }


def export_contents(
    policy: ExportablePolicy, action: dict[str, Any], metadata: dict[str, Any] | None = None
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The header (without the arrays table) and the arrays of a SarsaAAC policy's ``.aacp`` file, with ``action`` as
    the header's action section (:func:`sb3_aac.export.action_header` of the policy's spec)."""
    return policy_header(policy, action, metadata), policy_arrays(policy)
