"""Checking a parameterized action before an environment acts on it, and float32 Boxes that hold float64 values.

Every env of this package validates its whole action first and raises ``ValueError`` (saying what was wrong and what
is allowed) before any state or random number generator changes, so a rejected action changes nothing.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium import spaces


def action_type(value: Any, n_types: int) -> int:
    """``value`` as an action type in ``0..n_types-1``: a Python or numpy integer or an integral real number (not a bool).

    :raises ValueError: for anything else (None, a bool, a string, 1.5, -1, ``n_types``, NaN, ...).
    """
    allowed = f"an integer in 0..{n_types - 1}"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"The action type must be {allowed}, got {value!r:.100}")
    if not (float(value).is_integer() and 0 <= value < n_types):
        raise ValueError(f"The action type must be {allowed}, got {value!r:.100}")
    return int(value)


def parameter_vector(value: Any, size: int, what: str) -> np.ndarray:
    """``value`` as a finite float64 vector of ``size`` entries (any real array-like of that many elements).

    :raises ValueError: if it is not real, has another number of elements, or holds NaN or an infinity.
    """
    try:
        array = np.asarray(value)
        if array.dtype.kind not in "biuf":
            raise TypeError(array.dtype)
        vector = array.astype(np.float64).ravel()
    except (TypeError, ValueError) as error:
        raise ValueError(f"{what} must be a real vector of {size} value(s), got {value!r:.200}") from error
    if vector.size != size:
        raise ValueError(f"{what} must hold {size} value(s), got {vector.size} in {value!r:.200}")
    if not np.isfinite(vector).all():
        raise ValueError(f"{what} must be finite, got {value!r:.200}")
    return vector


def _split(action: Any, layout: str) -> tuple[Any, Any]:
    try:
        action_type_value, parameters = action
    except (TypeError, ValueError) as error:
        raise ValueError(f"An action must be a pair (action_type, {layout}), got {action!r:.200}") from error
    return action_type_value, parameters


def parse_nested(action: Any, sizes: Sequence[int]) -> tuple[int, tuple[np.ndarray, ...]]:
    """Check a nested action ``(k, (p_0, ..., p_{K-1}))``; ``sizes[j]`` is type ``j``'s number of parameters.

    :return: ``k`` and every type's parameters as float64 vectors (all are checked, only ``p_k`` is used).
    """
    layout = "(" + ", ".join(f"p_{j} ({size},)" for j, size in enumerate(sizes)) + ")"
    value, parameters = _split(action, layout)
    k = action_type(value, len(sizes))
    if isinstance(parameters, (str, bytes)) or not isinstance(parameters, Sequence) or len(parameters) != len(sizes):
        raise ValueError(f"The parameters of an action must be a tuple {layout}, got {parameters!r:.200}")
    return k, tuple(parameter_vector(p, size, f"p_{j}") for j, (p, size) in enumerate(zip(parameters, sizes, strict=True)))


def parse_shared(action: Any, n_types: int, size: int) -> tuple[int, np.ndarray]:
    """Check a shared-parameter action ``(k, p)`` with ``p`` of ``size`` entries (each type reads its own ones)."""
    value, parameters = _split(action, f"parameters ({size},)")
    return action_type(value, n_types), parameter_vector(parameters, size, "The parameters")


def float32_box(low: Sequence[float] | np.ndarray, high: Sequence[float] | np.ndarray) -> spaces.Box:
    """A float32 Box whose bounds are ``low``/``high`` rounded outwards, so it holds every float64 value between them
    after the cast to float32 (rounding to nearest could land a value just inside ``high`` one ulp above the bound)."""
    low64, high64 = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
    low32, high32 = low64.astype(np.float32), high64.astype(np.float32)
    low32 = np.where(low32 > low64, np.nextafter(low32, np.float32(-np.inf)), low32)
    high32 = np.where(high32 < high64, np.nextafter(high32, np.float32(np.inf)), high32)
    return spaces.Box(low32, high32, dtype=np.float32)
