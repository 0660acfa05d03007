"""
What SarsaAAC's training asks of a policy family's numerical core, as typing protocols (no code).

A *kernel* evaluates the ``A`` outputs of a SarsaAAC policy (column layout in
:class:`~sb3_aac.sarsa_aac.policies.SarsaAACPolicy`) for a batch of observations and moves them toward targets in
place, with numpy arrays in and out. :class:`~sb3_aac.sarsa_aac.approximators.BankKernel` (dense banks) and
:class:`~sb3_aac.sarsa_aac.tile_coding.TileKernel` (tile coding) implement :class:`NumpyKernel`; a family whose
core is not a numpy bank (a torch network) implements :class:`Kernel` only.
"""

from __future__ import annotations

from typing import Protocol, TypeVar

import numpy as np

CacheT = TypeVar("CacheT")


class Kernel(Protocol[CacheT]):
    """The training contract: a forward pass that keeps what the update needs, and the update."""

    def forward(self, obs: np.ndarray, /) -> tuple[np.ndarray, CacheT]:
        """
        Outputs ``(n, A)`` float64 of observations ``(n, D)`` (flattened, float64, finite), and a cache of what
        :meth:`update` needs; the cache's first ``m`` rows belong to the first ``m`` observations.
        """
        ...

    def update(self, cache: CacheT, err: np.ndarray, lr: np.ndarray, hidden_gain: np.ndarray | None = None, /) -> None:
        """
        One step of every output toward its target, in place, from the cache of a :meth:`forward` on the same weights.

        :param cache: the cache of :meth:`forward`; only its first ``n = len(err)`` rows are used
        :param err: ``(n, A)`` target minus output; a 0 leaves that output unchanged for that sample
        :param lr: ``(A,)`` learning rate of each output, in ``(0, 1]``: normalised, so that for one sample a rate of
            1 moves a linear output onto its target; a numpy bank applies a batch's samples one after another
            (:mod:`sb3_aac.sarsa_aac.lane_steps`), so the lane count does not change what a sample teaches
        :param hidden_gain: ``(A,)`` factor on the step of each output's hidden layers (None: 1), the
            ``1 / return_scale**2`` of the Q and V outputs (see :class:`~sb3_aac.SarsaAAC`); ignored by a core
            without hidden layers
        """
        ...


class ForwardPass(Protocol):
    """A numpy bank's forward pass in two stages (:class:`~sb3_aac.runtime.forward.BankForward`, ``TileForward``)."""

    def features(self, obs: np.ndarray, /) -> np.ndarray:
        """The features of observations ``(n, D)``: one row per observation."""
        ...

    def outputs(self, features: np.ndarray, /) -> tuple[np.ndarray, np.ndarray | None]:
        """Outputs ``(n, A)`` of :meth:`features`' rows, and the hidden activations (None for a linear head)."""
        ...


class NumpyKernel(Kernel[CacheT], ForwardPass, Protocol[CacheT]):
    """A numpy bank's kernel: the training contract on the bank's two-stage forward pass."""
