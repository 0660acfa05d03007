"""Greedy evaluation of a Half Field Offense policy as the papers report it: P(goal) and mean steps to goal over a
fixed set of trials (:func:`evaluate_offense`).

Trial ``j`` of a seed is lane ``j`` of :class:`half_field_offense.lanes.HFOLanes` seeded with it: its start and
every cycle's noise depend only on the seed and ``j`` (all lanes step every cycle until the last trial ends;
a finished lane keeps stepping unrecorded), so two policies evaluated on one seed play paired trials.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from half_field_offense import actions, referee
from half_field_offense.env import PROFILE, configure
from half_field_offense.lanes import HFOLanes
from robocup_dribble.params import ServerProfile
from robocup_dribble.vec_env import parse_actions


@dataclass(frozen=True)
class OffenseReport:
    """Per-trial results of an evaluation (row ``j``: trial ``j``)."""

    status: np.ndarray  # (n,) int64 referee.STATUS_NAMES codes
    lengths: np.ndarray  # (n,) int64 cycles
    returns: np.ndarray  # (n,) float64 undiscounted returns

    @property
    def goals(self) -> np.ndarray:
        """``(n,)`` bool: the trial ended in a goal."""
        goals: np.ndarray = self.status == referee.GOAL
        return goals

    @property
    def p_goal(self) -> float:
        """The share of trials that ended in a goal (HFO's "scoring percentage" as a fraction)."""
        return float(self.goals.mean())

    @property
    def steps_to_goal(self) -> float:
        """The mean cycles of the trials that ended in a goal (NaN without one): the papers' "avg. steps to goal"."""
        return float(self.lengths[self.goals].mean()) if self.goals.any() else float("nan")

    def counts(self) -> dict[str, int]:
        """Trials by final status name."""
        return {name: int((self.status == code).sum()) for code, name in enumerate(referee.STATUS_NAMES) if code}

    def summary(self) -> str:
        """One line: P(goal), steps to goal, mean return and the other endings."""
        return (
            f"P(goal) {self.p_goal:.3f}, {self.steps_to_goal:.1f} steps to goal, mean return {self.returns.mean():.2f} "
            f"over {len(self.status)} trials {self.counts()}"
        )


def evaluate_offense(
    policy: Any,
    n_episodes: int = 1000,
    seed: int = 0,
    deterministic: bool = True,
    profile: str | ServerProfile = PROFILE,
    **env_kwargs: Any,
) -> OffenseReport:
    """Play trials ``0 .. n_episodes - 1`` of ``seed`` (module docstring) with ``policy``, side by side.

    :param policy: an object with ``predict(obs, deterministic=...)`` returning ``(actions, state)`` for a batch of
        observations (Tuple actions, as :class:`half_field_offense.vec_env.HalfFieldOffenseVecEnv` takes them).
    :param n_episodes: trials to play.
    :param seed: the evaluation set: the same seed gives the same trials to every policy.
    :param deterministic: passed to ``predict`` (greedy actions by default).
    :param profile: the server profile (HFO's ``"v15"`` by default).
    :param env_kwargs: ``noise`` and the :class:`half_field_offense.task.HFOTask` settings.
    :raises ValueError: for ``n_episodes`` not an integer >= 1, a seed numpy refuses, or an invalid env setting.
    """
    if isinstance(n_episodes, bool) or not isinstance(n_episodes, (int, np.integer)) or n_episodes < 1:  # type: ignore[redundant-expr]
        raise ValueError(f"n_episodes must be an integer >= 1, got {n_episodes!r}")
    server_profile, task_settings = configure(profile, env_kwargs.pop("noise", True), None, env_kwargs)
    n = int(n_episodes)
    lanes = HFOLanes(n, server_profile, task_settings, np.random.default_rng(seed))
    action_params = actions.ACTION_PARAMS[: lanes.n_actions]
    obs = lanes.reset(np.arange(n))
    status = np.zeros(n, dtype=np.int64)
    lengths = np.zeros(n, dtype=np.int64)
    returns = np.zeros(n)
    playing = np.ones(n, dtype=np.bool_)
    while playing.any():
        batch, _ = policy.predict(obs, deterministic=deterministic)
        out = lanes.step(*parse_actions(batch, action_params), autoreset=False)
        obs = out.observations
        ended = playing & (out.terminated | out.truncated)
        status[ended], lengths[ended] = out.status[ended], out.episode_lengths[ended]
        returns[ended] = out.episode_returns[ended]
        playing &= ~ended
    return OffenseReport(status, lengths, returns)
