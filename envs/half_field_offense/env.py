"""The Gymnasium environment of one Half Field Offense 1v0 trial (:class:`HalfFieldOffenseEnv`).

This module needs Gymnasium and numpy only; :class:`half_field_offense.vec_env.HalfFieldOffenseVecEnv` (N lanes as a
Stable-Baselines3 ``VecEnv``) lives in its own module.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from half_field_offense import actions, features, referee
from half_field_offense.lanes import HFOLanes
from half_field_offense.task import HFOTask
from robocup_dribble import physics
from robocup_dribble.env import RENDER_MODES, TRAIL_LENGTH, configure_task, lane_frame, parse_action
from robocup_dribble.params import ServerProfile

PROFILE = "v15"
"""The server profile HFO's rcssserver 15.2.2 fork runs (:data:`robocup_dribble.params.PROFILES`)."""
VIEW_CENTRE = (26.25, 0.0)  # m: the middle of the HFO area, where a rendered view stays
VIEW_WIDTH = 57.0  # m: the HFO area and a margin, in 560 x 700 pixels


def configure(
    profile: str | ServerProfile, noise: bool, render_mode: str | None, task_kwargs: dict[str, Any]
) -> tuple[ServerProfile, HFOTask]:
    """Validate the constructor arguments both envs share (:func:`robocup_dribble.env.configure_task`)."""
    return configure_task(profile, noise, render_mode, task_kwargs, HFOTask)


def observation_space() -> spaces.Box:
    """``Box(-1, 1, (59,), float32)``: :data:`half_field_offense.features.FEATURE_NAMES`."""
    return spaces.Box(-1.0, 1.0, (features.N_FEATURES,), dtype=np.float32)


class HalfFieldOffenseEnv(gym.Env):
    """## Description

    Half Field Offense 1v0 (Hausknecht et al. 2016) with HFO's low-level features and actions: one agent must reach
    the ball and score on an empty goal from the attacking half. Server physics of HFO's rcssserver 15.2.2
    (``profile="v15"``, the default player type, the server's noise), HFO's referee, start distribution, features,
    the agent's command transforms and dqn-hfo's shaped reward (:mod:`half_field_offense`).

    ## Action Space

    ``Tuple(Discrete(3), Tuple(Box([0, -180], [100, 180]), Box([-180], [180]), Box([0, -180], [100, 180])))``:
    0 ``DASH(power, direction)``, 1 ``TURN(direction)``, 2 ``KICK(power, direction)`` (degrees relative to the
    body); with ``tackle=True`` a fourth, ``TACKLE(direction)``, with ``Box([-180], [180])``. Only the chosen
    action's parameters are used; out-of-range values are clipped. One action is one server cycle.

    ## Observation Space

    ``Box(-1, 1, (59,), float32)``: HFO's low-level features in its order
    (:data:`half_field_offense.features.FEATURE_NAMES`).

    ## Rewards

    ``reward="shaped"`` (default): ball approach, +1 once on first reaching the ball, three times the ball's progress
    to the goal while the agent holds it, +5 for a goal (:mod:`half_field_offense.reward`); ``"sparse"``: +1 for a goal.

    ## Starting State

    The ball at x in [0, 10.5], |y| <= 27.2; the agent 10.5-21 m from it in one of ten directions
    (:mod:`half_field_offense.referee`); both at rest. The body direction carries over from the previous trial.

    ## Episode End

    1. Termination: ``GOAL``; ``OUT_OF_BOUNDS`` (the ball left x in [0, 52.5], |y| <= 34 a cycle earlier);
       ``OUT_OF_TIME`` by a ball untouched for more than ``untouched_time`` (100) cycles.
    2. Truncation: ``OUT_OF_TIME`` after more than ``frames_per_trial`` (500) cycles.

    ``info["status"]`` is HFO's status name (``"IN_GAME"`` while the trial goes on); the last step's ``info`` also
    has ``is_success`` (a goal), which SB3 logs as ``rollout/success_rate``. :meth:`step` before the first
    :meth:`reset`, or after the trial ended, raises Gymnasium's ``ResetNeeded``; an invalid action raises
    ``ValueError`` and changes nothing.

    ## Arguments

    ``profile`` (``"v15"``, the default, or another server profile), ``noise`` (False switches every noise source
    off), ``render_mode`` (``"human"``, ``"rgb_array"`` or None) and the fields of
    :class:`half_field_offense.task.HFOTask` as keywords.
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 10}  # noqa: RUF012  (Gymnasium declares it so)

    def __init__(
        self, profile: str | ServerProfile = PROFILE, noise: bool = True, render_mode: str | None = None, **task_kwargs: Any
    ) -> None:
        self.profile, self.task = configure(profile, noise, render_mode, task_kwargs)
        self.render_mode = render_mode
        self._lanes = HFOLanes(1, self.profile, self.task, self.np_random)
        self._action_params = actions.ACTION_PARAMS[: self._lanes.n_actions]
        self.action_space = actions.action_space(self.task.tackle)
        self.observation_space = observation_space()
        self._lane = np.zeros(1, dtype=np.int64)
        self._started = False
        self._over = False
        self._status = referee.IN_GAME
        self._ball_trail: deque[tuple[float, float]] = deque(maxlen=TRAIL_LENGTH)
        self._player_trail: deque[tuple[float, float]] = deque(maxlen=TRAIL_LENGTH)
        self._renderer: Any = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        if seed is not None or self._lanes.rng is not self.np_random:
            self._lanes.reseed(self.np_random)
        obs = self._lanes.reset(self._lane)
        self._started, self._over, self._status = True, False, referee.IN_GAME
        self._ball_trail.clear()
        self._player_trail.clear()
        self._remember_positions()
        if self.render_mode == "human":
            self.render()
        return obs[0], {"status": referee.STATUS_NAMES[referee.IN_GAME]}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if not self._started:
            raise ResetNeeded("Call reset() before step(): the trial has not started")
        if self._over:
            raise ResetNeeded("Call reset() before step(): the trial has ended (terminated or truncated)")
        action_type, params = parse_action(action, self._action_params)
        out = self._lanes.step(np.array([action_type], dtype=np.int64), params[None, :], autoreset=False)
        self._remember_positions()
        if self.render_mode == "human":
            self.render()
        terminated, truncated = bool(out.terminated[0]), bool(out.truncated[0])
        self._over, self._status = terminated or truncated, int(out.status[0])
        info: dict[str, Any] = {"status": referee.STATUS_NAMES[self._status]}
        if self._over:
            info["is_success"] = self._status == referee.GOAL
        return out.observations[0], float(out.rewards[0]), terminated, truncated, info

    def render(self) -> np.ndarray | None:
        if not self._started:
            raise ResetNeeded("Call reset() before render(): there is no trial to draw yet")
        if self.render_mode is None:
            gym.logger.warn("render() was called without a render_mode; pass render_mode='rgb_array' or 'human' to the env.")
            return None
        from robocup_dribble.render import DribbleRenderer

        if self._renderer is None:
            fps = self.metadata["render_fps"]
            self._renderer = DribbleRenderer(self.render_mode, 560, 700, VIEW_WIDTH, fps, VIEW_CENTRE)
        frame = render_frame(self._lanes, 0, self._ball_trail, self._player_trail, referee.STATUS_NAMES[self._status])
        image: np.ndarray | None = self._renderer.render(frame)
        return image

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def _remember_positions(self) -> None:
        s = self._lanes.state
        self._ball_trail.append((s[0, physics.B_X], s[0, physics.B_Y]))
        self._player_trail.append((s[0, physics.P_X], s[0, physics.P_Y]))


def render_frame(
    lanes: HFOLanes,
    lane: int,
    ball_trail: Iterable[tuple[float, float]],
    player_trail: Iterable[tuple[float, float]],
    status: str,
) -> Any:
    """The :class:`robocup_dribble.render.RenderFrame` of a lane (imports the renderer's module on first use)."""
    caption = f"Half Field Offense | cycle {int(lanes.steps[lane])} | {status}"
    return lane_frame(lanes.state[lane], lanes.types[lane], lanes.profile.server.ball_size, ball_trail, player_trail, caption)
