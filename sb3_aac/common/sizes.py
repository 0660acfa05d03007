"""
Limits on what a constructor allocates, so that a typo in a size (``hidden_units=100000000``, ``buffer_size=1e10``)
is a ``ValueError`` naming the size at once, not a ``MemoryError`` after minutes or a machine brought down.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any

MAX_ALLOCATION_BYTES = 8 * 2**30  # 8 GiB: far above any model or buffer this library's tasks need
MAX_LAYER_WIDTH = 65_536  # units in one hidden layer


def is_whole(value: Any) -> bool:
    """Whether ``value`` is an integer (Python or numpy), not a bool."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def check_allocation(what: str, n_values: int, itemsize: int = 8) -> None:
    """
    :raises ValueError: if ``n_values`` values of ``itemsize`` bytes exceed :data:`MAX_ALLOCATION_BYTES`, naming
        ``what`` (e.g. ``"TilePolicy's weight table (n_features x n_outputs)"``) and the size
    """
    size = n_values * itemsize
    if size > MAX_ALLOCATION_BYTES:
        raise ValueError(
            f"{what} would take {format_bytes(size)} ({n_values:,} values), more than the limit of "
            f"{format_bytes(MAX_ALLOCATION_BYTES)}; choose smaller sizes"
        )


def check_layer_sizes(name: str, sizes: Sequence[Any]) -> list[int]:
    """
    ``sizes`` (hidden layer widths) as ints.

    :raises ValueError: unless every one is a whole number in ``1 .. MAX_LAYER_WIDTH``
    """
    if isinstance(sizes, (str, bytes)) or not isinstance(sizes, Sequence):
        raise ValueError(f"{name} must be a list of hidden layer widths, e.g. [64, 64], got {sizes!r}")
    if not all(is_whole(s) and 1 <= int(s) <= MAX_LAYER_WIDTH for s in sizes):
        raise ValueError(f"{name} must hold whole numbers in 1 .. {MAX_LAYER_WIDTH:,} (hidden layer widths), got {sizes!r}")
    return [int(s) for s in sizes]


def format_bytes(size: float) -> str:
    """``size`` bytes in binary units, e.g. ``"8.0 GiB"``."""
    units = ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB")
    exponent = min(int(math.log(max(size, 1), 1024)), len(units) - 1)
    return f"{size / 1024**exponent:.1f} {units[exponent]}"
