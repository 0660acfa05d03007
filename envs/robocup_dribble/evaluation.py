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

from robocup_dribble import physics
from robocup_dribble.vec_env import DribbleVecEnv
from robocup_dribble.params import make_profile, without_noise
from robocup_dribble.player_types import draw_type_table


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
    :param env_kwargs: further :class:`robocup_dribble.vec_env.DribbleVecEnv` arguments (e.g. ``episodes_per_type_set``).
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


def reliability_test(
    policy: Any, n_players: int = 10_000, profile: str = "v19", seed: int = 0, **kwargs: Any
) -> DribbleReport:
    """The paper's reliability test: ``n_players`` freshly generated players each dribble once from the centre.

    Every episode draws a new set of player types and plays one type of it (``episodes_per_type_set=1``).
    """
    return evaluate_dribbling(policy, n_players, profile, seed, episodes_per_type_set=1, **kwargs)


def running_ceiling(profile: str = "v19", n_players: int = 1000, cycles: int = 35, seed: int = 0) -> np.ndarray:
    """The physical ceiling: metres each of ``n_players`` fresh players covers in ``cycles`` full-power dashes along
    +x from rest, with no ball and no noise (what no dribbler can beat in an episode of that many actions)."""
    server_profile = without_noise(make_profile(profile))
    rng = np.random.default_rng(seed)
    n_sets = -(-n_players // server_profile.player.player_types)
    types = draw_type_table(server_profile, n_sets, lambda low, high, size: low + (high - low) * rng.random(size))
    types = types.reshape(-1, physics.TYPE_SIZE)[:n_players]
    state = physics.new_state(len(types))
    physics.recover(state, types, server_profile)
    state[:, physics.B_Y] = 1e3  # the ball is far away
    commands = np.zeros((len(types), physics.COMMAND_SIZE))
    commands[:, physics.C_KIND], commands[:, physics.C_POWER] = physics.CMD_DASH, server_profile.server.max_dash_power
    uniforms = np.full((len(types), physics.N_UNIFORMS), 0.5)
    constants = physics.profile_constants(server_profile)
    for _ in range(cycles):
        physics.step(state, types, commands, uniforms, constants)
    distances: np.ndarray = state[:, physics.P_X].copy()
    return distances
