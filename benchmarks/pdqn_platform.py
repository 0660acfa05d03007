"""
P-DQN / MP-DQN on Platform-v0 (PyPI ``hybrid-platform``): greedy mean return against env steps.

The hyperparameters are the reference MP-DQN code's Platform settings (``hyperparams/mpdqn.yml``), except the
training length: the reference trains 20,000 episodes; this script trains ``--steps`` env steps and evaluates the
greedy policy every ``--eval-every`` steps on ``--eval-episodes`` fresh episodes, then once more on
``--final-episodes`` (1,000 in the papers). It prints one line per evaluation and a final JSON line.

Usage: ``python -m benchmarks.pdqn_platform [--algo mpdqn|pdqn] [--steps 100000] [--seed 0]``
"""

from __future__ import annotations

import argparse
import json
import time

import gym_platform  # noqa: F401  (registers Platform-v0)
import gymnasium as gym
import numpy as np
import torch as th
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

from benchmarks.zoo_hyperparams import settings
from sb3_aac import MPDQN, PDQN, SelectObservation
from sb3_aac.common.checkpoints import GreedyCheckpoints


def make_env(seed: int, n_envs: int = 1):
    return make_vec_env(lambda: SelectObservation(gym.make("Platform-v0"), 0), n_envs=n_envs, seed=seed)


class GreedyEvaluation(GreedyCheckpoints):
    """Evaluates the greedy policy every ``every`` env steps and records (steps, episodes, mean return)."""

    def __init__(self, every: int, episodes: int, seed: int):
        eval_env = make_env(seed + 1000)
        super().__init__(every, lambda model: float(evaluate_policy(model, eval_env, episodes, deterministic=True)[0]))
        self.history: list[dict] = []

    def on_checkpoint(self, score: float) -> bool:
        row = dict(steps=self.num_timesteps, episodes=self.model.episode_num, mean_return=round(score, 4))
        self.history.append(row)
        print(json.dumps(row), flush=True)
        return True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[1])
    parser.add_argument("--algo", choices=["mpdqn", "pdqn"], default="mpdqn")
    parser.add_argument("--steps", type=int, default=100_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--exploration-fraction", type=float, default=0.1)
    parser.add_argument("--eval-every", type=int, default=10_000)
    parser.add_argument("--eval-episodes", type=int, default=100)
    parser.add_argument("--final-episodes", type=int, default=1000)
    args = parser.parse_args()
    th.set_num_threads(1)

    algo = MPDQN if args.algo == "mpdqn" else PDQN
    model = algo(
        "MlpPolicy",
        make_env(args.seed),
        seed=args.seed,
        device="cpu",
        **{**settings(args.algo, "Platform-v0"), "exploration_fraction": args.exploration_fraction},
    )
    evaluation = GreedyEvaluation(args.eval_every, args.eval_episodes, args.seed)
    start = time.perf_counter()
    model.learn(args.steps, callback=evaluation)
    seconds = time.perf_counter() - start
    returns, _ = evaluate_policy(
        model, make_env(args.seed + 2000), args.final_episodes, deterministic=True, return_episode_rewards=True
    )
    print(
        json.dumps(
            dict(
                algo=algo.__name__,
                seed=args.seed,
                env_steps=model.num_timesteps,
                episodes=model.episode_num,
                train_seconds=round(seconds, 1),
                final_mean_return=round(float(np.mean(returns)), 4),
                final_episodes=len(returns),
                history=evaluation.history,
            )
        )
    )


if __name__ == "__main__":
    main()
