"""
Training throughput (env steps per second) of HybridPPO next to SB3's PPO on the same env with the same network
sizes (the target: HybridPPO within 1.5x of PPO, i.e. ratio >= 0.67).

Both learn ``--env`` in SB3's ``DummyVecEnv`` with ``--n-envs`` envs and the same rollout shape (256 steps per env,
minibatches of 256, 10 epochs): HybridPPO on the env's own Tuple actions, PPO through
:class:`sb3_aac.FlattenParameterizedAction`. Networks: PPO's default (``pi`` and ``vf`` of 64x64 each); HybridPPO
with its default (three networks of 64x64: discrete actor, parameter actor, critic) and with the actors sharing
their 64x64 layers (``net_arch=dict(shared=[64, 64], type=[], params=[])``, the same layer sizes as PPO's). A last
column gives HybridPPO on the batched :class:`robocup_dribble.DribbleVecEnv` (the array path) for the dribbling envs.
The measurements are interleaved and repeated (``--repeats``); the medians are printed, so that a load change on a
shared machine hits both sides alike.

Usage: ``python -m benchmarks.speed.hppo_speed [--env RoboCupDribblePaper-v0] [--steps 8192] [--repeats 3]``

Note, for comparison: before the fast rollouts (main at 337ec70; AMD EPYC, torch 2.13 CPU, load average 0.4), HybridPPO
with this rollout shape on one env (``--n-envs 1``) gave 1219 env steps/s.
"""

from __future__ import annotations

import argparse
import os
import statistics
from typing import Any

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import gymnasium as gym  # noqa: E402
import torch as th  # noqa: E402
from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402

import robocup_dribble  # noqa: E402
from benchmarks.speed.timing import load_average, steps_per_second  # noqa: E402
from sb3_aac import FlattenParameterizedAction, HybridPPO  # noqa: E402
from sb3_aac.cli import register_toy_env  # noqa: E402

ROLLOUT = dict(n_steps=256, batch_size=256, n_epochs=10)
SHARED_ACTORS = dict(net_arch=dict(shared=[64, 64], type=[], params=[], vf=[64, 64]))


def build(column: str, env_id: str, n_envs: int) -> Any:
    if column == "PPO":
        env = make_vec_env(env_id, n_envs=n_envs, seed=0, wrapper_class=FlattenParameterizedAction)
        return PPO("MlpPolicy", env, seed=0, device="cpu", **ROLLOUT)
    if column == "HybridPPO+DribbleVecEnv":
        env = robocup_dribble.DribbleVecEnv(n_envs, profile=gym.spec(env_id).kwargs["profile"])
        return HybridPPO("MlpPolicy", env, seed=0, device="cpu", **ROLLOUT)
    env = make_vec_env(env_id, n_envs=n_envs, seed=0)
    policy_kwargs = SHARED_ACTORS if column == "HybridPPO shared" else None
    return HybridPPO("MlpPolicy", env, seed=0, device="cpu", policy_kwargs=policy_kwargs, **ROLLOUT)


def training_rate(column: str, env_id: str, n_envs: int, steps: int) -> float:
    # warm-up: one rollout per env (compiled kernels, first allocations)
    return steps_per_second(build(column, env_id, n_envs), steps, warmup=n_envs * ROLLOUT["n_steps"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--env", default="RoboCupDribblePaper-v0")
    parser.add_argument("--n-envs", type=int, default=8)
    parser.add_argument("--steps", type=int, default=8192)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    th.set_num_threads(1)
    register_toy_env()
    columns = ["PPO", "HybridPPO", "HybridPPO shared"]
    if args.env in robocup_dribble.ENV_PROFILES:
        columns.append("HybridPPO+DribbleVecEnv")
    rates: dict[str, list[float]] = {column: [] for column in columns}
    for _ in range(args.repeats):
        for column in columns:
            rates[column].append(training_rate(column, args.env, args.n_envs, args.steps))
    medians = {column: statistics.median(values) for column, values in rates.items()}
    print(f"{args.env}, {args.n_envs} envs, {args.steps} steps x {args.repeats} (medians; load {load_average():.1f})")
    for column in columns:
        ratio = medians[column] / medians["PPO"]
        runs = ", ".join(f"{value:.0f}" for value in rates[column])
        print(f"  {column:24s} {medians[column]:7.0f} steps/s  {ratio:5.2f}x PPO  (runs: {runs})")


if __name__ == "__main__":
    main()
