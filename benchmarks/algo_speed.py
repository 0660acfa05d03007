"""
Training throughput (env steps per second) of SarsaAAC next to SB3's PPO and DQN on the dribbling env, and
single-observation ``predict`` latency next to DQN's.

All three learn ``RoboCupDribblePaper-v0`` (or ``--env``) in SB3's ``DummyVecEnv`` with the same number of envs:
SarsaAAC on the env's own Tuple actions, PPO through :class:`sb3_aac.FlattenParameterizedAction` (a Box) and DQN
through :class:`sb3_aac.DiscretizeParameterizedAction` (a Discrete grid). A last column gives SarsaAAC on the batched
:class:`robocup_dribble.DribbleVecEnv` with the same number of lanes, which is how the dribbling env is meant to be
trained.

Usage: ``python benchmarks/algo_speed.py [--steps 20000] [--n-envs 1 4 16] [--policy RbfPolicy] [--torch-threads 1]``

Single runs on a shared machine: repeat them, and report the load average next to the numbers.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import gymnasium as gym
import numpy as np
import torch as th
from stable_baselines3 import DQN, PPO
from stable_baselines3.common.env_util import make_vec_env

import robocup_dribble
from sb3_aac import DiscretizeParameterizedAction, FlattenParameterizedAction, SarsaAAC


def build(algo: str, env_id: str, n_envs: int, policy: str):
    if algo == "SarsaAAC":
        return SarsaAAC(policy, make_vec_env(env_id, n_envs=n_envs, seed=0), seed=0)
    if algo == "SarsaAAC+DribbleVecEnv":
        profile = gym.spec(env_id).kwargs["profile"]
        return SarsaAAC(policy, robocup_dribble.DribbleVecEnv(n_envs, profile=profile), seed=0)
    if algo == "PPO":
        # Defaults, with the rollout kept at 2048 transitions whatever the number of envs.
        env = make_vec_env(env_id, n_envs=n_envs, seed=0, wrapper_class=FlattenParameterizedAction)
        return PPO("MlpPolicy", env, n_steps=max(2048 // n_envs, 64), seed=0, device="cpu")
    env = make_vec_env(env_id, n_envs=n_envs, seed=0, wrapper_class=DiscretizeParameterizedAction)
    return DQN("MlpPolicy", env, buffer_size=100_000, seed=0, device="cpu")


def steps_per_second(algo: str, env_id: str, n_envs: int, steps: int, policy: str) -> float:
    model = build(algo, env_id, n_envs, policy)
    model.learn(min(1000, steps))  # warm-up: compiled kernels, first allocations
    start = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    return steps / (time.perf_counter() - start)


def predict_microseconds(model, obs: np.ndarray, repeats: int = 2000) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        model.predict(obs, deterministic=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times) * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="RoboCupDribblePaper-v0", help="a registered dribbling env id")
    parser.add_argument("--steps", type=int, default=20_000, help="env steps per training measurement")
    parser.add_argument("--n-envs", type=int, nargs="+", default=[1, 4, 16])
    parser.add_argument("--policy", default="RbfPolicy", help="SarsaAAC policy")
    parser.add_argument(
        "--torch-threads", type=int, default=1, help="torch threads for PPO/DQN (1 is fastest at these sizes on a busy box)"
    )
    args = parser.parse_args()
    th.set_num_threads(args.torch_threads)
    print(f"{args.env}; torch threads {th.get_num_threads()}; {args.steps} steps per measurement; SarsaAAC {args.policy}; "
          f"load average {os.getloadavg()[0]:.1f}")
    algos = ("SarsaAAC", "PPO", "DQN", "SarsaAAC+DribbleVecEnv")
    print(f"{'n_envs':>6} {'SarsaAAC':>10} {'PPO':>8} {'DQN':>8} {'vs PPO':>7} {'vs DQN':>7} {'SarsaAAC+DribbleVecEnv':>23}"
          "   (env steps/s)")
    for n_envs in args.n_envs:
        rates = {algo: steps_per_second(algo, args.env, n_envs, args.steps, args.policy) for algo in algos}
        print(
            f"{n_envs:>6} {rates['SarsaAAC']:>10.0f} {rates['PPO']:>8.0f} {rates['DQN']:>8.0f} "
            f"{rates['SarsaAAC'] / rates['PPO']:>6.1f}x {rates['SarsaAAC'] / rates['DQN']:>6.1f}x "
            f"{rates['SarsaAAC+DribbleVecEnv']:>23.0f} ({rates['SarsaAAC+DribbleVecEnv'] / rates['PPO']:.1f}x PPO)",
            flush=True,
        )
    obs = gym.make(args.env).reset(seed=0)[0]
    sarsa, dqn = build("SarsaAAC", args.env, 1, args.policy), build("DQN", args.env, 1, args.policy)
    print(
        f"predict (one observation, deterministic, median of 2000): "
        f"SarsaAAC {predict_microseconds(sarsa, obs):.1f} us, DQN {predict_microseconds(dqn, obs):.1f} us"
    )


if __name__ == "__main__":
    main()
