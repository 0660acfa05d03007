"""A small parameterized-action environment with a known optimum, for tests and benchmarks."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from sb3_aac.runtime.actions import LAYOUTS


class ParameterizedTargetEnv(gym.Env):
    """
    ## Description
    Each step shows a random point ``s`` of the square ``[-1, 1]^2``. The agent picks an action type ``k`` and its
    parameters. One type is best in each vertical band of the square, and each type's parameters should hit a
    target that depends on ``s``. The next point is drawn independently of the action, so the optimal policy is
    greedy and known in closed form (:meth:`best_type`, :meth:`target`).

    ## Action Space
    ``n_types`` action types; type 0 has 1 parameter, every other type 2. Per-type bounds (deliberately different,
    to exercise scaling): type 0 ``[-2, 2]``; type 1 ``[0, 1] x [0, 10]``; types >= 2 ``[-1, 1]^2``. The ``layout``
    argument chooses how this is declared (see :mod:`sb3_aac.common.spaces`): ``"nested"``, ``"flat"``, ``"oneof"``,
    or ``"shared"`` (one ``Box(2)`` with bounds ``[-2, 2] x [0, 10]``; type 0 reads its first coordinate).

    ## Observation Space
    ``Box(-1, 1, (2,), float32)``, uniform.

    ## Rewards
    With ``p~`` the parameters of type ``k`` scaled to ``[-1, 1]`` and ``t_k(s)`` the target (also scaled):
    ``closeness = exp(-||p~ - t_k(s)||^2 / (2 * tolerance^2))``, reward ``closeness`` if ``k`` is the best type at
    ``s`` and ``wrong_type_weight * closeness`` otherwise. The best type is ``floor((s_0 + 1) / 2 * n_types)``
    (vertical bands); ``t_k(s) = 0.7 * (-1)^k * (s_1, -s_0)`` truncated to the type's dimension.

    ## Episode End
    1. Termination: ``closeness < loss_threshold`` ("ball lost"; reward as above, ``info["ball_lost"] = True``).
    2. Truncation: after ``max_episode_steps`` steps.

    The optimal return is ``max_episode_steps`` (reward 1 every step); a uniformly random policy gets about 0.1.
    ``info`` holds ``"distance"`` (the return so far) and ``"ball_lost"``, mirroring the dribbling env's keys.

    ## Arguments
    :param layout: How the action space is declared: ``"nested"``, ``"flat"``, ``"shared"`` or ``"oneof"``
    :param n_types: Number of action types K (>= 1)
    :param max_episode_steps: Steps before truncation
    :param tolerance: Width of the reward bump, in scaled parameter units
    :param wrong_type_weight: Reward factor for a type that is not the best one at ``s``
    :param loss_threshold: The episode terminates when ``closeness`` falls below this
    :param check_action: Raise a ValueError for actions outside the action space (``action_space.contains`` is
        most of the step's cost, so benchmarks turn it off)
    """

    metadata: dict[str, Any] = {"render_modes": []}  # noqa: RUF012

    def __init__(
        self,
        layout: str = "nested",
        n_types: int = 3,
        max_episode_steps: int = 10,
        tolerance: float = 0.3,
        wrong_type_weight: float = 0.3,
        loss_threshold: float = 0.05,
        check_action: bool = True,
    ):
        if layout not in LAYOUTS:
            raise ValueError(f"Unknown layout {layout!r}, valid layouts: {list(LAYOUTS)}")
        if n_types < 1:
            raise ValueError(f"n_types must be >= 1, got {n_types}")
        self.layout, self.n_types, self.max_episode_steps = layout, n_types, max_episode_steps
        self.tolerance, self.wrong_type_weight, self.loss_threshold = tolerance, wrong_type_weight, loss_threshold
        self.check_action = check_action
        self.dims = [1] + [2] * (n_types - 1)
        boxes = [self._box(k) for k in range(n_types)]
        shared = spaces.Box(np.array([-2.0, 0.0], np.float32), np.array([2.0, 10.0], np.float32))
        if layout == "nested":
            self.action_space = spaces.Tuple((spaces.Discrete(n_types), spaces.Tuple(boxes)))
        elif layout == "flat":
            self.action_space = spaces.Tuple((spaces.Discrete(n_types), *boxes))
        elif layout == "oneof":
            self.action_space = spaces.OneOf(boxes)
        else:
            self.action_space = spaces.Tuple((spaces.Discrete(n_types), shared))
        self.observation_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        # Bounds each type's parameters are read with: its own Box, or the shared one (first dims[k] coordinates).
        param_boxes = [shared] * n_types if layout == "shared" else boxes
        self._param_low = [box.low[:d].tolist() for box, d in zip(param_boxes, self.dims, strict=True)]
        self._param_high = [box.high[:d].tolist() for box, d in zip(param_boxes, self.dims, strict=True)]
        self._obs = np.zeros(2, np.float32)
        self._steps, self._distance = 0, 0.0

    @staticmethod
    def _box(k: int) -> spaces.Box:
        if k == 0:
            return spaces.Box(-2.0, 2.0, (1,), np.float32)
        if k == 1:
            return spaces.Box(np.array([0.0, 0.0], np.float32), np.array([1.0, 10.0], np.float32))
        return spaces.Box(-1.0, 1.0, (2,), np.float32)

    def best_type(self, obs: np.ndarray) -> int:
        """The best action type at ``obs`` (0-based)."""
        return min(self.n_types - 1, int((float(obs[0]) + 1) / 2 * self.n_types))

    def target(self, obs: np.ndarray, k: int) -> np.ndarray:
        """Type ``k``'s target parameters at ``obs``, scaled to ``[-1, 1]``, shape ``(dims[k],)``."""
        return np.array(self._target(float(obs[0]), float(obs[1]), k))

    def _target(self, x: float, y: float, k: int) -> list[float]:
        sign = 0.7 if k % 2 == 0 else -0.7
        return [sign * y, -sign * x][: self.dims[k]]

    def _scaled_params(self, action: Any) -> tuple[int, list[float]]:
        # Plain floats: this env is also the benchmark's, so its step should cost little next to the agent's.
        if self.layout in ("oneof", "shared"):
            k, value = int(action[0]), action[1]
        else:
            k = int(action[0])
            value = (action[1] if self.layout == "nested" else action[1:])[k]
        low, high = self._param_low[k], self._param_high[k]
        value = np.ravel(value).tolist()[: self.dims[k]]
        return k, [(v - (hi + lo) / 2) / ((hi - lo) / 2) for v, lo, hi in zip(value, low, high, strict=True)]

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self._steps, self._distance = 0, 0.0
        self._obs = self.np_random.uniform(-1.0, 1.0, 2).astype(np.float32)
        return self._obs, {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self.check_action and not self.action_space.contains(action):
            raise ValueError(f"{action!r} is not an element of {self.action_space}")
        k, params = self._scaled_params(action)
        x, y = self._obs.tolist()
        squared_error = sum((p - t) ** 2 for p, t in zip(params, self._target(x, y, k), strict=True))
        closeness = math.exp(-squared_error / (2 * self.tolerance**2))
        best = min(self.n_types - 1, int((x + 1) / 2 * self.n_types))
        reward = closeness if k == best else self.wrong_type_weight * closeness
        self._steps += 1
        self._distance += reward
        terminated = closeness < self.loss_threshold
        truncated = self._steps >= self.max_episode_steps and not terminated
        self._obs = self.np_random.uniform(-1.0, 1.0, 2).astype(np.float32)  # a new array: returning it is safe
        return self._obs, reward, terminated, truncated, {"distance": self._distance, "ball_lost": terminated}
