"""The generator of an algorithm's own random draws (exploration, minibatches), seeded as SB3's draws are."""

from __future__ import annotations

import numpy as np


def algorithm_generator(seed: int | None) -> np.random.Generator:
    """
    A generator from ``seed``; with ``seed=None``, from one draw of numpy's global state, so that
    ``stable_baselines3.common.utils.set_random_seed(7)`` before the constructor repeats a run, as it does for SB3's
    algorithms (which draw from the global state) and HybridPPO.
    """
    return np.random.default_rng(seed if seed is not None else int(np.random.randint(0, 2**63 - 1, dtype=np.int64)))
