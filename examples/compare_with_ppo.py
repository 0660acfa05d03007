"""
SarsaAAC against PPO on the dribbling env, with the same number of steps and the same evaluation.

PPO cannot take the env's Tuple action space; ``sb3_aac.FlattenParameterizedAction`` turns it into a
``Box(K + n_params)`` (type scores, then every type's scaled parameters; the env runs the argmax type). Both are
then measured greedily on the same fresh heterogeneous players.

    python examples/compare_with_ppo.py            # 100,000 steps each: a few minutes
    python examples/compare_with_ppo.py --quick    # seconds, to check the pipeline
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env

import robocup_dribble  # noqa: F401  (registers the env ids)
from robocup_dribble import DribbleVecEnv
from robocup_dribble.evaluation import evaluate_dribbling
from sb3_aac import FlattenParameterizedAction, SarsaAAC
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.wrappers import scores_to_action

ENV_ID, PROFILE = "RoboCupDribblePaper-v0", "v11"


class FlatActionsToTuples:
    """Give a model trained through FlattenParameterizedAction the ``predict`` of the Tuple-action env."""

    def __init__(self, model: Any, spec: ParameterizedActionSpec):
        self.model, self.spec = model, spec

    def predict(self, obs: np.ndarray, state: Any = None, episode_start: Any = None, deterministic: bool = True):
        flat, _ = self.model.predict(obs, deterministic=deterministic)
        k, params = scores_to_action(np.atleast_2d(flat), self.spec.n_types)
        actions = self.spec.to_env(k, params)
        return (actions if np.ndim(obs) > 1 else actions[0]), state


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a tiny budget")
    parser.add_argument("--steps", type=int, default=100_000, help="training steps for each algorithm")
    args = parser.parse_args()
    steps, episodes = (2_048, 100) if args.quick else (args.steps, 1_000)

    env = DribbleVecEnv(16, profile=PROFILE)
    env.seed(0)
    sarsa = SarsaAAC("RbfPolicy", env, seed=0).learn(steps)

    ppo_env = make_vec_env(ENV_ID, n_envs=8, seed=0, wrapper_class=FlattenParameterizedAction)
    ppo = PPO("MlpPolicy", ppo_env, n_steps=256, seed=0, device="cpu").learn(steps)
    spec = ParameterizedActionSpec.from_space(env.action_space)

    for name, policy in (("SarsaAAC RbfPolicy", sarsa), ("PPO + FlattenParameterizedAction", FlatActionsToTuples(ppo, spec))):
        report = evaluate_dribbling(policy, episodes, profile=PROFILE, seed=1)
        print(f"{name:34s} {report.summary()}")


if __name__ == "__main__":
    main()
