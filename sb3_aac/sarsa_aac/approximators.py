"""
Banks of independent function approximators, stored as batched tensors and trained in closed form with numpy.

An :class:`ApproximatorBank` holds ``A`` independent approximators ``f_a(s)``, ``a = 0..A-1``, of one observation
``s``. It is a fixed feature layer followed by a head:

- feature layer (no trainable weights), ``x = phi(s)`` with ``F`` features:

  - ``n_rbf=None``: the inputs scaled affinely from ``[low, high]`` to ``[-1, 1]`` (``F = D``);
  - ``n_rbf=m``: per-input arrays of ``m`` Gaussian radial basis functions on the scaled inputs,
    ``x[i*m + j] = exp(-(s~_i - c_ij)**2 / (2 * sigma_ij**2))`` (``F = D*m``), set to 0 outside a window of
    ``rbf_window`` standard deviations around the input (not computed at all);

- head, one per approximator (the heads share the features but no weights):

  - ``hidden_units=None``: linear, ``f_a = weight[a] . x + bias[a]``;
  - ``hidden_units=H``: one hidden tanh layer,
    ``f_a = weight2[a] . tanh(weight1[a] @ x + bias1[a]) + bias2[a]``.

The three function approximators of Uc-Cetina (2013, Sec. 4.2) are the configurations
(``n_rbf=None``, ``H``) (MLP), (``m``, ``H``) (MLP with an RBF filter layer) and (``m``, ``None``) (RBF arrays).

Training is gradient descent on ``0.5 * err**2`` with *normalised* step sizes (chosen by us; the paper gives none),
one sample at a time:

- per sample, each layer's step is divided by ``1 + ||input of that layer||**2`` (normalised LMS). For one sample
  and a linear head a learning rate of 1 moves the output all the way to its target, whatever the number of
  features, so the default rates work for 10, 30 or 50 RBFs per input alike;
- a batch of ``n`` samples (one per lane) is applied one sample after another, in lane order, each sample's error
  recomputed on the weights its predecessors left (:mod:`sb3_aac.sarsa_aac.lane_steps`): ``n`` lanes take the steps
  one lane would take on the same samples, so what a sample teaches does not depend on the number of lanes, and no
  linear head's step overshoots its sample's target for any rate in ``(0, 1]``.

The parameters are torch tensors (so SB3's ``state_dict``-based save/load keeps working), but every computation is
numpy on the CPU: the forward pass is :class:`sb3_aac.runtime.forward.BankForward`, the one implementation of the
formulas above, which lives in the numpy-only :mod:`sb3_aac.runtime` so that exported policies run the very same code.
:class:`BankKernel` adds the closed-form update and works on zero-copy views of the CPU parameter tensors, so no
torch op runs per step. ``ApproximatorBank.forward`` runs the same numpy code and returns a tensor.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
import torch as th
from torch import nn

from sb3_aac.common.sizes import check_allocation, is_whole
from sb3_aac.runtime.forward import BankForward, check_rbf_window
from sb3_aac.sarsa_aac.kernels import ForwardPass, NumpyKernel
from sb3_aac.sarsa_aac.lane_steps import linear_steps, mlp_steps

# RBFs farther than this many standard deviations from the input are not computed (0): below exp(-12.5) = 3.7e-6.
DEFAULT_RBF_WINDOW = 5.0


def rbf_layout(n_inputs: int, n_rbf: int, rbf_width: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Evenly spaced Gaussian RBF centres on ``[-1, 1]`` for each scaled input, with widths ``rbf_width * spacing``.

    :return: ``centers`` and ``widths``, each of shape ``(n_inputs, n_rbf)``
    """
    if not (is_whole(n_rbf) and n_rbf >= 1):
        raise ValueError(f"n_rbf must be a whole number >= 1, got {n_rbf!r}")
    if not rbf_width > 0:
        raise ValueError(f"rbf_width must be > 0, got {rbf_width}")
    centers = np.linspace(-1.0, 1.0, n_rbf) if n_rbf > 1 else np.zeros(1)
    spacing = 2.0 / (n_rbf - 1) if n_rbf > 1 else 2.0
    return np.tile(centers, (n_inputs, 1)), np.full((n_inputs, n_rbf), rbf_width * spacing)


class BankCache(NamedTuple):
    """What :meth:`BankKernel.forward` computed and :meth:`BankKernel.update` needs. ``n`` rows."""

    x: np.ndarray  # (n, F) features
    hidden: np.ndarray | None  # (n, A, H) tanh activations, None for a linear head


class NumpyBank(nn.Module):
    """
    What every bank of approximators shares: parameters as float64 torch tensors (for SB3's save/load), and a numpy
    kernel on zero-copy views of them, built once and cached. Subclasses build the kernel and the forward pass.
    """

    # Axis of the outputs (approximators) in each parameter, where it is not 0.
    output_axes: dict[str, int] = {}  # noqa: RUF012
    # Number of approximators ``A``, set by every subclass.
    n_outputs: int

    def __init__(self) -> None:
        super().__init__()
        self._kernel: NumpyKernel[Any] | None = None
        # load_state_dict copies in place, but the kernel's constants derived from the buffers would go stale.
        self.register_load_state_dict_post_hook(  # type: ignore[no-untyped-call]  # untyped in torch
            lambda module, incompatible_keys: module.invalidate_kernel()
        )

    @staticmethod
    def _uniform(shape: tuple[int, ...], bound: float) -> nn.Parameter:
        # Weights are updated by hand (no autograd); float64 keeps many tiny online steps accurate.
        return nn.Parameter(th.empty(shape, dtype=th.float64).uniform_(-bound, bound), requires_grad=False)

    def _make_kernel(self) -> NumpyKernel[Any]:
        """The kernel on zero-copy views of this bank's CPU parameters."""
        raise NotImplementedError

    def _forward_pass(self) -> ForwardPass:
        """The forward pass on CPU copies of this bank's arrays (for parameters stored on another device)."""
        raise NotImplementedError

    def _output_weights(self) -> tuple[th.Tensor, th.Tensor, int]:
        """The output layer's weight, its bias, and the axis of the outputs in the weight."""
        raise NotImplementedError

    def arrays(self) -> dict[str, np.ndarray]:
        """
        The buffers and parameters by name (the names of the forward pass and of the export format) as numpy
        arrays: zero-copy views of CPU storage, copies from another device.
        """
        return {name: t.detach().cpu().numpy() for name, t in (*self.named_buffers(), *self.named_parameters())}

    def evaluate(self, obs: np.ndarray) -> np.ndarray:
        """Every approximator's output ``(n, A)`` for ``obs`` ``(n, D)``, with numpy (on CPU copies if stored elsewhere)."""
        bank = self.numpy_kernel() if self.obs_mid.device.type == "cpu" else self._forward_pass()
        return bank.outputs(bank.features(obs))[0]

    def forward(self, obs: th.Tensor) -> th.Tensor:
        """:meth:`evaluate` for a tensor ``(n, D)``: a float64 tensor ``(n, A)`` on ``obs``'s device (no autograd)."""
        return th.as_tensor(self.evaluate(obs.detach().cpu().numpy()), device=obs.device)

    def numpy_kernel(self) -> NumpyKernel[Any]:
        """
        Numpy evaluation and update on zero-copy views of the (CPU) parameters, built once and cached.

        The cache is dropped on device/dtype moves and after ``load_state_dict``; after assigning a tensor's
        ``.data`` directly, call :meth:`invalidate_kernel`.
        """
        if self._kernel is None:
            self._kernel = self._make_kernel()
        return self._kernel

    def invalidate_kernel(self) -> None:
        self._kernel = None

    def scale_outputs(self, outputs: list[int], factor: float) -> None:
        """Multiply the given approximators' outputs by ``factor`` (their output layer's weights and bias)."""
        weight, bias, axis = self._output_weights()
        with th.no_grad():
            th.movedim(weight, axis, 0)[outputs] *= factor  # a view: writes into the weight's storage
            bias[outputs] *= factor

    def finite_outputs(self) -> np.ndarray:
        """``(A,)`` bool: whether every parameter of each approximator is finite."""
        finite = np.ones(self.n_outputs, dtype=bool)
        for name, p in self.named_parameters():
            array = np.moveaxis(p.detach().cpu().numpy(), self.output_axes.get(name, 0), 0)
            finite &= np.isfinite(array.reshape(self.n_outputs, -1)).all(1)
        return finite

    def __getstate__(self) -> dict[str, Any]:
        # A copy (deepcopy, pickle) gets new storage, so it must not inherit views of ours.
        return {**self.__dict__, "_kernel": None}  # not super(): object.__getstate__ is Python 3.11+

    def _apply(self, fn, recurse=True):  # type: ignore[no-untyped-def]
        # Device and dtype moves replace the storage the numpy views point to.
        self._kernel = None
        return super()._apply(fn, recurse)  # type: ignore[no-untyped-call]  # untyped in torch


class ApproximatorBank(NumpyBank):
    """
    ``n_outputs`` independent function approximators of one observation vector (see the module docstring).

    :param low: ``(D,)`` lower bounds of the observation used for scaling and RBF placement
    :param high: ``(D,)`` upper bounds. An input with an infinite bound is not scaled (only allowed without RBFs)
    :param n_outputs: Number of approximators ``A``
    :param n_rbf: Gaussian RBFs per input, or ``None`` for the scaled inputs themselves
    :param rbf_width: RBF standard deviation in units of the centre spacing
    :param hidden_units: Hidden tanh units of each approximator, or ``None`` for a linear head
    :param rbf_window: Only the RBFs within this many standard deviations of the input are computed, the others
        are 0 (:class:`~sb3_aac.runtime.forward.BankForward`); ``None`` computes all
    """

    def __init__(
        self,
        low: np.ndarray,
        high: np.ndarray,
        n_outputs: int,
        n_rbf: int | None = None,
        rbf_width: float = 1.0,
        hidden_units: int | None = None,
        rbf_window: float | None = None,
    ):
        super().__init__()
        low, high = np.asarray(low, dtype=np.float64).ravel(), np.asarray(high, dtype=np.float64).ravel()
        if low.shape != high.shape or not np.all(low < high):
            raise ValueError(f"Need low < high elementwise with equal shapes, got low={low}, high={high}")
        finite = np.isfinite(low) & np.isfinite(high)
        if n_rbf is not None and not finite.all():
            raise ValueError(
                f"RBF features need finite bounds for every input, got low={low}, high={high}; "
                "pass finite bounds for the RBF placement (policy_kwargs obs_bounds=(low, high))"
            )
        if hidden_units is not None and not (is_whole(hidden_units) and hidden_units >= 1):
            raise ValueError(f"hidden_units must be a whole number >= 1 or None, got {hidden_units!r}")
        n_weights = n_outputs * len(low) * (n_rbf or 1) * (hidden_units or 1)
        check_allocation(f"The approximators (n_rbf={n_rbf}, hidden_units={hidden_units})", n_weights)
        self.n_inputs, self.n_outputs = len(low), n_outputs
        self.n_rbf, self.hidden_units = n_rbf, hidden_units
        check_rbf_window(rbf_window)
        self.rbf_window = rbf_window if n_rbf is not None else None
        low, high = np.where(finite, low, -1.0), np.where(finite, high, 1.0)  # unscaled: mid 0, half-range 1
        self.register_buffer("obs_mid", th.as_tensor((high + low) / 2))
        self.register_buffer("obs_half", th.as_tensor((high - low) / 2))
        if n_rbf is not None:
            centers, widths = rbf_layout(self.n_inputs, n_rbf, rbf_width)
            self.register_buffer("rbf_centers", th.as_tensor(centers))
            self.register_buffer("rbf_widths", th.as_tensor(widths))
        self.n_features = self.n_inputs * (n_rbf or 1)
        f, a = self.n_features, n_outputs
        # Fan-in scaled uniform initialisation, like torch.nn.Linear (the paper only says "at random").
        if hidden_units is None:
            self.weight = self._uniform((a, f), 1 / math.sqrt(f))
            self.bias = self._uniform((a,), 1 / math.sqrt(f))
        else:
            h = hidden_units
            self.weight1 = self._uniform((a, h, f), 1 / math.sqrt(f))
            self.bias1 = self._uniform((a, h), 1 / math.sqrt(f))
            self.weight2 = self._uniform((a, h), 1 / math.sqrt(h))
            self.bias2 = self._uniform((a,), 1 / math.sqrt(h))

    def _make_kernel(self) -> BankKernel:
        return BankKernel(self)

    def _forward_pass(self) -> BankForward:
        return BankForward(**self.arrays(), rbf_window=self.rbf_window)

    def _output_weights(self) -> tuple[th.Tensor, th.Tensor, int]:
        return (self.weight, self.bias, 0) if self.hidden_units is None else (self.weight2, self.bias2, 0)


class BankKernel(BankForward):
    """
    The numpy forward pass (:class:`~sb3_aac.runtime.forward.BankForward`) of an :class:`ApproximatorBank`, with the cache
    and the closed-form update of training.

    It holds views of the bank's CPU parameters, so updates write straight into the module, and constants
    derived from its buffers (input scaling, RBF centres and widths).
    """

    def __init__(self, bank: ApproximatorBank):
        if bank.obs_mid.device.type != "cpu":
            raise ValueError(f"The numpy kernel needs CPU tensors, the bank is on {bank.obs_mid.device}")
        super().__init__(**bank.arrays(), rbf_window=bank.rbf_window)

    def forward(self, obs: np.ndarray) -> tuple[np.ndarray, BankCache]:
        """``obs``: ``(n, D)`` -> outputs ``(n, A)`` and the cache for :meth:`update`."""
        x = self.features(obs)
        out, hidden = self.outputs(x)
        return out, BankCache(x, hidden)

    def update(self, cache: BankCache, err: np.ndarray, lr: np.ndarray, hidden_gain: np.ndarray | None = None) -> None:
        """
        A gradient step on ``0.5 * err**2`` for each sample in turn, in place (see the module docstring and
        :mod:`sb3_aac.sarsa_aac.lane_steps`).

        :param cache: from :meth:`forward` on the same weights; its first ``n`` rows are used
        :param err: ``(n, A)`` target minus output; 0 leaves an approximator unchanged for that sample
        :param lr: ``(A,)`` learning rate of each approximator
        :param hidden_gain: ``(A,)`` factor on each approximator's hidden-layer step (MLP heads only; None: 1).
            An approximator whose outputs are in units of ``sigma`` takes ``1 / sigma**2`` here, so that its
            hidden layer moves as if its targets were divided by ``sigma`` (see :class:`sb3_aac.SarsaAAC`).
        """
        n = len(err)
        x, err = np.ascontiguousarray(cache.x[:n]), np.ascontiguousarray(err, dtype=np.float64)
        if not self.mlp:
            linear_steps(self.w, self.b, x, err, lr)
            return
        gain = np.ones(len(lr)) if hidden_gain is None else hidden_gain
        mlp_steps(self.w1, self.b1, self.w2, self.b2, x, err, lr, gain)
