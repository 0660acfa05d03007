"""
The pieces of a gradient step that the torch learners share, on lists of tensors with one ``foreach`` kernel per
list instead of one Python call per tensor: Polyak averaging and gradient-norm clipping (element by element exactly
what SB3's ``polyak_update`` and torch's ``clip_grad_norm_`` compute, so the same bits), and optimizers built with
torch's fused implementation where it has one (the same update rounded differently, see :func:`make_optimizer`).
"""

from __future__ import annotations

import inspect
from collections.abc import Iterable, Sequence
from typing import Any

import torch as th


def polyak_update(params: Sequence[th.Tensor], target_params: Sequence[th.Tensor], tau: float) -> None:
    """``target <- (1 - tau) * target + tau * param`` in place, for matching lists (SB3's ``polyak_update``)."""
    with th.no_grad():
        th._foreach_mul_(list(target_params), 1.0 - tau)
        th._foreach_add_(list(target_params), list(params), alpha=tau)


def clip_grad_norm(grads: Sequence[th.Tensor], max_norm: float) -> th.Tensor:
    """
    Scale ``grads`` in place by ``min(max_norm / (norm + 1e-6), 1)``, ``norm`` their joint 2-norm, which is returned
    (torch's ``clip_grad_norm_`` on the gradients themselves).
    """
    with th.no_grad():
        total: th.Tensor = th.linalg.vector_norm(th.stack(th._foreach_norm(list(grads), 2.0)), 2.0)
        th._foreach_mul_(list(grads), th.clamp(max_norm / (total + 1e-6), max=1.0))
    return total


def set_grads(params: Sequence[th.Tensor], grads: Sequence[th.Tensor]) -> None:
    """Make ``grads`` the ``.grad`` of ``params`` (as ``zero_grad(set_to_none=True)`` then ``backward`` would)."""
    for param, grad in zip(params, grads, strict=True):
        param.grad = grad


def make_optimizer(
    optimizer_class: type[th.optim.Optimizer], params: Iterable[th.Tensor], lr: float, kwargs: dict[str, Any]
) -> th.optim.Optimizer:
    """
    ``optimizer_class(params, lr=lr, **kwargs)``, with torch's ``fused`` implementation (one kernel per tensor for
    the whole update; Adam, AdamW, SGD) where the class has one, else ``foreach``, unless ``kwargs`` choose
    (``fused`` or ``foreach``). torch picks the per-tensor loop on the CPU by default, several times slower on small
    networks. ``foreach`` computes the loop's numbers exactly; ``fused`` the same update with its own rounding, so a
    seeded run differs in the last bits of the weights from the first step on (pass ``foreach=True`` for the loop's
    numbers).
    """
    options = dict(kwargs)
    accepted = inspect.signature(optimizer_class).parameters
    if not {"foreach", "fused"} & set(options):
        if "fused" in accepted:
            options["fused"] = True
        elif "foreach" in accepted:
            options["foreach"] = True
    # SB3's optimizer_class is typed as the Optimizer base, whose constructor takes no lr (as in SB3's own policies).
    return optimizer_class(params, lr=lr, **options)  # type: ignore[call-arg]
