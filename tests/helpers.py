"""Shared test constants and tiny envs (imported by the test modules)."""

import gymnasium as gym
import numpy as np
from gymnasium import spaces

POLICIES = ["MlpPolicy", "RbfMlpPolicy", "RbfPolicy", "TilePolicy", "DeepPolicy"]
LAYOUTS = ["nested", "flat", "shared", "oneof"]


class OneStepEnv(gym.Env):
    """Constant observation, reward 1, every episode ends after one step: terminated, or truncated (time limit)."""

    def __init__(self, truncate: bool, obs: float = 0.0, reward: float = 1.0):
        self.truncate, self.obs, self.reward = truncate, np.array([obs], np.float32), reward
        self.observation_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.action_space = spaces.Tuple((spaces.Discrete(2), spaces.Box(-1.0, 1.0, (1,), np.float32)))

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return self.obs.copy(), {}

    def step(self, action):
        return self.obs.copy(), self.reward, not self.truncate, self.truncate, {}
