"""
Export a trained SarsaAAC, HybridPPO, P-DQN or MP-DQN policy for a runtime without torch or Stable-Baselines3 (a
RoboCup agent, a C++ program).

The file holds plain float64 arrays and a JSON description, never pickled objects; see ``docs/export-format.md``
and :class:`sb3_aac.runtime.RuntimePolicy`, which reads it with numpy alone::

    from sb3_aac import SarsaAAC, export_policy, RuntimePolicy

    model = SarsaAAC.load("model.zip")
    export_policy(model, "dribbler.aacp")
    action_type, params = RuntimePolicy.load("dribbler.aacp").act(obs)
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from sb3_aac.common.output_files import replaced_atomically
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.sarsa_aac.policies import DeepPolicy, DenseBankPolicy, TilePolicy
from sb3_aac.runtime.format import (
    ARRAY_DTYPE,
    FORMAT_NAME,
    TILE_ARRAYS,
    encode_policy_file,
    expected_array_shapes,
    output_layout,
    policy_file_path,
    read_policy_file,
    written_version,
)
from sb3_aac.runtime.forward import network_array_shapes
from sb3_aac.version import __version__


ExportablePolicy = DenseBankPolicy | TilePolicy | DeepPolicy
"""The policies the format describes: the numpy banks of the dense families and of tile coding, and the deep
policy's networks."""


def _policy_of(model: Any) -> ExportablePolicy:
    policy = getattr(model, "policy", model)
    if not isinstance(policy, (DenseBankPolicy, TilePolicy, DeepPolicy)):
        raise ValueError(
            "export_policy needs a SarsaAAC model or a SarsaAACPolicy on a numpy bank (MlpPolicy, RbfMlpPolicy, "
            f"RbfPolicy, TilePolicy, DeepPolicy or their subclasses), or a HybridPPO, PDQN or MPDQN model, got "
            f"{type(model).__name__}"
        )
    return policy


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


def action_header(spec: ParameterizedActionSpec) -> dict[str, Any]:
    """The header's ``action`` section: the layout, the types' parameter counts, shapes, dtypes and offsets."""
    return {
        "layout": spec.layout,
        "n_types": spec.n_types,
        "type_start": spec.start,
        "n_params": spec.n_params,
        "types": [
            {"dim": dim, "shape": [int(s) for s in box.shape], "dtype": str(box.dtype), "offset": spec.offsets[j]}
            for j, (dim, box) in enumerate(zip(spec.dims, spec.boxes, strict=True))
        ],
    }


def policy_header(policy: ExportablePolicy, metadata: dict[str, Any] | None = None) -> dict[str, Any]:
    """The JSON header (without the arrays table) describing a dense-bank, tile or deep policy."""
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
        "action": action_header(spec),
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


def export_policy(model: Any, path: str | os.PathLike[str], metadata: dict[str, Any] | None = None) -> Path:
    """
    Write a trained SarsaAAC, HybridPPO, P-DQN or MP-DQN policy as plain arrays and a JSON description (format
    ``sb3-aac-policy``: version 4 for P-DQN's ``pdqn`` head, 3 for a ``networks`` head, a
    :class:`~sb3_aac.sarsa_aac.policies.DeepPolicy`'s or HybridPPO's, else 2: the oldest version that holds the policy,
    since older readers cannot compute the newer heads). HybridPPO's decisions are its ``mode()``: the most probable
    type and its mean parameters (:mod:`sb3_aac.hppo.export`); P-DQN's are ``predict(deterministic=True)``'s
    (:mod:`sb3_aac.pdqn.export`).

    :param model: a :class:`sb3_aac.SarsaAAC`, :class:`sb3_aac.HybridPPO`, :class:`sb3_aac.PDQN` or
        :class:`sb3_aac.MPDQN` model, or its policy
    :param path: where to write; ``.aacp`` is appended when the name has no suffix (``RuntimePolicy.load`` accepts
        the same name)
    :param metadata: JSON-serialisable extras stored in the header (e.g. ``{"env_id": "RoboCupDribble-v0"}``)
    :return: the path written. The file is written to a temporary name beside it, re-read and checked with
        :func:`sb3_aac.runtime.format.read_policy_file`, flushed to disk, then renamed into place: an interrupted export
        leaves the earlier file (or none), never a part or a stray temporary.
    """
    from sb3_aac.hppo.policies import HybridActorCriticPolicy
    from sb3_aac.pdqn.policies import PDQNPolicy

    path = Path(policy_file_path(path))
    meta = dict(metadata or {})
    num_timesteps = getattr(model, "num_timesteps", None)
    if num_timesteps is not None:
        meta.setdefault("num_timesteps", int(num_timesteps))
    torch_policy = getattr(model, "policy", model)
    if isinstance(torch_policy, HybridActorCriticPolicy):
        from sb3_aac.hppo import export as hppo_export

        header, arrays = hppo_export.export_contents(torch_policy, action_header(torch_policy.spec), meta)
    elif isinstance(torch_policy, PDQNPolicy):
        from sb3_aac.pdqn import export as pdqn_export

        header, arrays = pdqn_export.export_contents(torch_policy, action_header(torch_policy.spec), meta)
    else:
        policy = _policy_of(model)
        header, arrays = policy_header(policy, meta), policy_arrays(policy)
    shapes = {name: a.shape for name, a in arrays.items()}
    assert shapes == expected_array_shapes({**header, "arrays": {}}), "writer/reader disagree"
    try:
        data = encode_policy_file(header, arrays)
    except ValueError as error:  # allow_nan=False: a NaN in the metadata
        raise ValueError(f"metadata must be JSON-serialisable without NaN/inf: {error}") from error
    with replaced_atomically(path) as tmp:
        tmp.write_bytes(data)
        read_policy_file(tmp)
    return path
