"""A hand-coded Half Field Offense 1v0 agent on the low-level features (:class:`HandCodedOffense`): the sanity anchor
and the baseline every learner is compared with.

It reads only the observation, as a learner does: away from the ball it turns to face it and runs at it (slowing
near it so as not to run into it); with the ball kickable it shoots at the goal centre with full power when the goal
is within ``shooting_distance``, and otherwise dribbles, kicking the ball ahead towards the goal with
``dribble_power`` and running after it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from half_field_offense import actions, features
from half_field_offense.task import DISTANCE_NORMALISERS
from robocup_dribble.skills import as_env_actions

F = features.FEATURE_NAMES.index


class HandCodedOffense:
    """Go to the ball, dribble towards the goal, shoot when close (module docstring).

    :param distance_normaliser: the env's (``HFOTask.distance_normaliser``): how proximities map to metres.
    :param tackle: the env's action set has Tackle (the agent never tackles; this only sizes its parameters).
    :param shooting_distance: metres from the goal centre within which a kickable ball is shot.
    :param dribble_power: kick power of a dribbling kick.
    :param turn_threshold: degrees off the ball's bearing beyond which the agent turns rather than runs.
    :param approach_distance: metres from the ball within which the agent dashes with less than full power.
    """

    def __init__(
        self,
        distance_normaliser: str = "current",
        tackle: bool = False,
        shooting_distance: float = 25.0,
        dribble_power: float = 35.0,
        turn_threshold: float = 15.0,
        approach_distance: float = 2.0,
    ) -> None:
        if distance_normaliser not in DISTANCE_NORMALISERS:
            raise ValueError(f"distance_normaliser must be one of {sorted(DISTANCE_NORMALISERS)}, got {distance_normaliser!r}")
        self.max_distance = DISTANCE_NORMALISERS[distance_normaliser]
        self.n_params = actions.n_params(tackle)
        self.shooting_distance, self.dribble_power = float(shooting_distance), float(dribble_power)
        self.turn_threshold, self.approach_distance = float(turn_threshold), float(approach_distance)

    def _distance(self, proximity: np.ndarray) -> np.ndarray:
        return 0.5 * (1.0 - proximity) * self.max_distance

    def act(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Action types ``(n,)`` and parameters ``(n, P)`` for a batch of observations ``(n, 59)`` (or one)."""
        obs = np.atleast_2d(np.asarray(obs, dtype=np.float64))
        if obs.shape[1] != features.N_FEATURES:
            raise ValueError(f"observations must have {features.N_FEATURES} features, got shape {obs.shape}")
        ball_bearing = np.degrees(np.arctan2(obs[:, F("ball_sin")], obs[:, F("ball_cos")]))
        goal_bearing = np.degrees(np.arctan2(obs[:, F("goal_centre_sin")], obs[:, F("goal_centre_cos")]))
        ball_distance = self._distance(obs[:, F("ball_proximity")])
        goal_distance = self._distance(obs[:, F("goal_centre_proximity")])
        kickable = obs[:, F("kickable")] > 0.0
        n = obs.shape[0]
        kinds = np.full(n, actions.DASH, dtype=np.int64)
        params = np.zeros((n, self.n_params))
        dash, turn, kick = (actions.PARAM_STARTS[a] for a in (actions.DASH, actions.TURN, actions.KICK))
        params[:, dash] = np.where(ball_distance < self.approach_distance, 40.0 + 30.0 * ball_distance, 100.0).clip(0, 100)
        params[:, dash + 1] = ball_bearing
        turning = ~kickable & (np.abs(ball_bearing) > self.turn_threshold)
        kinds[turning] = actions.TURN
        params[:, turn] = ball_bearing
        kinds[kickable] = actions.KICK
        params[:, kick] = np.where(goal_distance < self.shooting_distance, 100.0, self.dribble_power)
        params[:, kick + 1] = goal_bearing
        return kinds, params

    def predict(
        self, obs: np.ndarray, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[Any, None]:
        """SB3-style ``predict``: one Tuple action for one observation, an object array of them for a batch."""
        single = np.asarray(obs).ndim == 1
        batch = as_env_actions(*self.act(obs), param_slices=actions.PARAM_SLICES[: actions.n_actions(self.n_params == 6)])
        return (batch[0] if single else batch), None
