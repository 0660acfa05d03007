"""The timing the speed scripts share: best-of-repeats microseconds per call (the measurement ``sb3-aac bench``
prints, :func:`sb3_aac.common.timing.microseconds`), the median of single calls, training throughput after a warm-up,
and the load average printed next to every figure (single runs on a shared machine: repeat them)."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from typing import Any

from sb3_aac.common.timing import load_average, microseconds

__all__ = ["load_average", "median_microseconds", "microseconds", "steps_per_second"]


def median_microseconds(fn: Callable[[], Any], calls: int) -> float:
    """Median wall time of ``calls`` single calls of ``fn``, in microseconds (no warm-up call)."""
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times) * 1e6


def steps_per_second(model: Any, steps: int, warmup: int, repeats: int = 1) -> float:
    """Env steps per second of ``model.learn(steps)`` after ``model.learn(warmup)`` (compiled kernels, first
    allocations, past ``learning_starts``), the timesteps counted on; the best of ``repeats`` timings."""
    model.learn(warmup)
    best = 0.0
    for _ in range(repeats):
        start = time.perf_counter()
        model.learn(steps, reset_num_timesteps=False)
        best = max(best, steps / (time.perf_counter() - start))
    return best
