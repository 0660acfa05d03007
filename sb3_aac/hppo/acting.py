"""
HybridPPO's actors during a rollout: the type logits and parameter means of one observation batch per env step, as
numpy arrays.

On one observation the arithmetic of three 64x64 networks takes microseconds, and torch's per-call machinery
(module calls, autograd bookkeeping, tensor conversions) several hundred: on the paper env 258 us a step through
``policy(obs)`` against 27 us through the runtime's numpy forward pass. The weights do not change within a rollout, so
a :class:`RolloutActor` copies them once at its start.
"""

from __future__ import annotations

import numpy as np
import torch as th
from stable_baselines3.common.utils import obs_as_tensor

from sb3_aac.hppo.export import networks_head
from sb3_aac.hppo.policies import HybridActorCriticPolicy
from sb3_aac.runtime.forward import ScaledNetworks


class RolloutActor:
    """
    The actors of ``policy`` as they are when made: :meth:`__call__` gives the type logits and parameter means of
    observations. Where the policy exports to the ``.aacp`` format (its default features extractors, and Linear layers
    with tanh, ReLU or leaky ReLU activations), through the runtime's :class:`~sb3_aac.runtime.forward.ScaledNetworks`
    on a float64 copy of the weights (the formulas an exported policy runs, on CPU whatever the policy's device);
    otherwise through the policy's torch networks (:meth:`HybridActorCriticPolicy.actor_outputs`). The two agree to
    float32 rounding.

    :param policy: the policy whose current weights act
    """

    def __init__(self, policy: HybridActorCriticPolicy):
        self.policy = policy
        self.networks: ScaledNetworks | None
        try:
            approximators, arrays = networks_head(policy)
        except ValueError:
            self.networks = None
        else:
            self.networks = ScaledNetworks(arrays["obs_mid"], arrays["obs_half"], approximators["head"]["networks"], arrays)

    def __call__(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Observations ``(n, *obs_shape)`` -> type logits ``(n, K)`` (not normalised), parameter means ``(n, n_params)``."""
        if self.networks is None:
            with th.no_grad():
                type_logits, mean = self.policy.actor_outputs(obs_as_tensor(obs, self.policy.device))
            return type_logits.cpu().numpy(), mean.cpu().numpy()
        x = self.networks.features(obs.reshape(len(obs), -1))
        return self.networks.network(0, x), self.networks.network(1, x)
