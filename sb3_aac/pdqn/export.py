"""
A P-DQN / MP-DQN policy in the ``.aacp`` format's ``pdqn`` head (format version 4, ``docs/export-format.md``).

Network 0 is the parameter actor ``x(s)`` (its fixed offset folded into the last layer's bias, then the tanh of
``param_bounding="tanh"``), writing the parameter columns; network 1 is the Q network on ``[s, x(s)]``, writing the Q
columns, in one pass or (MP-DQN) in ``K`` masked passes. The reader's argmax of Q and its clipping of the chosen
type's parameters to their bounds are ``predict(deterministic=True)``'s. The target networks are not written.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sb3_aac.common.network_export import array_of, network_layers, policy_file_contents
from sb3_aac.pdqn.policies import PDQNPolicy
from sb3_aac.runtime.format import output_layout


def pdqn_head(policy: PDQNPolicy) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """
    The ``approximators`` section (``scaled`` features, ``pdqn`` head) of a P-DQN / MP-DQN policy and its arrays
    (``obs_mid``, ``obs_half`` and both networks' layer weights).

    :raises ValueError: for an activation the format cannot hold (anything but tanh, ReLU, leaky ReLU)
    """
    spec = policy.spec
    n_outputs, outputs = output_layout(spec.n_types, spec.n_params)
    arrays: dict[str, np.ndarray] = {"obs_mid": array_of(policy.obs_mid), "obs_half": array_of(policy.obs_half)}
    actor = network_layers([policy.actor.net], 0, arrays)
    last = len(actor) - 1  # ParamActor's last layer is linear: x(s) = net(s) + offset
    arrays[f"net0_{last}_bias"] = arrays[f"net0_{last}_bias"] + array_of(policy.actor.offset)
    if policy.actor.squash:
        actor.append({"type": "activation", "function": "tanh"})
    networks = [
        {"columns": outputs["params"], "layers": actor},
        {"columns": outputs["q"], "layers": network_layers([policy.q_net.net], 1, arrays)},
    ]
    approximators = {
        "n_outputs": n_outputs,
        "outputs": outputs,
        "features": {"type": "scaled", "n_features": len(arrays["obs_mid"])},
        "head": {"type": "pdqn", "multi_pass": policy.multi_pass, "networks": networks},
    }
    return approximators, arrays


def export_contents(
    policy: PDQNPolicy, action: dict[str, Any], metadata: dict[str, Any] | None = None
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """
    The header (without the arrays table) and the arrays of a P-DQN / MP-DQN policy's ``.aacp`` file (version 4), with
    ``action`` as the header's action section (:func:`sb3_aac.export.action_header` of the policy's spec).
    """
    approximators, arrays = pdqn_head(policy)
    algorithm = "MPDQN" if policy.multi_pass else "PDQN"
    return policy_file_contents(algorithm, policy, policy.spec, approximators, arrays, action, metadata)
