"""
Training throughput (env steps per second) of SarsaAAC next to SB3's PPO and DQN, and single-observation
``predict`` latency next to DQN's.

All three learn the same toy env, :class:`~sb3_aac.common.envs.ParameterizedTargetEnv` (action checks off). PPO and
DQN cannot take its Tuple actions, so this script flattens them just for the comparison:

- PPO: ``Box(K + n_params)``; the type is the argmax of the first K entries, the rest are the scaled parameters;
- DQN: ``Discrete``; each type's parameters on a 3-point grid per coordinate ({-0.5, 0, 0.5} scaled).

These stand-ins will be replaced by the dribbling env and the project's action wrappers.

Usage: ``python benchmarks/algo_speed.py [--steps 20000] [--n-envs 1 4 16] [--policy RbfPolicy] [--torch-threads 1]``

Single runs on a shared machine: repeat them, and report the load average next to the numbers.
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import time

import gymnasium as gym
import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3 import DQN, PPO
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac import SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.common.spaces import ParameterizedActionSpec


class BoxActions(gym.ActionWrapper):
    """Type = argmax of the first K entries, then the scaled parameters of every type."""

    def __init__(self, env: gym.Env):
        super().__init__(env)
        self.param_spec = ParameterizedActionSpec.from_space(env.action_space)
        n = self.param_spec.n_types + self.param_spec.n_params
        self.action_space = spaces.Box(-1.0, 1.0, (n,), np.float32)

    def action(self, action: np.ndarray) -> tuple:
        n_types = self.param_spec.n_types
        return self.param_spec.to_env_single(int(np.argmax(action[:n_types])), action[n_types:])


class DiscreteActions(gym.ActionWrapper):
    """Every type with its parameters on a 3-point grid per coordinate."""

    def __init__(self, env: gym.Env):
        super().__init__(env)
        spec = self.param_spec = ParameterizedActionSpec.from_space(env.action_space)
        self.table = []
        for k in range(spec.n_types):
            for values in itertools.product((-0.5, 0.0, 0.5), repeat=spec.dims[k]):
                params = np.zeros(spec.n_params)
                params[spec.type_slice(k)] = values
                self.table.append((k, params))
        self.action_space = spaces.Discrete(len(self.table))

    def action(self, action: int) -> tuple:
        return self.param_spec.to_env_single(*self.table[int(action)])


def make_env(wrapper: type[gym.ActionWrapper] | None, n_envs: int):
    def env_fn() -> gym.Env:
        env = ParameterizedTargetEnv("nested", check_action=False)
        return env if wrapper is None else wrapper(env)

    return make_vec_env(env_fn, n_envs=n_envs, seed=0)


def build(algo: str, n_envs: int, policy: str):
    if algo == "SarsaAAC":
        return SarsaAAC(policy, make_env(None, n_envs), seed=0)
    if algo == "PPO":
        # Defaults, with the rollout kept at 2048 transitions whatever the number of envs.
        return PPO("MlpPolicy", make_env(BoxActions, n_envs), n_steps=max(2048 // n_envs, 64), seed=0, device="cpu")
    return DQN("MlpPolicy", make_env(DiscreteActions, n_envs), buffer_size=100_000, seed=0, device="cpu")


def steps_per_second(algo: str, n_envs: int, steps: int, policy: str) -> float:
    model = build(algo, n_envs, policy)
    start = time.perf_counter()
    model.learn(steps)
    return model.num_timesteps / (time.perf_counter() - start)


def predict_microseconds(model, obs: np.ndarray, repeats: int = 2000) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        model.predict(obs, deterministic=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times) * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=20_000, help="env steps per training measurement")
    parser.add_argument("--n-envs", type=int, nargs="+", default=[1, 4, 16])
    parser.add_argument("--policy", default="RbfPolicy", help="SarsaAAC policy")
    parser.add_argument(
        "--torch-threads", type=int, default=1, help="torch threads for PPO/DQN (1 is fastest at these sizes on a busy box)"
    )
    args = parser.parse_args()
    th.set_num_threads(args.torch_threads)
    print(f"torch threads: {th.get_num_threads()}, steps per measurement: {args.steps}, SarsaAAC policy: {args.policy}")
    print(f"{'n_envs':>6} {'SarsaAAC':>10} {'PPO':>8} {'DQN':>8} {'vs PPO':>7} {'vs DQN':>7}   (env steps/s)")
    for n_envs in args.n_envs:
        rates = {algo: steps_per_second(algo, n_envs, args.steps, args.policy) for algo in ("SarsaAAC", "PPO", "DQN")}
        print(
            f"{n_envs:>6} {rates['SarsaAAC']:>10.0f} {rates['PPO']:>8.0f} {rates['DQN']:>8.0f} "
            f"{rates['SarsaAAC'] / rates['PPO']:>6.1f}x {rates['SarsaAAC'] / rates['DQN']:>6.1f}x",
            flush=True,
        )
    obs = ParameterizedTargetEnv().reset(seed=0)[0]
    sarsa, dqn = build("SarsaAAC", 1, args.policy), build("DQN", 1, args.policy)
    print(
        f"predict (one observation, deterministic, median of 2000): "
        f"SarsaAAC {predict_microseconds(sarsa, obs):.1f} us, DQN {predict_microseconds(dqn, obs):.1f} us"
    )


if __name__ == "__main__":
    main()
