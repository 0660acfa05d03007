"""Measure a dribbling policy: greedy metres on fresh heterogeneous players, and the paper's reliability test.

Any policy with an SB3-style ``predict(obs, deterministic=True) -> (actions, state)`` works (a trained model, or
:class:`robocup_dribble.dribbler.HandCodedDribbler`). The episodes run in a :class:`DribbleVecEnv`; each lane plays
the same number of episodes, so short episodes are not over-represented (counting the first N episodes to finish
across lanes would favour them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from robocup_dribble.env import DribbleVecEnv


@dataclass(frozen=True)
class DribbleReport:
    """Per-episode results of an evaluation."""

    distances: np.ndarray  # metres dribbled along +x before the ball was lost or the episode ended
    ball_lost: np.ndarray  # bool: the episode ended by losing the ball (not by the action limit)

    @property
    def mean_distance(self) -> float:
        return float(np.mean(self.distances))

    @property
    def loss_rate(self) -> float:
        return float(np.mean(self.ball_lost))

    def share_reaching(self, metres: float) -> float:
        """The share of episodes that dribbled at least ``metres``."""
        return float(np.mean(self.distances >= metres))

    def summary(self) -> str:
        return (
            f"{len(self.distances)} episodes: mean {self.mean_distance:.2f} m, median {np.median(self.distances):.2f} m, "
            f"max {np.max(self.distances):.2f} m, >= 20 m {100 * self.share_reaching(20):.1f} %, "
            f"ball lost {100 * self.loss_rate:.1f} %"
        )


def evaluate_dribbling(
    policy: Any,
    n_episodes: int = 1000,
    profile: str = "v19",
    seed: int = 0,
    n_lanes: int = 100,
    deterministic: bool = True,
    **env_kwargs: Any,
) -> DribbleReport:
    """Run ``n_episodes`` episodes of ``policy`` on fresh heterogeneous players.

    :param policy: an object with ``predict(obs, deterministic=...)`` returning ``(actions, state)``.
    :param n_episodes: episodes to run (spread evenly over the lanes; rounded up to a multiple of their number).
    :param profile: the env's server profile (``"v19"``, ``"v11"``).
    :param seed: seed of the evaluation env (player types, starts and noise).
    :param n_lanes: episodes run side by side.
    :param deterministic: passed to ``predict`` (greedy actions by default).
    :param env_kwargs: further :class:`robocup_dribble.env.DribbleVecEnv` arguments (e.g. ``episodes_per_type_set``).
    """
    if n_episodes < 1 or n_lanes < 1:
        raise ValueError(f"n_episodes and n_lanes must be >= 1, got {n_episodes} and {n_lanes}")
    n_lanes = min(n_lanes, n_episodes)
    per_lane = -(-n_episodes // n_lanes)
    env = DribbleVecEnv(n_lanes, profile=profile, **env_kwargs)
    env.seed(seed)
    obs = env.reset()
    played = np.zeros(n_lanes, dtype=np.int64)
    distances, lost = [], []
    while played.min() < per_lane:
        actions, _ = policy.predict(obs, deterministic=deterministic)
        obs, _, dones, infos = env.step(actions)
        for lane in np.flatnonzero(dones):
            if played[lane] < per_lane:
                distances.append(infos[lane]["distance"])
                lost.append(infos[lane]["ball_lost"])
            played[lane] += 1
    env.close()
    return DribbleReport(np.array(distances), np.array(lost, dtype=bool))


def reliability_test(policy: Any, n_players: int = 10_000, profile: str = "v19", seed: int = 0, **kwargs: Any) -> DribbleReport:
    """The paper's reliability test: ``n_players`` freshly generated players each dribble once from the centre.

    Every episode draws a new set of player types and plays one type of it (``episodes_per_type_set=1``).
    """
    return evaluate_dribbling(policy, n_players, profile, seed, episodes_per_type_set=1, **kwargs)
