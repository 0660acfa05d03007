"""
SarsaAAC on your own parameterized-action env: a tiny one defined here.

"Golf": the ball lies ``d`` metres from the hole (the observation). Each step the agent chooses a club and its
parameter: PUTT(strength in [0, 1], rolls 0..5 m) or DRIVE(strength in [0, 1], flies 0..40 m). The ball moves that
far (past the hole means overshooting); the episode ends in the hole (within 0.5 m) or after 5 shots. Reward: the
metres gained minus 1 per shot. Greedy optimum: drive when far, putt when close, with the strength that lands in the hole.

    python examples/custom_env.py [--steps 30000]
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

from sb3_aac import SarsaAAC

PUTT, DRIVE = 0, 1
REACH = (5.0, 40.0)  # metres at full strength


class GolfEnv(gym.Env):
    def __init__(self) -> None:
        self.observation_space = spaces.Box(0.0, 60.0, (1,), np.float32)
        # The canonical layout: a type, then one parameter Box per type.
        self.action_space = spaces.Tuple(
            (
                spaces.Discrete(2),
                spaces.Tuple((spaces.Box(0.0, 1.0, (1,), np.float32), spaces.Box(0.0, 1.0, (1,), np.float32))),
            )
        )
        self.distance, self.shots = 0.0, 0

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.distance, self.shots = float(self.np_random.uniform(5.0, 60.0)), 0
        return np.array([self.distance], np.float32), {}

    def step(self, action):
        club, strengths = action
        travel = REACH[club] * float(np.clip(strengths[club][0], 0.0, 1.0))
        before, self.distance = self.distance, abs(self.distance - travel)
        self.shots += 1
        holed = self.distance < 0.5
        reward = before - self.distance - 1.0 + (5.0 if holed else 0.0)
        obs = np.array([min(self.distance, 60.0)], np.float32)
        return obs, reward, holed, self.shots >= 5 and not holed, {"distance": self.distance}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=30_000)
    args = parser.parse_args()
    env = make_vec_env(GolfEnv, n_envs=4, seed=0)
    model = SarsaAAC("RbfPolicy", env, policy_kwargs=dict(n_rbf=20), info_keywords=("distance",), seed=0)
    before, _ = evaluate_policy(model, make_vec_env(GolfEnv, seed=1), n_eval_episodes=200)
    model.learn(args.steps)
    after, _ = evaluate_policy(model, make_vec_env(GolfEnv, seed=1), n_eval_episodes=200)
    print(f"mean return over 200 greedy episodes: {before:.1f} untrained, {after:.1f} after {args.steps} steps")
    for d in (3.0, 20.0, 45.0):
        (club, strengths), _ = model.predict(np.array([d], np.float32), deterministic=True)
        print(f"  {d:4.0f} m from the hole: {('PUTT', 'DRIVE')[club]} at strength {float(strengths[club][0]):.2f}")


if __name__ == "__main__":
    main()
