"""
A critic of the parameters for SarsaAAC's parameter actor (not in Uc-Cetina 2013): the ``parameter_update="critic"``
of :class:`sb3_aac.SarsaAAC`.

The paper's CACLA step moves type ``k``'s parameters toward the executed ones ``x`` whenever the state critic's TD error
``delta = r + gamma * V(s') - V(s)`` is positive. That sign mixes everything that happened in the step (the reward's
noise, the value of the chosen *type*, the next state's luck) with what the parameters did, so half the steps of a
sample can point the wrong way. The critic here learns, per type ``k``, how ``delta`` depends on the parameters,
by regression over the stream of samples, a linear advantage in the exploration noise ``e = (x - mu(s)) / sigma``
(``sigma`` the current parameter noise, so that ``e`` is of order 1 and ``g`` learns as fast as ``b``):

    ``A_k(s, x) = b_k(s) + g_k(s) . (x - mu_k(s)) / sigma``

(the compatible form of Silver et al. 2014, "Deterministic Policy Gradient Algorithms", Sec. 4.3, with a gradient
``g_k(s)`` learned by the policy's own family instead of the actor's features). ``b_k(s)`` takes the type's advantage
and the mean of ``delta``, so ``g_k(s) / sigma`` estimates ``dQ/dx`` at ``mu(s)`` from what ``delta`` says over many
samples (the mean, where CACLA follows the sign of single samples: with skewed returns the two disagree).
Only type ``k``'s parameters enter its ``A_k`` (as MP-DQN keeps one type's parameters out of another's value).

Per sample ``(s, k, x, delta)``:

- the critic takes one normalised step on ``0.5 * (delta - A_k(s, x))**2``: the residual, divided by
  ``1 + |e|**2`` (the normalised LMS step on the noise features), is the error of ``b_k``, and times ``e_j`` that
  of ``g_kj``; for one sample and a linear family a rate of 1 moves ``A_k(s, x)`` onto ``delta``;
- the parameter actor takes CACLA's step toward ``x`` only where the critic (before this step) says the executed
  parameters gain: ``A_k(s, x) - A_k(s, mu(s)) = g_k(s) . e > 0``. Its expected step is along ``g_k(s)``
  (a normalised deterministic policy gradient), and CACLA's units stay: a rate of 1 lands on ``x``.

The critic is an instance of the policy's own family and arguments (so the same streaming steps, lane rule and
return units; :class:`~sb3_aac.sarsa_aac.policies.SarsaAACPolicy`'s columns read ``Q_k -> b_k``, parameter ``j ->
g_j``, and ``V`` unused), with its outputs starting at 0 (no gain is claimed before one is seen). It only shapes
training: ``predict`` and the exported policies read the actor alone, so the critic is saved with the model but not
exported.
"""

from __future__ import annotations

import math

import numpy as np
from torch import nn

from sb3_aac.sarsa_aac.deep import DeepKernel
from sb3_aac.sarsa_aac.policies import DeepPolicy, SarsaAACPolicy

# The parameter actor's update: the paper's CACLA (gated by the sign of delta), or CACLA gated by this critic.
PARAMETER_UPDATES = ("cacla", "critic")


class ParameterCritic(nn.Module):
    """
    The per-type advantage ``A_k(s, x) = b_k(s) + g_k(s) . (x - mu_k(s)) / sigma`` (module docstring).

    :param policy: the actor; the critic is a new instance of its class with its constructor arguments
    """

    def __init__(self, policy: SarsaAACPolicy):
        super().__init__()
        self.approximators: SarsaAACPolicy = type(policy)(**policy._get_constructor_parameters())
        self.approximators.scale_outputs(list(range(policy.n_outputs)), 0.0)
        # owns[k, j] = 1 if scalar parameter j belongs to type k.
        self.owns = policy.param_table[1]

    def parameter_errors(
        self,
        obs: np.ndarray,
        k: np.ndarray,
        params: np.ndarray,
        mu: np.ndarray,
        delta: np.ndarray,
        rate: float,
        hidden_gain: float,
        noise_scale: float,
        observe: bool = True,
    ) -> np.ndarray:
        """
        One step of the critic on a batch, and the parameter actor's errors (its CACLA targets where the critic says
        the executed parameters gain).

        :param obs: ``(n, D)`` float64 observations ``s``
        :param k: ``(n,)`` executed types
        :param params: ``(n, P)`` executed (clipped) scaled parameters ``x``
        :param mu: ``(n, P)`` the parameter actor's outputs ``mu(s)`` on its current weights
        :param delta: ``(n,)`` the state critic's TD errors
        :param rate: the critic's normalised learning rate, in ``[0, 1]``
        :param hidden_gain: the factor on hidden-layer steps, ``1 / return_scale**2`` (see :class:`sb3_aac.SarsaAAC`)
        :param noise_scale: ``sigma``, the standard deviation of the exploration noise on the scaled parameters (0: 1)
        :param observe: whether a deep critic folds ``obs`` into its input normalisation (False for replayed samples,
            which it has seen)
        :return: ``(n, P)`` target minus output of the parameter actor: ``x - mu`` on type ``k``'s parameters where
            ``g_k(s) . (x - mu) > 0``, else 0 (with ``noise_scale`` 0 the executed parameters are ``mu``: no step)
        :raises FloatingPointError: if the critic's outputs are not finite
        """
        model = self.approximators
        if observe and isinstance(model, DeepPolicy):
            model.approximators.observe(obs)
        kernel = model.kernel()
        # b_k and g_k: the "q" and "params" columns; a deep critic skips its unused value network.
        out, cache = kernel.forward(obs, ("q", "params")) if isinstance(kernel, DeepKernel) else kernel.forward(obs)
        if not math.isfinite(out.sum()):
            raise FloatingPointError(
                "SarsaAAC's parameter critic has non-finite outputs: lower learning_rate (its rate), or use "
                'parameter_update="cacla"'
            )
        rows, ps = np.arange(len(k)), model.param_slice
        scale = noise_scale if noise_scale > 0 else 1.0
        noise = (params - mu) * (self.owns[k] / scale)
        gain = (out[:, ps] * noise).sum(1)
        residual = (delta - out[rows, k] - gain) / (1.0 + (noise * noise).sum(1))
        err = np.zeros_like(out)
        err[rows, k] = residual
        err[:, ps] = residual[:, None] * noise
        lr = np.full(model.n_outputs, rate)
        gains = np.full(model.n_outputs, hidden_gain)
        if isinstance(kernel, DeepKernel):
            kernel.update(cache, err, lr, gains, k)
        else:
            kernel.update(cache, err, lr, gains)
        errors: np.ndarray = noise * (scale * (gain > 0))[:, None]
        return errors

    def reset_kernel(self) -> None:
        """Rebuild the numpy kernel on the current storage (after a load or a move; see ``SarsaAACPolicy.rebind``)."""
        self.approximators.rebind()


def check_parameter_update(parameter_update: object) -> None:
    """A ``ValueError`` naming the allowed values unless ``parameter_update`` is one of :data:`PARAMETER_UPDATES`."""
    if parameter_update not in PARAMETER_UPDATES:
        raise ValueError(
            f"parameter_update must be one of {list(PARAMETER_UPDATES)} (the paper's CACLA, or CACLA gated by a critic "
            f"of the parameters), got {parameter_update!r}"
        )
