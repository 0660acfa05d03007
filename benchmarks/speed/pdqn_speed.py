"""
Training throughput (env steps per second) and single-observation ``predict`` latency of P-DQN and MP-DQN next to
SB3's TD3 and DQN, on the same env, machine and run.

P-DQN and MP-DQN act in the env's own Tuple actions; TD3 learns through :class:`sb3_aac.FlattenParameterizedAction`
(a Box) and DQN through :class:`sb3_aac.DiscretizeParameterizedAction` (a Discrete grid, 5 values per parameter), as
in the benchmark's baselines. All four take one gradient step per step of the vectorized env (``train_freq=1``,
``gradient_steps=1``: one per ``n_envs`` transitions) on minibatches of 128 with two hidden layers of 64 units, so the
figures compare the cost of the algorithms, not of their default settings.

Usage: ``python -m benchmarks.speed.pdqn_speed [--env RoboCupDribblePaper-v0] [--steps 5000] [--n-envs 1 16]``

Single runs on a shared machine: repeat them, and report the load average next to the numbers.

Note, for comparison: before the fast gradient steps (main at 337ec70; AMD EPYC, torch 2.13 CPU, load average 0.4),
``--n-envs 1`` gave P-DQN 355 and MP-DQN 229 env steps/s.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import torch as th
from stable_baselines3 import DQN, TD3
from stable_baselines3.common.env_util import make_vec_env

import robocup_dribble  # noqa: F401  (registers the env ids)
from benchmarks.speed.algo_speed import predict_microseconds
from benchmarks.speed.timing import load_average, steps_per_second
from sb3_aac import MPDQN, PDQN, DiscretizeParameterizedAction, FlattenParameterizedAction

ALGOS = ("PDQN", "MPDQN", "TD3", "DQN")
COMMON = dict(learning_starts=100, batch_size=128, train_freq=1, gradient_steps=1, seed=0, device="cpu")


def build(algo: str, env_id: str, n_envs: int):
    if algo in ("PDQN", "MPDQN"):
        cls = PDQN if algo == "PDQN" else MPDQN
        return cls("MlpPolicy", make_vec_env(env_id, n_envs=n_envs, seed=0), policy_kwargs=dict(net_arch=[64, 64]), **COMMON)
    if algo == "TD3":
        env = make_vec_env(env_id, n_envs=n_envs, seed=0, wrapper_class=FlattenParameterizedAction)
        return TD3("MlpPolicy", env, policy_kwargs=dict(net_arch=[64, 64]), **COMMON)
    env = make_vec_env(env_id, n_envs=n_envs, seed=0, wrapper_class=DiscretizeParameterizedAction)
    return DQN("MlpPolicy", env, policy_kwargs=dict(net_arch=[64, 64]), **COMMON)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[1])
    parser.add_argument("--env", default="RoboCupDribblePaper-v0", help="a registered parameterized-action env id")
    parser.add_argument("--steps", type=int, default=5000, help="env steps per training measurement")
    parser.add_argument("--n-envs", type=int, nargs="+", default=[1, 16])
    args = parser.parse_args()
    th.set_num_threads(1)
    print(f"{args.env}; torch threads 1; {args.steps} steps per measurement; load average {load_average():.1f}")
    print(
        f"{'n_envs':>6} "
        + " ".join(f"{algo:>8}" for algo in ALGOS)
        + "   (env steps/s; one gradient step per n_envs env steps)"
    )
    for n_envs in args.n_envs:
        rates = [steps_per_second(build(algo, args.env, n_envs), args.steps, warmup=500) for algo in ALGOS]
        print(f"{n_envs:>6} " + " ".join(f"{rate:>8.0f}" for rate in rates), flush=True)
    obs = gym.make(args.env).reset(seed=0)[0]
    latencies = {algo: predict_microseconds(build(algo, args.env, 1), obs) for algo in ALGOS}
    print(
        "predict (one observation, deterministic, median of 2000): "
        + ", ".join(f"{a} {us:.0f} us" for a, us in latencies.items())
    )


if __name__ == "__main__":
    main()
