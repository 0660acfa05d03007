"""
Training throughput (env steps per second) of SarsaAAC with ``DeepPolicy`` next to SB3's TD3, in the same run.

Both learn the same env in SB3's ``DummyVecEnv``: TD3 (default ``MlpPolicy``, 400 x 300, one gradient step of a
256-sample batch per transition: SB3's defaults ``train_freq=1, gradient_steps=1``) through
:class:`sb3_aac.FlattenParameterizedAction`, on one lane; ``DeepPolicy`` (defaults: three networks of two hidden
layers of 64) on the env's own actions, on one lane and on ``--lanes`` lanes. Each algorithm first runs ``--warmup``
steps (TD3's replay buffer fills past ``learning_starts``, numba and numpy warm up), then ``--steps`` steps are
timed; the figure is the best of ``--repeats`` timings. One torch and one BLAS thread.

Usage: ``python -m benchmarks.speed.deep_speed [--env navigation|RoboCupDribblePaper-v0] [--steps 3000] [--lanes 16]``

Target: ``DeepPolicy`` >= 5x TD3's env steps per second on the same env. Single runs on a shared machine:
report the load average (printed) with the numbers.
"""

from __future__ import annotations

import argparse

import torch as th
from stable_baselines3 import TD3
from stable_baselines3.common.env_util import make_vec_env

import robocup_dribble  # noqa: F401  (registers the dribbling env ids)
from benchmarks.speed.timing import load_average, steps_per_second
from sb3_aac import FlattenParameterizedAction, SarsaAAC
from sb3_aac.common.envs import NavigationEnv


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="navigation", help="'navigation' (NavigationEnv) or a registered env id")
    parser.add_argument("--steps", type=int, default=3000, help="timed env steps per run")
    parser.add_argument("--warmup", type=int, default=500, help="untimed env steps first (TD3 learns from step 100)")
    parser.add_argument("--repeats", type=int, default=2, help="timed runs (the best is reported)")
    parser.add_argument("--lanes", type=int, default=16, help="lanes of the second DeepPolicy run")
    args = parser.parse_args(argv)
    th.set_num_threads(1)
    env_id = NavigationEnv if args.env == "navigation" else args.env
    print(f"env steps/s on {args.env} (best of {args.repeats} x {args.steps} steps; load average {load_average():.2f})")

    td3_env = make_vec_env(env_id, n_envs=1, seed=0, wrapper_class=FlattenParameterizedAction)
    td3 = steps_per_second(TD3("MlpPolicy", td3_env, seed=0, device="cpu"), args.steps, args.warmup, args.repeats)
    print(f"{'TD3 (1 lane, 1 gradient step per transition)':48s} {td3:10.0f}")
    for lanes in (1, args.lanes):
        model = SarsaAAC("DeepPolicy", make_vec_env(env_id, n_envs=lanes, seed=0), seed=0, trace_lambda=0.8)
        deep = steps_per_second(model, args.steps, args.warmup, args.repeats)
        print(f"{f'SarsaAAC DeepPolicy ({lanes} lanes, trace_lambda=0.8)':48s} {deep:10.0f}   {deep / td3:6.1f}x TD3")


if __name__ == "__main__":
    main()
