"""What the reference MP-DQN code (cycraig/MP-DQN, ``run_goal_pdqn.py``) feeds its agent on Goal-v0, as wrappers.

Facts taken from cycraig/MP-DQN (commit eec13eb): ``common/goal_domain.py`` ``GoalObservationWrapper`` (three
features appended to the 14 state variables: the unit vector from the keeper to the ball, and the keeper's projection
from the ball onto the goal line) and the agent's ``reward_scale`` of 1/50. The code is ours.
"""

from __future__ import annotations

import math
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np

from hybrid_domains.actions import float32_box
from hybrid_domains.goal import GOAL_WIDTH, PITCH_LENGTH

FEATURE_NAMES = ("ball_from_keeper_x", "ball_from_keeper_y", "keeper_goal_line_y")


def keeper_projection(state: np.ndarray) -> float:
    """Where the line from the ball through the keeper meets the goal line (x = 20), clipped to [-7.01, 14.02] (sic:
    the reference clips with ``GOAL_WIDTH`` above, not ``GOAL_WIDTH / 2``); ``-/+7.01`` if the line is vertical."""
    keeper_x, keeper_y, ball_x, ball_y = (float(v) for v in state[[5, 6, 10, 11]])
    if keeper_x == ball_x:
        return -GOAL_WIDTH / 2 if keeper_y < ball_y else GOAL_WIDTH / 2
    grad = (keeper_y - ball_y) / (keeper_x - ball_x)
    return min(max(grad * PITCH_LENGTH / 2 + ball_y - grad * ball_x, -GOAL_WIDTH / 2), GOAL_WIDTH)


class GoalFeatures(gym.ObservationWrapper[np.ndarray, Any, Any]):
    """Goal-v0's observation as the reference MP-DQN agent sees it: the 14 state variables (the step count dropped)
    followed by :data:`FEATURE_NAMES`, a ``Box(17)``. The keeper-to-ball vector is normalised (0 if they coincide)."""

    def __init__(self, env: gym.Env[Any, Any]) -> None:
        super().__init__(env)
        box = env.observation_space[0]  # type: ignore[index]
        self.observation_space = float32_box([*box.low, -1.0, -1.0, -GOAL_WIDTH / 2], [*box.high, 1.0, 1.0, GOAL_WIDTH])

    def observation(self, observation: Any) -> np.ndarray:
        state = np.asarray(observation[0], dtype=np.float64)
        dx, dy = state[10] - state[5], state[11] - state[6]
        length = math.hypot(dx, dy)
        unit = (dx / length, dy / length) if length > 0 else (0.0, 0.0)
        return np.concatenate([state, unit, [keeper_projection(state)]]).astype(np.float32)


class ScaleReward(gym.RewardWrapper[Any, Any]):
    """Multiply every reward by ``scale`` (the reference code trains on Goal with 1/50, so a goal is worth 1)."""

    def __init__(self, env: gym.Env[Any, Any], scale: float = 1.0 / 50.0) -> None:
        if not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):  # type: ignore[redundant-expr]
            raise ValueError(f"scale must be a positive finite number, got {scale!r}")
        super().__init__(env)
        self.scale = float(scale)

    def reward(self, reward: SupportsFloat) -> float:
        return float(reward) * self.scale
