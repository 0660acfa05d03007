"""What every cell records about where it ran: package versions (with the git commit), the machine, the load."""

from __future__ import annotations

import contextlib
import os
import platform
from pathlib import Path
from typing import Any

import numpy as np
import torch as th

from benchmarks.provenance import git_state


def versions() -> dict[str, str]:
    import gymnasium
    import numba
    import stable_baselines3

    import sb3_aac

    return {
        "python": platform.python_version(),
        "sb3_aac": sb3_aac.__version__,
        "git_commit": git_state().label,  # of the checkout this process imports (a Ray worker's own)
        "stable_baselines3": stable_baselines3.__version__,
        "torch": th.__version__,
        "numpy": np.__version__,
        "gymnasium": gymnasium.__version__,
        "numba": numba.__version__,
    }


def machine() -> dict[str, Any]:
    cpu = platform.processor() or platform.machine()
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    return {"cpu": cpu, "cores": os.cpu_count(), "platform": platform.platform(), "torch_threads": th.get_num_threads()}


def loadavg() -> float | None:
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return None
