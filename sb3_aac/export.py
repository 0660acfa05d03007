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

from sb3_aac.common.output_files import replaced_atomically
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.hppo import export as hppo_export
from sb3_aac.hppo.policies import HybridActorCriticPolicy
from sb3_aac.pdqn import export as pdqn_export
from sb3_aac.pdqn.policies import PDQNPolicy
from sb3_aac.runtime.format import encode_policy_file, expected_array_shapes, policy_file_path, read_policy_file
from sb3_aac.sarsa_aac import export as sarsa_export
from sb3_aac.sarsa_aac.export import EXPORTABLE, ExportablePolicy


def _sarsa_policy(model: Any) -> ExportablePolicy:
    """The SarsaAAC policy of ``model`` (a model or a policy); raises ValueError for anything the format cannot hold."""
    policy = getattr(model, "policy", model)
    if not isinstance(policy, EXPORTABLE):
        raise ValueError(
            "export_policy needs a SarsaAAC model or a SarsaAACPolicy on a numpy bank (MlpPolicy, RbfMlpPolicy, "
            f"RbfPolicy, TilePolicy, DeepPolicy or their subclasses), or a HybridPPO, PDQN or MPDQN model, got "
            f"{type(model).__name__}"
        )
    return policy


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
    path = Path(policy_file_path(path))
    meta = dict(metadata or {})
    num_timesteps = getattr(model, "num_timesteps", None)
    if num_timesteps is not None:
        meta.setdefault("num_timesteps", int(num_timesteps))
    torch_policy = getattr(model, "policy", model)
    if isinstance(torch_policy, HybridActorCriticPolicy):
        header, arrays = hppo_export.export_contents(torch_policy, action_header(torch_policy.spec), meta)
    elif isinstance(torch_policy, PDQNPolicy):
        header, arrays = pdqn_export.export_contents(torch_policy, action_header(torch_policy.spec), meta)
    else:
        policy = _sarsa_policy(model)
        header, arrays = sarsa_export.export_contents(policy, action_header(policy.spec), meta)
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
