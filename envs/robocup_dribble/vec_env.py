"""N dribbling lanes as one Stable-Baselines3 ``VecEnv`` (:class:`DribbleVecEnv`), with the array path.

This module imports SB3 (and so torch); :mod:`robocup_dribble.env` does not.
"""

from __future__ import annotations

import gc
import time
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvObs, VecEnvStepReturn

from robocup_dribble import skills
from robocup_dribble.env import DribbleEnv, configure, parse_action, render_frame
from robocup_dribble.lanes import DribbleLanes
from robocup_dribble.params import ServerProfile


class ArrayStep(NamedTuple):
    """One step of all N lanes from :meth:`DribbleVecEnv.step_arrays`.

    It has the field names and meanings of ``sb3_aac.common.array_env.ArrayStep`` (this package does not import
    ``sb3_aac``), so :class:`DribbleVecEnv` satisfies that array-path protocol. Rows marked "where ended" are
    meaningful only where ``terminated | truncated`` (zero elsewhere).
    """

    observations: np.ndarray
    """``(N, 10)`` float32: the next observations (the next episode's first one where ended)."""
    rewards: np.ndarray
    """``(N,)`` float64: this step's rewards."""
    terminated: np.ndarray
    """``(N,)`` bool: the ball was lost (a terminal state)."""
    truncated: np.ndarray
    """``(N,)`` bool: ``max_actions`` reached with the ball."""
    terminal_observations: np.ndarray
    """``(N, 10)`` float32: the episode's last observation, where ended."""
    episode_returns: np.ndarray
    """``(N,)`` float64: the episode's undiscounted return, where ended."""
    episode_lengths: np.ndarray
    """``(N,)`` int64: the episode's number of actions, where ended."""
    episode_info: Mapping[str, np.ndarray]
    """``"distance"`` (metres dribbled along +x, frozen at the last step with the ball) and ``"ball_lost"``
    (``(N,)`` bool), where ended."""


class LaneVecEnv(VecEnv):
    """What every lane-based ``VecEnv`` of the env packages shares: SB3's ``VecEnv`` methods over lanes that step in
    one call (no sub-environments), one seed for all lanes, and :meth:`step_packed`, SB3's return built from a
    subclass's :meth:`step_arrays`.

    A subclass sets ``_action_params`` (each action type's parameter names), implements :meth:`step_arrays` and
    :meth:`_infos` (the per-lane ``info`` dicts of a step), may override :meth:`_episode_started` (called for each
    lane whose episode ended and restarted), and sets ``_started`` in ``reset``.
    """

    _action_params: tuple[tuple[str, ...], ...]
    _started = False
    _t_start = 0.0
    _actions: np.ndarray | Sequence[Any] | None = None

    def step_async(self, actions: np.ndarray | Sequence[Any]) -> None:
        self._actions = actions

    def step_wait(self) -> VecEnvStepReturn:
        actions, self._actions = self._actions, None
        if actions is None or len(actions) != self.num_envs:
            got = None if actions is None else len(actions)
            raise ValueError(f"step() needs one action per lane ({self.num_envs}), got {got}")
        return self.step_packed(*parse_actions(actions, self._action_params))

    def step_arrays(self, action_types: np.ndarray, params: np.ndarray) -> ArrayStep:
        raise NotImplementedError

    def _infos(self, step: ArrayStep) -> list[dict[str, Any]]:
        raise NotImplementedError

    def _episode_started(self, lane: int) -> None:
        """Lane ``lane`` ended an episode and started the next one (nothing to do by default)."""

    def step_packed(self, action_types: np.ndarray, params: np.ndarray) -> VecEnvStepReturn:
        """:meth:`step_arrays` with SB3's return: ``(obs, rewards float32, dones, infos)``."""
        step = self.step_arrays(action_types, params)
        dones = step.terminated | step.truncated
        finished = np.flatnonzero(dones).tolist()
        # Thousands of fresh dicts per step would otherwise set off collector passes over every live object;
        # none of them forms a reference cycle, so the collector is paused while they are made.
        collecting = gc.isenabled()
        gc.disable()
        try:
            infos = self._infos(step)
            if finished:
                elapsed = round(time.time() - self._t_start, 6)
                returns = step.episode_returns[finished].tolist()
                lengths = step.episode_lengths[finished].tolist()
                timeouts = step.truncated[finished].tolist()
                for j, i in enumerate(finished):
                    info = infos[i]
                    info["terminal_observation"] = step.terminal_observations[i]
                    info["TimeLimit.truncated"] = timeouts[j]
                    info["episode"] = {"r": returns[j], "l": lengths[j], "t": elapsed}
                    self._episode_started(i)
        finally:
            if collecting:
                gc.enable()
        return step.observations, step.rewards.astype(np.float32), dones, infos

    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Seed the lanes' generator with ``seed`` (an int, or None for a random one) at the next ``reset``.

        :raises ValueError: for anything but an int or None (lanes take one seed, not one per lane)
        """
        # A run-time check of user input that the annotation cannot guarantee.
        if not (seed is None or (isinstance(seed, (int, np.integer)) and not isinstance(seed, bool))):  # type: ignore[redundant-expr]
            raise ValueError(f"seed must be an int or None (the lanes share one generator), got {seed!r}")
        return super().seed(None if seed is None else int(seed))

    def _get_indices(self, indices: VecEnvIndices) -> Iterable[int]:
        """SB3's lane indices, checked: ``IndexError`` for one outside ``-n_envs .. n_envs - 1``."""
        chosen = list(super()._get_indices(indices))
        outside = [i for i in chosen if not -self.num_envs <= i < self.num_envs]
        if outside:
            raise IndexError(f"lane indices {outside} are out of range for {self.num_envs} lanes (0 .. {self.num_envs - 1})")
        return chosen

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return [getattr(self, attr_name)] * len(list(self._get_indices(indices)))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **method_kwargs: Any
    ) -> list[Any]:
        raise AttributeError(f"{type(self).__name__} has no per-lane sub-environments to call {method_name!r} on")

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        """Lanes are not wrapped, but they report SB3 ``Monitor``'s episode statistics, so ``Monitor`` answers True
        (SB3's ``evaluate_policy`` asks this to know whether ``info["episode"]`` is there)."""
        return [issubclass(wrapper_class, Monitor)] * len(list(self._get_indices(indices)))

    def _check_started(self) -> None:
        if not self._started:
            raise ValueError(f"Call reset() before stepping or rendering a {type(self).__name__}: no episode has started")


class DribbleVecEnv(LaneVecEnv):
    """``n_envs`` dribbling lanes stepped by one compiled call: a Stable-Baselines3 ``VecEnv``.

    Same physics, task and arguments (``perception`` included) as :class:`robocup_dribble.env.DribbleEnv` (one code path:
    :class:`robocup_dribble.lanes.DribbleLanes`); with ``n_envs=1`` and the same seed it produces the same episodes.
    Finished lanes reset automatically, inside the compiled step. All lanes draw from one generator seeded by
    :meth:`seed` (the first seed).

    Three ways to step, giving the same transitions:

    * :meth:`step_arrays` (the array path of ``sb3_aac.common.array_env``): ``(N,)`` action types and ``(N, 7)``
      parameters in, an :class:`ArrayStep` of arrays out; no per-lane Python object at all.
    * :meth:`step_packed`: the same arrays in, SB3's ``(obs, rewards, dones, infos)`` out.
    * :meth:`step` (SB3's form): a sequence of N per-lane Tuple actions in, SB3's return out. ``infos[i]`` carry
      ``distance``, ``ball_lost`` and ``player_type``, and where an episode ended ``terminal_observation``,
      ``TimeLimit.truncated`` and, like SB3's ``VecMonitor``, ``episode = {"r", "l", "t"}``.
    """

    metadata = DribbleEnv.metadata
    _action_params = skills.ACTION_PARAMS

    def __init__(
        self,
        n_envs: int,
        profile: str | ServerProfile = "v19",
        noise: bool = True,
        render_mode: str | None = None,
        perception: str = "full",
        **task_kwargs: Any,
    ) -> None:
        self.profile, self.task = configure(profile, noise, render_mode, task_kwargs)
        self._lanes = DribbleLanes(n_envs, self.profile, self.task, seeding.np_random()[0], perception)
        self.render_mode = render_mode
        super().__init__(n_envs, self._lanes.observation_space, skills.action_space(self.profile))
        self.metadata = dict(DribbleEnv.metadata)  # VecEnv.__init__ replaced it with one lacking render_fps
        self._all = np.arange(self.num_envs)
        self._t_start = time.time()
        self._player_types: list[Any] = [None] * self.num_envs
        self._renderer: Any = None

    def reset(self) -> VecEnvObs:
        if self._seeds[0] is not None:
            self._lanes.reseed(seeding.np_random(self._seeds[0])[0])
        self._reset_seeds()
        obs = self._lanes.reset(self._all)
        self._player_types = [self._lanes.player_type(i) for i in range(self.num_envs)]
        self._started = True
        return obs

    def step_arrays(self, action_types: np.ndarray, params: np.ndarray) -> ArrayStep:
        """Step all lanes with ``(N,)`` action types and ``(N, 7)`` parameters (``robocup_dribble.skills.PARAM_*``
        columns, env units; out-of-range values are clipped); lanes whose episode ended start the next one.

        :raises ValueError: for a wrong shape, an action type outside 0..3, a non-finite parameter, or a call before
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
            {"distance": out.distances, "ball_lost": out.terminated},
        )

    def _infos(self, step: ArrayStep) -> list[dict[str, Any]]:
        distances, lost = step.episode_info["distance"].tolist(), step.terminated.tolist()
        return [
            {"distance": d, "ball_lost": b, "player_type": t}
            for d, b, t in zip(distances, lost, self._player_types, strict=True)
        ]

    def _episode_started(self, lane: int) -> None:
        self._player_types[lane] = self._lanes.player_type(lane)

    def get_images(self) -> Sequence[np.ndarray | None]:
        if self.render_mode != "rgb_array":
            raise ValueError(f"get_images() needs render_mode='rgb_array', this env has {self.render_mode!r}")
        self._check_started()
        renderer = self._renderer_for("rgb_array")
        return [renderer.render(render_frame(self._lanes, i, [], [])) for i in range(self.num_envs)]

    def render(self, mode: str | None = None) -> np.ndarray | None:
        """``"rgb_array"``: all lanes' frames tiled into one image (SB3's ``VecEnv.render``); ``"human"``: lane 0 in
        a window."""
        if self.render_mode == "human" and mode in (None, "human"):
            self._check_started()
            self._renderer_for("human").render(render_frame(self._lanes, 0, [], []))
            return None
        return super().render(mode)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def _renderer_for(self, mode: str) -> Any:
        from robocup_dribble.render import DribbleRenderer

        if self._renderer is None:
            self._renderer = DribbleRenderer(mode, fps=self.metadata["render_fps"])
        return self._renderer


def parse_actions(
    actions: np.ndarray | Sequence[Any], action_params: tuple[tuple[str, ...], ...] = skills.ACTION_PARAMS
) -> tuple[np.ndarray, np.ndarray]:
    """N per-lane Tuple actions -> ``(N,)`` int64 action types and ``(N, P)`` parameters, for action types whose
    parameters are named by ``action_params`` (by default the dribbling skills': P = 7).

    The common case (integer types, real numpy parameter vectors of one dtype and the right sizes, as SB3 policies
    and the action space give them) is read in one pass over the vectors' bytes; anything else goes through
    :func:`robocup_dribble.env.parse_action` lane by lane, which converts what it can and names what is wrong. (The
    action types' range is checked with the parameters, by the lanes.)
    """
    try:
        kind_list = [action[0] for action in actions]
        kinds = np.array(kind_list)
        kind_types = set(map(type, kind_list))
        parts = [part for action in actions for part in action[1]]
        dtypes = {part.dtype for part in parts}
        if kinds.dtype.kind in "iu" and bool not in kind_types and np.bool_ not in kind_types and len(dtypes) == 1:
            dtype = dtypes.pop()
            sizes = [len(names) for names in action_params]
            expected = [dtype.itemsize * size for size in sizes] * len(actions)
            if dtype.kind == "f" and [part.nbytes for part in parts] == expected:
                joined = b"".join(parts)  # the vectors' buffers (a non-contiguous one raises BufferError)
                params = np.frombuffer(joined, dtype=dtype).reshape(len(actions), sum(sizes))
                return kinds.astype(np.int64, copy=False), params.astype(np.float64)
    except (TypeError, ValueError, AttributeError, IndexError, KeyError, BufferError):
        pass
    parsed = [parse_action(action, action_params) for action in actions]
    return np.array([k for k, _ in parsed], dtype=np.int64), np.stack([p for _, p in parsed])
