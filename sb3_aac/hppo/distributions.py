"""
The hybrid action distribution of H-PPO: a categorical over the K action types and, per type, a diagonal Gaussian
over that type's own parameters (in the scaled space of :class:`~sb3_aac.common.spaces.ParameterizedActionSpec`).

An action is packed into one tensor row ``[k, x]`` of length ``1 + n_params``: the type ``k`` (0-based, as a float)
and a sample ``x`` of *every* type's parameters (the Gaussians are independent, so drawing the unused types' costs
nothing and keeps the rows rectangular). Only ``x_k``, the chosen type's slice, is part of the executed action:

``log pi(k, x | s) = log p(k | s) + log N(x_k; mu_k(s), sigma_k)``

so the other types' entries of ``x`` (and of ``mu``) never change a log-probability, and neither does the number of
parameters the other types own.
"""

from __future__ import annotations

import math
from typing import TypeVar

import numpy as np
import torch as th
from stable_baselines3.common.distributions import Distribution
from torch import nn
from torch.nn import functional as F

SelfHybridDistribution = TypeVar("SelfHybridDistribution", bound="HybridDistribution")

HALF_LOG_2PI_E = 0.5 * math.log(2.0 * math.pi * math.e)  # entropy of N(0, 1), per dimension
HALF_LOG_2PI = 0.5 * math.log(2.0 * math.pi)


def sample_packed(
    type_logits: np.ndarray, mean: np.ndarray, std: np.ndarray, exponential: np.ndarray, normal: np.ndarray
) -> np.ndarray:
    """
    :meth:`HybridDistribution.sample`'s draw in numpy, on given noise: packed rows ``(n, 1 + n_params)`` of the type
    ``argmax_k p(k|s) / q_k`` (``exponential``: ``q``, ``(n, K)`` draws of Exp(1), which makes the type a draw from
    ``p``) and every type's parameters ``mean + std * normal`` (``std``: ``exp(log_std)``; ``normal``: ``(n, n_params)``
    standard normal draws). ``type_logits`` ``(n, K)`` need not be normalised.
    """
    # p(k|s) up to a positive factor per row, which the argmax ignores
    probs = np.exp(type_logits - type_logits.max(axis=1, keepdims=True))
    types = (probs / exponential).argmax(axis=1)
    params = mean + std * normal
    return np.concatenate((types[:, None].astype(params.dtype), params), axis=1)


class HybridDistribution(Distribution):
    """
    Categorical over K action types times a diagonal Gaussian per type over the type's parameters.

    The parameter entropy is weighted by the type probabilities: :meth:`entropy` is the exact entropy of the pair
    (chain rule) ``H(k, x_k) = H(k) + sum_k p(k|s) H(N_k)`` with ``H(N_k) = sum_{j in k} (log sigma_j + 0.5 log(2 pi
    e))`` (differential entropy, so it is negative for small sigmas). :meth:`entropy_parts` gives the two terms
    apart; there the weights ``p(k|s)`` are detached, so a parameter-entropy bonus widens the Gaussians without pulling
    the type probabilities towards the types that own more (or wider) parameters.

    Samples are not squashed: the Gaussian is unbounded and the algorithm clips the executed parameters to ``[-1, 1]``
    (the space's bounds) when it builds the env action, as SB3's PPO clips Box actions. Log-probabilities are those of
    the unclipped sample, so the PPO ratio is exact for this Gaussian and the entropy has its closed form (a tanh
    squash would need the Jacobian correction and has no closed-form entropy).

    :param param_type: ``(n_params,)`` the type owning each scalar parameter (``spec.param_type``)
    :param n_types: Number of action types K
    """

    def __init__(self, param_type: np.ndarray, n_types: int):
        super().__init__()  # type: ignore[no-untyped-call]
        self.n_types = n_types
        self.n_params = len(param_type)
        # owner[k, j] = 1.0 where scalar parameter j belongs to type k
        self.owner = th.as_tensor(np.arange(n_types)[:, None] == np.asarray(param_type)[None, :], dtype=th.float32)
        self.type_logits: th.Tensor
        """``(n, K)`` normalised: ``log p(k|s)``."""
        self.mean: th.Tensor
        self.log_std: th.Tensor

    def proba_distribution_net(  # type: ignore[override]
        self, latent_type_dim: int, latent_params_dim: int, log_std_init: float = 0.0
    ) -> tuple[nn.Module, nn.Module, nn.Parameter]:
        """
        The output layers: type logits ``(K,)`` and parameter means ``(n_params,)`` from the two actors' latent
        features, and the state-independent log standard deviations ``(n_params,)``.
        """
        type_net = nn.Linear(latent_type_dim, self.n_types)
        mean_net = nn.Linear(latent_params_dim, self.n_params)
        log_std = nn.Parameter(th.full((self.n_params,), float(log_std_init)), requires_grad=True)
        return type_net, mean_net, log_std

    def proba_distribution(
        self: SelfHybridDistribution, type_logits: th.Tensor, mean: th.Tensor, log_std: th.Tensor
    ) -> SelfHybridDistribution:
        """
        :param type_logits: ``(n, K)``
        :param mean: ``(n, n_params)`` parameter means (scaled space)
        :param log_std: ``(n_params,)`` or ``(n, n_params)`` log standard deviations
        """
        # The categorical's arithmetic as torch.distributions.Categorical's, without its per-call validation.
        self.type_logits = type_logits - type_logits.logsumexp(dim=-1, keepdim=True)
        self._type_probs: th.Tensor | None = None
        self.mean = mean
        self.log_std = log_std.expand_as(mean)
        self.owner = self.owner.to(mean.device)
        return self

    @property
    def type_probs(self) -> th.Tensor:
        """``(n, K)``: ``p(k|s)``."""
        if self._type_probs is None:
            self._type_probs = F.softmax(self.type_logits, dim=-1)
        return self._type_probs

    def _chosen(self, types: th.Tensor) -> th.Tensor:
        """``(n, n_params)`` True where the parameter belongs to the row's type."""
        return self.owner[types] > 0

    def log_prob_parts(self, actions: th.Tensor) -> tuple[th.Tensor, th.Tensor]:
        """
        ``log p(k|s)`` and ``log N(x_k; mu_k, sigma_k)`` of packed actions ``(n, 1 + n_params)``, each ``(n,)``.
        A type without parameters has parameter log-probability 0.
        """
        types = actions[:, 0].long()
        params = actions[:, 1:]
        per_param = -(((params - self.mean) / self.log_std.exp()) ** 2) / 2 - self.log_std - HALF_LOG_2PI
        # where(), not a product with the mask: an unused entry that is huge (inf) must not make the sum NaN
        type_log_prob = self.type_logits.gather(-1, types.unsqueeze(-1)).squeeze(-1)
        return type_log_prob, th.where(self._chosen(types), per_param, 0.0).sum(dim=1)

    def log_prob(self, actions: th.Tensor) -> th.Tensor:
        """``log p(k|s) + log N(x_k; mu_k, sigma_k)``, ``(n,)``."""
        type_log_prob, param_log_prob = self.log_prob_parts(actions)
        return type_log_prob + param_log_prob

    def type_entropy(self) -> th.Tensor:
        """``H(k|s)``, ``(n,)``."""
        logits = th.clamp(self.type_logits, min=th.finfo(self.type_logits.dtype).min)
        return -(logits * self.type_probs).sum(-1)

    def param_entropies(self) -> th.Tensor:
        """``(n, K)``: the entropy of each type's Gaussian (0 for a type without parameters)."""
        return (self.log_std + HALF_LOG_2PI_E) @ self.owner.T

    def entropy_parts(self) -> tuple[th.Tensor, th.Tensor]:
        """``H(k|s)`` and ``sum_k p(k|s) H(N_k)`` with ``p`` detached (see the class docstring), each ``(n,)``."""
        weights = self.type_probs.detach()
        return self.type_entropy(), (weights * self.param_entropies()).sum(dim=1)

    def entropy(self) -> th.Tensor:
        """The exact entropy ``H(k|s) + sum_k p(k|s) H(N_k)``, ``(n,)``."""
        return self.type_entropy() + (self.type_probs * self.param_entropies()).sum(dim=1)

    def sample(self) -> th.Tensor:
        """Packed actions ``(n, 1 + n_params)``: ``k ~ p(.|s)`` and every type's parameters ``~ N(mu, sigma)``."""
        # th.multinomial's draw of one sample, argmax(p / q) with q ~ Exp(1) (the same generator calls, so the same
        # types), without its checks of the probabilities, which synchronise with the device twice per call.
        probs = self.type_probs
        types = (probs / th.empty_like(probs).exponential_()).argmax(dim=-1)
        params = self.mean + self.log_std.exp() * th.randn_like(self.mean)
        return th.cat((types.unsqueeze(1).to(params.dtype), params), dim=1)

    def mode(self) -> th.Tensor:
        """Packed actions ``(n, 1 + n_params)``: the most probable type (the lowest index on ties) and the means."""
        types = self.type_logits.argmax(dim=1)
        return th.cat((types.unsqueeze(1).to(self.mean.dtype), self.mean), dim=1)

    def actions_from_params(
        self, type_logits: th.Tensor, mean: th.Tensor, log_std: th.Tensor, deterministic: bool = False
    ) -> th.Tensor:
        self.proba_distribution(type_logits, mean, log_std)
        return self.get_actions(deterministic=deterministic)

    def log_prob_from_params(self, type_logits: th.Tensor, mean: th.Tensor, log_std: th.Tensor) -> tuple[th.Tensor, th.Tensor]:
        actions = self.actions_from_params(type_logits, mean, log_std)
        return actions, self.log_prob(actions)
