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
from stable_baselines3.common.preprocessing import is_image_space
from stable_baselines3.common.torch_layers import FlattenExtractor

from sb3_aac.common.network_export import array_of, network_layers, policy_file_contents
from sb3_aac.hppo.torch_layers import BoundsScaledFlatten
from sb3_aac.hppo.policies import HybridActorCriticPolicy
from sb3_aac.runtime.format import output_layout


def _observation_scaling(policy: HybridActorCriticPolicy) -> tuple[np.ndarray, np.ndarray]:
    """``obs_mid`` and ``obs_half`` of the features extractor (the format's ``scaled`` features), with SB3's division
    of image observations by 255 (``normalize_images``) folded in."""
    extractor = policy.features_extractor
    # SB3's preprocessing divides an image by 255 before the extractor: (s / 255 - mid) / half = (s - 255 mid) / (255 half)
    scale = 255.0 if policy.normalize_images and is_image_space(policy.observation_space) else 1.0
    if isinstance(extractor, BoundsScaledFlatten):
        return scale * array_of(extractor.obs_mid), scale * array_of(extractor.obs_half)
    if type(extractor) is FlattenExtractor:
        size = int(np.prod(policy.observation_space.shape))  # type: ignore[arg-type]
        return np.zeros(size), np.full(size, scale)
    raise ValueError(
        f"Cannot export a HybridPPO policy whose features extractor is {type(extractor).__name__}: the format's networks "
        "read the observation scaled affinely (BoundsScaledFlatten, the default, or FlattenExtractor)"
    )


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
        networks.append({"columns": list(columns), "layers": network_layers(modules, i, arrays)})
    head = {"type": "networks", "networks": networks}
    approximators = {
        "n_outputs": n_outputs,
        "outputs": outputs,
        "features": {"type": "scaled", "n_features": len(obs_mid)},
        "head": head,
    }
    return approximators, arrays


def export_contents(
    policy: HybridActorCriticPolicy, action: dict[str, Any], metadata: dict[str, Any] | None = None
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """
    The header (without the arrays table) and the arrays of a HybridPPO policy's ``.aacp`` file (version 3), with
    ``action`` as the header's action section (:func:`sb3_aac.export.action_header` of the policy's spec).
    """
    approximators, arrays = networks_head(policy)
    return policy_file_contents("HybridPPO", policy, policy.spec, approximators, arrays, action, metadata)
