"""
The recent transitions SarsaAAC replays (its ``replay_ratio``; not in Uc-Cetina 2013).

A ring buffer of the last ``size`` transitions ``(s, k, x, r, discount, s', k')`` of all lanes, where ``s'`` is the
observation the step's targets bootstrap from (the terminal observation of a time-limit truncation), ``k'`` the type
chosen there and ``discount`` is ``gamma``, or 0 where the episode terminated. Replaying one is a one-step update on
the current weights, so a small buffer of recent samples adds updates without the staleness of a large one.
"""

from __future__ import annotations

import numpy as np

# A batch of transitions: (obs, types, params, rewards, discounts, next_obs, next_types), with one row each.
Transitions = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


class RecentTransitions:
    """
    The last ``size`` transitions, oldest overwritten first.

    :param size: how many transitions it holds (>= 1)
    :param obs_dim: the length of a flattened observation
    :param n_params: the number of scalar (scaled) parameters of an action
    """

    def __init__(self, size: int, obs_dim: int, n_params: int):
        self.size = size
        self.obs = np.zeros((size, obs_dim))
        self.next_obs = np.zeros((size, obs_dim))
        self.params = np.zeros((size, n_params))
        self.types = np.zeros(size, dtype=np.int64)
        self.next_types = np.zeros(size, dtype=np.int64)
        self.rewards = np.zeros(size)
        self.discounts = np.zeros(size)
        self.count = 0  # transitions added so far; the next goes to row count % size

    def __len__(self) -> int:
        """How many transitions it holds: ``min(count, size)``."""
        return min(self.count, self.size)

    def add(
        self,
        obs: np.ndarray,
        types: np.ndarray,
        params: np.ndarray,
        rewards: np.ndarray,
        discounts: np.ndarray,
        next_obs: np.ndarray,
        next_types: np.ndarray,
    ) -> None:
        """Append a batch of ``n`` transitions (arrays with ``n`` rows); with ``n > size`` only the last ``size`` stay."""
        n = len(types)
        rows = (self.count + np.arange(n)) % self.size
        for store, values in (
            (self.obs, obs),
            (self.types, types),
            (self.params, params),
            (self.rewards, rewards),
            (self.discounts, discounts),
            (self.next_obs, next_obs),
            (self.next_types, next_types),
        ):
            store[rows[-self.size :]] = values[-self.size :]
        self.count += n

    def sample(self, n: int, rng: np.random.Generator) -> Transitions:
        """``n`` transitions drawn uniformly with replacement from those held (it must hold one), as copies."""
        rows = rng.integers(len(self), size=n)
        return (
            self.obs[rows],
            self.types[rows],
            self.params[rows],
            self.rewards[rows],
            self.discounts[rows],
            self.next_obs[rows],
            self.next_types[rows],
        )
