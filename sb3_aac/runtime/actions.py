"""
Action layouts and parameter scaling, shared by training (:class:`sb3_aac.common.spaces.ParameterizedActionSpec`)
and the exported policy (:class:`~sb3_aac.runtime.policy.RuntimePolicy`): how the K action types' parameters,
scaled to ``[-1, 1]``, become env units, and how one decision becomes an env action in each layout.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

LAYOUTS = ("nested", "flat", "shared", "oneof")


def unscale(low: np.ndarray, high: np.ndarray, params_scaled: np.ndarray) -> np.ndarray:
    """
    Map parameters from ``[-1, 1]`` to ``[low, high]`` and clip them inside the bounds (float64, ``(..., n_params)``).

    ``-1`` and ``1`` give ``low`` and ``high`` exactly, whatever the dtype: ``mid + half * p`` can miss a float64
    bound by one ulp, so the interpolation weights both bounds instead. Training
    (:meth:`sb3_aac.common.spaces.ParameterizedActionSpec.unscale`) and :meth:`RuntimePolicy.unscale` call this.
    """
    weight = 0.5 * np.asarray(params_scaled, dtype=np.float64)
    value = low * (0.5 - weight) + high * (0.5 + weight)
    # minimum/maximum: np.clip costs several times more on small arrays.
    clipped: np.ndarray = np.minimum(np.maximum(value, low), high)
    return clipped


def unscale_value(scaled: float, low: float, high: float) -> float:
    """
    :func:`unscale` of one parameter in Python floats: the same IEEE operations, cheaper than numpy on a few values.
    :meth:`RuntimePolicy.act <sb3_aac.runtime.policy.RuntimePolicy.act>` calls it, and its numba kernel compiles it.
    """
    weight = 0.5 * scaled
    return min(max(low * (0.5 - weight) + high * (0.5 + weight), low), high)


def env_action(
    layout: str, start: int, k: int, n_types: int, box: Callable[[int, np.ndarray], np.ndarray], params: np.ndarray
) -> tuple[Any, ...]:
    """
    One env action of 0-based type ``k`` in action ``layout`` (see ``LAYOUTS``), as ``model.predict`` returns it.

    :param start: the ``Discrete``'s start, added to ``k`` (a ``"oneof"`` action numbers its types from 0)
    :param box: ``box(j, params)`` is type ``j``'s part of the parameter vector ``params`` in its Box's shape and dtype
    """
    if layout == "oneof":
        return (k, box(k, params))
    if layout == "shared":
        return (start + k, box(k, params))
    values = tuple(box(j, params) for j in range(n_types))
    return (start + k, values) if layout == "nested" else (start + k, *values)
