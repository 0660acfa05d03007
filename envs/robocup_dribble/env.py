"""Gymnasium environments: one dribbling lane (:class:`DribbleEnv`) and N lanes as an SB3 VecEnv (:class:`DribbleVecEnv`)."""

from __future__ import annotations

import contextlib
import gc
import time
from collections import deque
from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvObs, VecEnvStepReturn

from robocup_dribble import physics, skills
from robocup_dribble.lanes import DribbleLanes
from robocup_dribble.params import ServerProfile, make_profile, without_noise
from robocup_dribble.task import DribbleTask

RENDER_MODES = ("human", "rgb_array")
TRAIL_LENGTH = 20


def _configure(profile: str | ServerProfile, noise: bool, render_mode: str | None, task_kwargs: dict) -> tuple[ServerProfile, DribbleTask]:
    """Validate the shared constructor arguments of both envs."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(f"render_mode={render_mode!r} is not supported; choose one of {list(RENDER_MODES)} or None")
    server_profile = make_profile(profile)
    if not noise:
        server_profile = without_noise(server_profile)
    allowed = set(DribbleTask.__dataclass_fields__)
    unknown = sorted(set(task_kwargs) - allowed)
    if unknown:
        raise ValueError(f"Unknown argument(s) {unknown}; the task takes {sorted(allowed)}")
    return server_profile, DribbleTask(**task_kwargs)


def parse_action(action: Any) -> tuple[int, np.ndarray]:
    """``(k, (p_dash, p_kick_velocity, p_kick_position, p_kick_align))`` -> ``(k, (7,) params)``."""
    try:
        action_type, parts = action
        params = np.concatenate(parts, axis=None, dtype=np.float64)  # axis=None flattens each part
        sizes = tuple(part.size if type(part) is np.ndarray else np.size(part) for part in parts)
    except (TypeError, ValueError) as error:
        raise ValueError(
            f"An action must be (action_type, (dash (1,), kick_velocity (2,), kick_position (2,), kick_align (2,))), got {action!r}"
        ) from error
    if sizes != (1, 2, 2, 2):
        raise ValueError(f"The parameter vectors of an action must have sizes (1, 2, 2, 2), got {sizes} in {action!r}")
    if isinstance(action_type, (bool, np.bool_)) or not float(action_type).is_integer():
        raise ValueError(f"The action type must be an integer in 0..{skills.N_ACTION_TYPES - 1}, got {action_type!r}")
    return int(action_type), params


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

    ## Arguments

    ``profile`` (``"v19"``, ``"v11"`` or a ServerProfile), ``noise`` (False switches every noise source off),
    ``render_mode`` (``"human"``, ``"rgb_array"`` or None) and the fields of :class:`DribbleTask` as keywords.
    """

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 10}

    def __init__(self, profile: str | ServerProfile = "v19", noise: bool = True, render_mode: str | None = None, **task_kwargs: Any) -> None:
        self.profile, self.task = _configure(profile, noise, render_mode, task_kwargs)
        self.render_mode = render_mode
        self._lanes = DribbleLanes(1, self.profile, self.task, self.np_random)
        self.action_space = skills.action_space(self.profile)
        self.observation_space = self._lanes.observation_space
        self._lane = np.zeros(1, dtype=np.int64)
        self._player_type = None
        self._ball_trail: deque = deque(maxlen=TRAIL_LENGTH)
        self._player_trail: deque = deque(maxlen=TRAIL_LENGTH)
        self._renderer = None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        if seed is not None or self._lanes.rng is not self.np_random:
            self._lanes.reseed(self.np_random)
        obs = self._lanes.reset(self._lane)
        self._player_type = self._lanes.player_type(0)
        self._ball_trail.clear()
        self._player_trail.clear()
        self._remember_positions()
        if self.render_mode == "human":
            self.render()
        return obs[0], self._info(0.0, False)

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        action_type, params = parse_action(action)
        obs, reward, lost, truncated, distance = self._lanes.step(np.array([action_type]), params[None, :])
        self._remember_positions()
        if self.render_mode == "human":
            self.render()
        return obs[0], float(reward[0]), bool(lost[0]), bool(truncated[0]), self._info(float(distance[0]), bool(lost[0]))

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn("render() was called without a render_mode; pass render_mode='rgb_array' or 'human' to the env.")
            return None
        from robocup_dribble.render import DribbleRenderer

        if self._renderer is None:
            self._renderer = DribbleRenderer(self.render_mode, fps=self.metadata["render_fps"])
        return self._renderer.render(_frame(self._lanes, 0, self._ball_trail, self._player_trail))

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def _info(self, distance: float, lost: bool) -> dict[str, Any]:
        return {"distance": distance, "ball_lost": lost, "player_type": self._player_type}

    def _remember_positions(self) -> None:
        s = self._lanes.state[0]
        self._ball_trail.append((s[physics.B_X], s[physics.B_Y]))
        self._player_trail.append((s[physics.P_X], s[physics.P_Y]))


def _frame(lanes: DribbleLanes, lane: int, ball_trail: Iterable, player_trail: Iterable):
    from robocup_dribble.render import RenderFrame

    s, t = lanes.state[lane], lanes.types[lane]
    ball_size = lanes.profile.server.ball_size
    return RenderFrame(
        player_xy=(s[physics.P_X], s[physics.P_Y]),
        body_deg=float(np.degrees(s[physics.P_BODY])),
        player_size=t[physics.T_SIZE],
        kickable_area=t[physics.T_SIZE] + ball_size + t[physics.T_KICKABLE_MARGIN],
        ball_xy=(s[physics.B_X], s[physics.B_Y]),
        ball_size=ball_size,
        trail=np.array(list(ball_trail), dtype=np.float64).reshape(-1, 2),
        player_trail=np.array(list(player_trail), dtype=np.float64).reshape(-1, 2),
        caption=f"type {int(lanes.type_ids[lane])} | step {int(lanes.steps[lane])}/{lanes.task.max_actions} | {lanes.distance[lane]:.1f} m",
    )


@contextlib.contextmanager
def _gc_paused() -> Iterator[None]:
    """Pause Python's cyclic garbage collector: the objects made meanwhile form no reference cycles."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


class DribbleVecEnv(VecEnv):
    """``n_envs`` dribbling lanes stepped by one compiled call: a Stable-Baselines3 ``VecEnv``.

    Same physics, task and arguments as :class:`DribbleEnv` (one code path: :class:`robocup_dribble.lanes.DribbleLanes`);
    with ``n_envs=1`` and the same seed it produces the same episodes. Finished lanes reset automatically: their
    ``infos[i]`` carry ``terminal_observation``, ``TimeLimit.truncated`` and, like SB3's ``VecMonitor``,
    ``episode = {"r", "l", "t"}``. All lanes draw from one generator seeded by :meth:`seed` (the first seed).

    :meth:`step_packed` takes a batch as two arrays (``(N,)`` action types, ``(N, 7)`` parameters) and skips
    building N Python tuples; :meth:`step` takes the SB3 form, a sequence of N per-lane Tuple actions.
    """

    metadata = DribbleEnv.metadata

    def __init__(self, n_envs: int, profile: str | ServerProfile = "v19", noise: bool = True, render_mode: str | None = None, **task_kwargs: Any) -> None:
        self.profile, self.task = _configure(profile, noise, render_mode, task_kwargs)
        self._lanes = DribbleLanes(n_envs, self.profile, self.task, seeding.np_random()[0])
        self.render_mode = render_mode
        super().__init__(n_envs, self._lanes.observation_space, skills.action_space(self.profile))
        self._all = np.arange(self.num_envs)
        self._returns = np.zeros(self.num_envs)
        self._t_start = time.time()
        self._player_types: list = [None] * self.num_envs
        self._actions: Sequence | None = None
        self._renderer = None

    def reset(self) -> VecEnvObs:
        if self._seeds[0] is not None:
            self._lanes.reseed(seeding.np_random(self._seeds[0])[0])
        self._reset_seeds()
        self._returns[:] = 0.0
        return self._start(self._all)

    def step_async(self, actions: Sequence) -> None:
        self._actions = actions

    def step_wait(self) -> VecEnvStepReturn:
        if self._actions is None or len(self._actions) != self.num_envs:
            got = None if self._actions is None else len(self._actions)
            raise ValueError(f"step() needs one action per lane ({self.num_envs}), got {got}")
        parsed = [parse_action(action) for action in self._actions]
        self._actions = None
        return self.step_packed(np.array([k for k, _ in parsed]), np.stack([p for _, p in parsed]))

    def step_packed(self, action_types: np.ndarray, params: np.ndarray) -> VecEnvStepReturn:
        """Step all lanes with ``(N,)`` action types and ``(N, 7)`` parameters (``robocup_dribble.skills.PARAM_*``)."""
        obs, reward, lost, truncated, distance = self._lanes.step(action_types, params)
        self._returns += reward
        dones = lost | truncated
        lost_list, distance_list = lost.tolist(), distance.tolist()
        finished = np.flatnonzero(dones)
        # Thousands of fresh dicts and tuples per step would otherwise set off collector passes over every live
        # object (about a quarter of the step at N=4096); none of them forms a reference cycle.
        with _gc_paused():
            infos = [
                {"distance": d, "ball_lost": b, "player_type": t}
                for d, b, t in zip(distance_list, lost_list, self._player_types)
            ]
            if len(finished):
                elapsed = round(time.time() - self._t_start, 6)
                terminal = obs[finished]  # a copy: obs rows are overwritten by the reset below
                returns = self._returns[finished].tolist()
                lengths = self._lanes.steps[finished].tolist()
                timeouts = truncated[finished].tolist()
                for j, i in enumerate(finished.tolist()):
                    info = infos[i]
                    info["terminal_observation"] = terminal[j]
                    info["TimeLimit.truncated"] = timeouts[j]
                    info["episode"] = {"r": returns[j], "l": lengths[j], "t": elapsed}
                self._returns[finished] = 0.0
                obs[finished] = self._start(finished)
        return obs, reward.astype(np.float32), dones, infos

    def _start(self, lanes: np.ndarray) -> np.ndarray:
        obs = self._lanes.reset(lanes)
        for i in lanes.tolist():
            self._player_types[i] = self._lanes.player_type(i)
        return obs

    def get_images(self) -> Sequence[np.ndarray | None]:
        if self.render_mode != "rgb_array":
            raise ValueError(f"get_images() needs render_mode='rgb_array', this env has {self.render_mode!r}")
        from robocup_dribble.render import DribbleRenderer

        if self._renderer is None:
            self._renderer = DribbleRenderer("rgb_array", fps=self.metadata["render_fps"])
        return [self._renderer.render(_frame(self._lanes, i, [], [])) for i in range(self.num_envs)]

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return [getattr(self, attr_name)] * len(self._get_indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **method_kwargs: Any) -> list[Any]:
        raise AttributeError(f"DribbleVecEnv has no per-lane sub-environments to call {method_name!r} on")

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        """Lanes are not wrapped, but they report SB3 ``Monitor``'s episode statistics, so ``Monitor`` answers True
        (SB3's ``evaluate_policy`` asks this to know whether ``info["episode"]`` is there)."""
        return [issubclass(wrapper_class, Monitor)] * len(self._get_indices(indices))
