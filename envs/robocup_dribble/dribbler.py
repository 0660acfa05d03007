"""A hand-coded dribbler built from the same four skills: the reference a RoboCup team would write instead of learning.

It looks ahead with the server's own physics, as RoboCup agents do with their world models: from the observation it
rebuilds the player (at the origin, facing +x) and the ball, tries every candidate action (full-power dashes in a
few directions, KICK_ALIGN kicks over a grid of speeds and lateral offsets), follows each with
``horizon - 1`` cycles of straight dashes, and picks the candidate that keeps the ball (inside the kickable area,
clear of the player) and gets furthest along +x. The rollouts are noise-free and assume the player's effort is
``effort`` (the observation does not include it); everything else comes from the observation.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np

from robocup_dribble import physics, skills
from robocup_dribble.params import ServerProfile, make_profile, without_noise
from robocup_dribble.player_types import default_player_type, stack_player_types


class HandCodedDribbler:
    """Greedy look-ahead dribbling policy over the four skills.

    :param profile: the server profile whose physics the look-ahead uses (match the env's).
    :param horizon: cycles simulated per candidate (the candidate, then straight dashes).
    :param dash_directions: directions (deg) of the DASH_MAX candidates.
    :param kick_speeds: speeds (m/cycle) of the KICK_ALIGN candidates.
    :param kick_offsets: lateral offsets (m) of the KICK_ALIGN candidates.
    :param safety: metres the ball should keep from the kickable edge and from touching the player.
    :param effort: the effort assumed for the player's dashes.
    """

    def __init__(
        self,
        profile: str | ServerProfile = "v19",
        horizon: int = 4,
        dash_directions: tuple[float, ...] = (0.0, -30.0, 30.0),
        kick_speeds: tuple[float, ...] = (0.5, 0.7, 0.9, 1.1),
        kick_offsets: tuple[float, ...] = (-0.6, -0.45, 0.45, 0.6),
        safety: float = 0.08,
        effort: float = 0.9,
    ) -> None:
        if horizon < 1:
            raise ValueError(f"horizon must be >= 1, got {horizon}")
        self.profile = without_noise(make_profile(profile))
        self.horizon = horizon
        self.safety = safety
        self.effort = effort
        candidates = [(skills.DASH_MAX, {skills.PARAM_DASH_DIRECTION: d}) for d in dash_directions]
        candidates += [
            (skills.KICK_ALIGN, {skills.PARAM_ALIGN_SPEED: s, skills.PARAM_ALIGN_OFFSET: o})
            for s, o in itertools.product(kick_speeds, kick_offsets)
        ]
        self.candidate_kinds = np.array([kind for kind, _ in candidates])
        self.candidate_params = np.zeros((len(candidates), skills.N_PARAMS))
        for row, (_, values) in enumerate(candidates):
            for column, value in values.items():
                self.candidate_params[row, column] = value
        self._constants = physics.profile_constants(self.profile)
        self._default_type = stack_player_types([default_player_type(self.profile)])[0]

    def act(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Action types ``(n,)`` and parameters ``(n, 7)`` for a batch of observations ``(n, 10)``."""
        obs = np.atleast_2d(np.asarray(obs, dtype=np.float64))
        n, c = obs.shape[0], len(self.candidate_kinds)
        state, types = self._rebuild(np.repeat(obs, c, axis=0))
        kinds = np.tile(self.candidate_kinds, n)
        params = np.tile(self.candidate_params, (n, 1))
        reach = types[:, physics.T_SIZE] + self.profile.server.ball_size + types[:, physics.T_KICKABLE_MARGIN]
        touching = types[:, physics.T_SIZE] + self.profile.server.ball_size
        kept = np.ones(n * c, dtype=bool)  # the ball is still kickable
        safe = np.ones(n * c, dtype=bool)  # ... and kept its safety distances, without a collision
        cycles_kept = np.zeros(n * c)
        uniforms = np.full((n * c, physics.N_UNIFORMS), 0.5)
        for cycle in range(self.horizon):
            commands = skills.commands_for(state, types, kinds, params, self._constants)
            events = physics.step(state, types, commands, uniforms, self._constants)
            gap = np.hypot(state[:, physics.B_X] - state[:, physics.P_X], state[:, physics.B_Y] - state[:, physics.P_Y])
            kept &= gap <= reach
            safe &= kept & (gap <= reach - self.safety) & (gap >= touching + self.safety) & ~events[:, physics.E_COLLISION]
            cycles_kept += kept
            if cycle == 0:  # afterwards: straight full-power dashes
                kinds = np.full(n * c, skills.DASH_MAX)
                params = np.zeros((n * c, skills.N_PARAMS))
        # keeping the ball longest comes first, then keeping it safely, then progress along +x
        score = (100.0 * cycles_kept + 10.0 * safe + state[:, physics.P_X]).reshape(n, c)
        best = np.argmax(score, axis=1)
        return self.candidate_kinds[best], self.candidate_params[best]

    def predict(self, obs: np.ndarray, state: Any = None, episode_start: Any = None, deterministic: bool = True):
        """SB3-style ``predict``: one Tuple action for one observation, an object array of them for a batch."""
        single = np.asarray(obs).ndim == 1
        actions = skills.as_env_actions(*self.act(obs))
        return (actions[0] if single else actions), None

    def _rebuild(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Physics state and player types from observations (player at the origin facing +x)."""
        m = obs.shape[0]
        server = self.profile.server
        types = np.tile(self._default_type, (m, 1))
        types[:, physics.T_DECAY] = obs[:, 0]
        types[:, physics.T_INERTIA] = server.inertia_moment + (obs[:, 0] - server.player_decay) * self.profile.player.inertia_moment_delta_factor
        types[:, physics.T_DASH_POWER_RATE] = obs[:, 1]
        types[:, physics.T_KICKABLE_MARGIN] = obs[:, 2]
        types[:, physics.T_EFFORT_MAX] = self.effort
        state = physics.new_state(m)
        physics.recover(state, types, self.profile)
        state[:, physics.P_VX], state[:, physics.P_VY] = obs[:, 8], obs[:, 9]
        state[:, physics.B_X], state[:, physics.B_Y] = obs[:, 4], obs[:, 5]
        state[:, physics.B_VX], state[:, physics.B_VY] = obs[:, 6] + obs[:, 8], obs[:, 7] + obs[:, 9]
        return state, types
