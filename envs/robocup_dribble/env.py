"""The Gymnasium environment of one dribbling lane (:class:`DribbleEnv`) and what it shares with the vector env.

This module needs Gymnasium and numpy only; :class:`robocup_dribble.vec_env.DribbleVecEnv` (N lanes as a
Stable-Baselines3 ``VecEnv``) lives in its own module, so that ``DribbleEnv`` can be used without SB3 and torch.
"""

from __future__ import annotations

from collections import deque
import dataclasses
from collections.abc import Iterable
from typing import Any, TypeVar

import gymnasium as gym
import numpy as np
from gymnasium.error import ResetNeeded

from robocup_dribble import physics, skills
from robocup_dribble.lanes import DribbleLanes
from robocup_dribble.params import ServerProfile, make_profile, without_noise
from robocup_dribble.task import DribbleTask

RENDER_MODES = ("human", "rgb_array")
TRAIL_LENGTH = 20


Task = TypeVar("Task")


def configure_task(
    profile: str | ServerProfile, noise: bool, render_mode: str | None, task_kwargs: dict[str, Any], task_class: type[Task]
) -> tuple[ServerProfile, Task]:
    """Validate the constructor arguments every env on these physics shares: the render mode, the profile with or
    without noise, and the keywords of the env's task dataclass ``task_class``."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(f"render_mode={render_mode!r} is not supported; choose one of {list(RENDER_MODES)} or None")
    server_profile = make_profile(profile)
    if not noise:
        server_profile = without_noise(server_profile)
    allowed = {field.name for field in dataclasses.fields(task_class)}  # type: ignore[arg-type]
    unknown = sorted(set(task_kwargs) - allowed)
    if unknown:
        raise ValueError(f"Unknown argument(s) {unknown}; the task takes {sorted(allowed)}")
    return server_profile, task_class(**task_kwargs)


def configure(
    profile: str | ServerProfile, noise: bool, render_mode: str | None, task_kwargs: dict[str, Any]
) -> tuple[ServerProfile, DribbleTask]:
    """Validate the shared constructor arguments of both dribbling envs (:func:`configure_task`)."""
    return configure_task(profile, noise, render_mode, task_kwargs, DribbleTask)


def parse_action(action: Any, action_params: tuple[tuple[str, ...], ...] = skills.ACTION_PARAMS) -> tuple[int, np.ndarray]:
    """``(k, (p_0, ..., p_{K-1}))`` -> ``(k, flat params)`` for K action types whose parameters are named by
    ``action_params`` (by default the dribbling skills': ``(k, (p_dash, p_kick_velocity, p_kick_position,
    p_kick_align))`` -> ``(k, (7,) params)``).

    :raises ValueError: unless ``k`` is an integer (a Python or numpy integer, or an integral real number; not a
        bool) in 0..K-1 and the parts are real vectors of the sizes of ``action_params``.
    """
    param_sizes = tuple(len(names) for names in action_params)
    try:
        action_type, parts = action
        sizes = tuple(part.size if type(part) is np.ndarray else np.size(part) for part in parts)
        params = np.concatenate(parts, axis=None, dtype=np.float64)  # axis=None flattens each part
    except (TypeError, ValueError) as error:
        layout = ", ".join(f"{names[0].split('_')[0]} ({len(names)},)" for names in action_params)
        raise ValueError(f"An action must be (action_type, ({layout})) with real parameters, got {action!r:.300}") from error
    if sizes != param_sizes:
        raise ValueError(f"The parameter vectors of an action must have sizes {param_sizes}, got {sizes} in {action!r:.300}")
    return action_type_index(action_type, len(action_params)), params


def action_type_index(action_type: Any, n_types: int = skills.N_ACTION_TYPES) -> int:
    """``action_type`` as an int in 0..n_types-1; a Python or numpy integer or an integral real number, not a bool.

    :raises ValueError: for anything else (None, a bool, a complex number, a string, 1.5, 7, ...).
    """
    if isinstance(action_type, (bool, np.bool_)) or not isinstance(action_type, (int, float, np.integer, np.floating)):
        raise ValueError(f"The action type must be an integer in 0..{n_types - 1}, got {action_type!r}")
    if not (float(action_type).is_integer() and 0 <= action_type < n_types):
        raise ValueError(f"The action type must be an integer in 0..{n_types - 1}, got {action_type!r}")
    return int(action_type)


class DribbleEnv(gym.Env):
    """## Description

    RoboCup 2D soccer simulator dribbling (Uc-Cetina 2013): one player of a heterogeneous type must run along +x
    while keeping the ball inside its kickable area, alternating dashes and kicks. The physics follow rcssserver
    (``profile="v19"``, verified against a recorded server) or the 2007 server the paper used (``"v11"``).

    ## Action Space

    ``Tuple(Discrete(4), Tuple(Box(1), Box(2), Box(2), Box(2)))``: an action type and every type's parameters
    (only the chosen type's are used): 0 ``DASH_MAX(direction deg)``, 1 ``KICK_VELOCITY(speed m/cycle,
    direction deg)``, 2 ``KICK_POSITION(x m, y m)``, 3 ``KICK_ALIGN(speed m/cycle, offset m)``; see
    :mod:`robocup_dribble.skills`. Out-of-range parameters are clipped, as the server clips a command.

    ## Observation Space

    ``Box(10)`` float32: player decay, dash power rate, kickable margin, kick rand, ball-player position x/y, ball-player
    velocity x/y, player velocity x/y (see :func:`robocup_dribble.task.observation_space` for the bounds).

    ## Rewards

    In this order: ``in_the_way_penalty`` (-10) if ball and player collided; ``border_penalty`` (-10) if the ball is
    within ``border_width`` (0.1 m) of the kickable edge or lost; ``too_close_penalty`` (-5) if it is within
    ``close_margin`` (0.1 m) of touching; else ``progress_weight`` (50) times the metres advanced along +x.

    ## Starting State

    Player at the centre spot facing +x with a random velocity; ball at a random place of the kickable area with the
    player's velocity plus a random one (:class:`robocup_dribble.task.DribbleTask`). A new set of player types every
    ``episodes_per_type_set`` (7) episodes; each episode of a set uses a different type.

    ## Episode End

    1. Termination: the ball leaves the kickable area.
    2. Truncation: ``max_actions`` (35) actions.

    ``info``: ``distance`` (metres dribbled along +x, frozen at the last step with the ball), ``ball_lost``,
    and ``player_type`` (a :class:`robocup_dribble.player_types.PlayerType` with the type's parameters).
    :meth:`step` before the first :meth:`reset`, or after the episode ended, raises Gymnasium's ``ResetNeeded``; an
    invalid action raises ``ValueError`` and changes nothing.

    ## Arguments

    ``profile`` (``"v19"``, ``"v11"`` or a ServerProfile), ``noise`` (False switches every noise source off),
    ``render_mode`` (``"human"``, ``"rgb_array"`` or None), ``perception`` (``"full"``, the default: the observation
    and the skills' commands are computed from the exact state; ``"match"``: from the player's estimate kept from
    what rcssserver's see and sense_body would tell it, :mod:`robocup_dribble.perception`, while physics, reward and
    termination run on the true state) and the fields of :class:`DribbleTask` as keywords.
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 10}  # noqa: RUF012  (Gymnasium declares it so)

    def __init__(
        self,
        profile: str | ServerProfile = "v19",
        noise: bool = True,
        render_mode: str | None = None,
        perception: str = "full",
        **task_kwargs: Any,
    ) -> None:
        self.profile, self.task = configure(profile, noise, render_mode, task_kwargs)
        self.render_mode = render_mode
        self._lanes = DribbleLanes(1, self.profile, self.task, self.np_random, perception)
        self.action_space = skills.action_space(self.profile)
        self.observation_space = self._lanes.observation_space
        self._lane = np.zeros(1, dtype=np.int64)
        self._player_type: Any = None  # None until the first reset
        self._ball_trail: deque[tuple[float, float]] = deque(maxlen=TRAIL_LENGTH)
        self._player_trail: deque[tuple[float, float]] = deque(maxlen=TRAIL_LENGTH)
        self._renderer: Any = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        if seed is not None or self._lanes.rng is not self.np_random:
            self._lanes.reseed(self.np_random)
        obs = self._lanes.reset(self._lane)
        self._player_type = self._lanes.player_type(0)
        self._episode_over = False
        self._ball_trail.clear()
        self._player_trail.clear()
        self._remember_positions()
        if self.render_mode == "human":
            self.render()
        return obs[0], self._info(0.0, False)

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self._player_type is None:
            raise ResetNeeded("Call reset() before step(): the episode has not started")
        if self._episode_over:
            raise ResetNeeded("Call reset() before step(): the episode has ended (terminated or truncated)")
        action_type, params = parse_action(action)
        out = self._lanes.step(np.array([action_type], dtype=np.int64), params[None, :], autoreset=False)
        self._remember_positions()
        if self.render_mode == "human":
            self.render()
        lost, truncated = bool(out.terminated[0]), bool(out.truncated[0])
        self._episode_over = lost or truncated
        info = self._info(float(out.distances[0]), lost)
        return out.observations[0], float(out.rewards[0]), lost, truncated, info

    def render(self) -> np.ndarray | None:
        if self._player_type is None:
            raise ResetNeeded("Call reset() before render(): there is no episode to draw yet")
        if self.render_mode is None:
            gym.logger.warn("render() was called without a render_mode; pass render_mode='rgb_array' or 'human' to the env.")
            return None
        from robocup_dribble.render import DribbleRenderer

        if self._renderer is None:
            self._renderer = DribbleRenderer(self.render_mode, fps=self.metadata["render_fps"])
        frame: np.ndarray | None = self._renderer.render(render_frame(self._lanes, 0, self._ball_trail, self._player_trail))
        return frame

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def _info(self, distance: float, lost: bool) -> dict[str, Any]:
        return {"distance": distance, "ball_lost": lost, "player_type": self._player_type}

    def _remember_positions(self) -> None:
        s = self._lanes.state
        self._ball_trail.append((s[0, physics.B_X], s[0, physics.B_Y]))
        self._player_trail.append((s[0, physics.P_X], s[0, physics.P_Y]))


def render_frame(
    lanes: DribbleLanes, lane: int, ball_trail: Iterable[tuple[float, float]], player_trail: Iterable[tuple[float, float]]
) -> Any:
    """The :class:`robocup_dribble.render.RenderFrame` of a dribbling lane (imports the renderer's module on first use)."""
    caption = (
        f"type {int(lanes.type_ids[lane])} | step {int(lanes.steps[lane])}/{lanes.task.max_actions} | "
        f"{lanes.distance[lane]:.1f} m"
    )
    return lane_frame(lanes.state[lane], lanes.types[lane], lanes.profile.server.ball_size, ball_trail, player_trail, caption)


def lane_frame(
    state: np.ndarray,
    player_type: np.ndarray,
    ball_size: float,
    ball_trail: Iterable[tuple[float, float]],
    player_trail: Iterable[tuple[float, float]],
    caption: str,
) -> Any:
    """The :class:`robocup_dribble.render.RenderFrame` of one lane's state row and player type row (any env on these
    physics draws through it; imports the renderer's module on first use)."""
    from robocup_dribble.render import RenderFrame

    s, t = state, player_type
    return RenderFrame(
        player_xy=(s[physics.P_X], s[physics.P_Y]),
        body_deg=float(np.degrees(s[physics.P_BODY])),
        player_size=t[physics.T_SIZE],
        kickable_area=physics.kickable_radius(t[physics.T_SIZE], ball_size, t[physics.T_KICKABLE_MARGIN]),
        ball_xy=(s[physics.B_X], s[physics.B_Y]),
        ball_size=ball_size,
        trail=np.array(list(ball_trail), dtype=np.float64).reshape(-1, 2),
        player_trail=np.array(list(player_trail), dtype=np.float64).reshape(-1, 2),
        caption=caption,
    )
