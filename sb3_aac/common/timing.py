"""How the speed figures are measured: best-of-repeats microseconds per call, and the load average printed next to
every figure (single runs on a shared machine: repeat them)."""

from __future__ import annotations

import os
import timeit
from collections.abc import Callable
from typing import Any


def load_average() -> float:
    """The one-minute load average (NaN where the platform has none)."""
    return os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")


def microseconds(fn: Callable[[], Any], calls: int, repeats: int) -> float:
    """Best of ``repeats`` runs of ``calls`` calls, per call, after one warm-up call (numba compiles there)."""
    fn()
    return min(timeit.repeat(fn, number=calls, repeat=repeats)) / calls * 1e6
