"""SarsaAAC's exploratory choice of action types: epsilon-greedy or Boltzmann over the types' values."""

from __future__ import annotations

import numpy as np

TYPE_EXPLORATIONS = ("epsilon_greedy", "boltzmann")


def select_types(q: np.ndarray, rate: float, mode: str, rng: np.random.Generator) -> np.ndarray:
    """
    Exploratory choice of action types.

    :param q: ``(n, K)`` action-type values
    :param rate: ``epsilon`` (probability of a uniformly random type) for ``"epsilon_greedy"``, or the softmax
        temperature (in units of Q) for ``"boltzmann"``; 0 is greedy
    :param mode: ``"epsilon_greedy"`` or ``"boltzmann"``
    :param rng: random generator
    :return: ``(n,)`` chosen types
    """
    k: np.ndarray
    if rate <= 0:
        k = q.argmax(1)
        return k
    if mode == "epsilon_greedy":
        k = q.argmax(1)
        explore = rng.random(len(q)) < rate
        if explore.any():
            k[explore] = rng.integers(q.shape[1], size=int(explore.sum()))
        return k
    weights = np.exp((q - q.max(1, keepdims=True)) / rate)
    cumulative = weights.cumsum(1)
    u = rng.random(len(q)) * cumulative[:, -1]
    k = np.minimum((cumulative < u[:, None]).sum(1), q.shape[1] - 1)
    return k
