"""N Half Field Offense trials as one Stable-Baselines3 ``VecEnv`` (:class:`HalfFieldOffenseVecEnv`), with the array
path. This module imports SB3 (and so torch); :mod:`half_field_offense.env` does not."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from gymnasium.utils import seeding
from stable_baselines3.common.vec_env.base_vec_env import VecEnvObs

from half_field_offense import actions, referee
from half_field_offense.env import PROFILE, HalfFieldOffenseEnv, configure, observation_space
from half_field_offense.lanes import HFOLanes
from robocup_dribble.params import ServerProfile
from robocup_dribble.vec_env import ArrayStep, LaneVecEnv


class HalfFieldOffenseVecEnv(LaneVecEnv):
    """``n_envs`` Half Field Offense trials stepped by one compiled call: a Stable-Baselines3 ``VecEnv``.

    Same physics, task and arguments as :class:`half_field_offense.env.HalfFieldOffenseEnv` (one code path:
    :class:`half_field_offense.lanes.HFOLanes`); with ``n_envs=1`` and the same seed it plays the same trials. Ended
    trials restart inside the compiled step. All lanes draw from one generator seeded by :meth:`seed`.

    Ways to step, giving the same transitions: :meth:`step_arrays` (``(N,)`` action types and ``(N, P)`` parameters
    in, an :class:`robocup_dribble.vec_env.ArrayStep` out, ``episode_info["status"]`` the ``(N,)`` status codes of
    :data:`half_field_offense.referee.STATUS_NAMES`), :meth:`step_packed` (the same arrays in, SB3's return out) and
    :meth:`step` (SB3's form). ``infos[i]["status"]`` is HFO's status name; where a trial ended the infos also carry
    ``is_success`` (a goal: SB3 logs it as ``rollout/success_rate``), ``terminal_observation``, ``TimeLimit.truncated``
    and ``episode = {"r", "l", "t"}``.
    """

    metadata = HalfFieldOffenseEnv.metadata

    def __init__(self, n_envs: int, profile: str | ServerProfile = PROFILE, noise: bool = True, **task_kwargs: Any) -> None:
        self.profile, self.task = configure(profile, noise, None, task_kwargs)
        self._lanes = HFOLanes(n_envs, self.profile, self.task, seeding.np_random()[0])
        self._action_params = actions.ACTION_PARAMS[: self._lanes.n_actions]
        self.render_mode = None  # trials are drawn by the single env (HalfFieldOffenseEnv)
        super().__init__(n_envs, observation_space(), actions.action_space(self.task.tackle))
        self.metadata = dict(HalfFieldOffenseEnv.metadata)
        self._all = np.arange(self.num_envs)
        self._t_start = time.time()

    def reset(self) -> VecEnvObs:
        if self._seeds[0] is not None:
            self._lanes.reseed(seeding.np_random(self._seeds[0])[0])
        self._reset_seeds()
        obs = self._lanes.reset(self._all)
        self._started = True
        return obs

    def step_arrays(self, action_types: np.ndarray, params: np.ndarray) -> ArrayStep:
        """Step all lanes with ``(N,)`` action types and ``(N, P)`` parameters (columns
        :data:`half_field_offense.actions.PARAM_NAMES`, env units; out-of-range values are clipped); lanes whose
        trial ended start the next one.

        :raises ValueError: for a wrong shape, an action type out of range, a non-finite parameter, or a call before
            :meth:`reset`; nothing changes.
        """
        self._check_started()
        out = self._lanes.step(action_types, params)
        return ArrayStep(
            out.observations,
            out.rewards,
            out.terminated,
            out.truncated,
            out.terminal_observations,
            out.episode_returns,
            out.episode_lengths,
            {"status": out.status},
        )

    def _infos(self, step: ArrayStep) -> list[dict[str, Any]]:
        names, in_game, goal = referee.STATUS_NAMES, referee.IN_GAME, referee.GOAL
        return [
            {"status": names[code]} if code == in_game else {"status": names[code], "is_success": code == goal}
            for code in step.episode_info["status"].tolist()
        ]

    def close(self) -> None:
        """Nothing to release."""
