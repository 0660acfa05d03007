"""A navigation task whose value depends on combinations of inputs (heading relative to the target direction)."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces


class NavigationEnv(gym.Env):
    """
    ## Description
    An agent at ``p`` in the square ``[-1, 1]^2`` with heading ``theta`` must reach a target ``t``. It can turn to
    face any direction, or move forward along its heading. Whether moving helps depends on the heading *relative
    to* the target direction, ``cos(theta - atan2(t - p))``, a function of several inputs together that per-input
    features (sums of functions of one input) cannot represent.

    ## Action Space
    ``Tuple(Discrete(2), Tuple(Box(-pi, pi, (1,)), Box(0, max_move, (1,))))``: type 0 "turn" sets the heading to
    its parameter (radians, absolute); type 1 "move" goes forward by its parameter (clipped to the square).

    ## Observation Space
    ``Box(-1, 1, (4,), float32)``: the target's offset ``(t - p) / 2`` and ``(cos theta, sin theta)``.

    ## Rewards
    ``progress_weight * (d_before - d_after)`` per step (``d`` the distance to the target), ``-step_cost`` per step,
    and ``+1`` on reaching the target (``d < radius``).

    ## Episode End
    1. Termination: the target is reached (``info["is_success"] = True``).
    2. Truncation: after ``max_episode_steps`` steps.

    ``info`` holds ``"distance"`` (the distance to the target) and ``"is_success"``. Starting points, targets and
    headings are uniform; a random policy succeeds in a few percent of episodes, and two decisions (turn, then
    move) reach any target within ``max_move`` (three or more for farther ones).

    ## Arguments
    :param max_episode_steps: Steps before truncation
    :param radius: Distance at which the target counts as reached
    :param max_move: Longest move of one step
    :param progress_weight: Reward per unit of distance gained
    :param step_cost: Reward subtracted every step
    """

    metadata: dict[str, Any] = {"render_modes": []}  # noqa: RUF012

    def __init__(
        self,
        max_episode_steps: int = 20,
        radius: float = 0.15,
        max_move: float = 1.0,
        progress_weight: float = 0.5,
        step_cost: float = 0.01,
    ):
        if not (isinstance(max_episode_steps, int) and max_episode_steps >= 1):  # type: ignore[redundant-expr]
            raise ValueError(f"max_episode_steps must be an int >= 1, got {max_episode_steps!r}")
        for name, value in (("radius", radius), ("max_move", max_move)):
            if not (isinstance(value, (int, float)) and 0 < value < math.inf):  # type: ignore[redundant-expr]
                raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
        for name, value in (("progress_weight", progress_weight), ("step_cost", step_cost)):
            if not (isinstance(value, (int, float)) and math.isfinite(value)):  # type: ignore[redundant-expr]
                raise ValueError(f"{name} must be a finite number, got {value!r}")
        self.max_episode_steps, self.radius, self.max_move = max_episode_steps, radius, max_move
        self.progress_weight, self.step_cost = progress_weight, step_cost
        turn = spaces.Box(-math.pi, math.pi, (1,), np.float32)
        move = spaces.Box(0.0, max_move, (1,), np.float32)
        self.action_space = spaces.Tuple((spaces.Discrete(2), spaces.Tuple((turn, move))))
        self.observation_space = spaces.Box(-1.0, 1.0, (4,), np.float32)
        self._position = np.zeros(2)
        self._target = np.zeros(2)
        self._heading = 0.0
        self._steps = 0

    def _observation(self) -> np.ndarray:
        offset = (self._target - self._position) / 2
        return np.array([*offset, math.cos(self._heading), math.sin(self._heading)], np.float32)

    def _distance(self) -> float:
        return float(np.hypot(*(self._target - self._position)))

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self._steps = 0
        self._position = self.np_random.uniform(-1.0, 1.0, 2)
        self._target = self.np_random.uniform(-1.0, 1.0, 2)
        while self._distance() < self.radius:
            self._target = self.np_random.uniform(-1.0, 1.0, 2)
        self._heading = float(self.np_random.uniform(-math.pi, math.pi))
        return self._observation(), {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        k = int(action[0])
        if k not in (0, 1):
            raise ValueError(f"Action type must be 0 (turn) or 1 (move), got {action[0]!r}")
        value = float(np.ravel(action[1][k])[0])
        if not math.isfinite(value):
            raise ValueError(f"The parameter must be finite, got {value!r}")
        before = self._distance()
        if k == 0:
            self._heading = min(max(value, -math.pi), math.pi)
        else:
            length = min(max(value, 0.0), self.max_move)
            step = length * np.array([math.cos(self._heading), math.sin(self._heading)])
            self._position = np.clip(self._position + step, -1.0, 1.0)
        self._steps += 1
        after = self._distance()
        success = after < self.radius
        reward = self.progress_weight * (before - after) - self.step_cost + (1.0 if success else 0.0)
        truncated = self._steps >= self.max_episode_steps and not success
        return self._observation(), reward, success, truncated, {"distance": after, "is_success": success}
