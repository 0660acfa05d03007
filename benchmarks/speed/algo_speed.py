"""
Training throughput (env steps per second) of SarsaAAC next to SB3's PPO and DQN on the dribbling env, and
single-observation ``predict`` latency next to DQN's.

All three learn ``RoboCupDribblePaper-v0`` (or ``--env``) in SB3's ``DummyVecEnv`` with the same number of envs:
SarsaAAC on the env's own Tuple actions, PPO through :class:`sb3_aac.FlattenParameterizedAction` (a Box) and DQN
through :class:`sb3_aac.DiscretizeParameterizedAction` (a Discrete grid). A last column gives SarsaAAC on the batched
:class:`robocup_dribble.DribbleVecEnv` with the same number of lanes, which is how the dribbling env is meant to be
trained.

Then SarsaAAC on ``DribbleVecEnv(--lanes)`` (array path) with 10, 30 and 50 RBFs per input (``--n-rbf``): the
cost growth with the number of features; and SarsaAAC's own cost on the array path (:mod:`sb3_aac.common.array_env`)
for ``--lanes`` lanes: a :class:`NullArrayEnv` with the dribbling env's spaces whose ``step_arrays`` costs almost
nothing, so the figure is the algorithm's ceiling, which an array env's own cost then lowers.

Targets: RbfPolicy (10 per input) >= 300k env steps/s on ``DribbleVecEnv(256)``; on 16 lanes SarsaAAC on
``DribbleVecEnv`` >= 20x PPO and >= 3x DQN (the "SarsaAAC+DribbleVecEnv" column's ratios).

Usage: ``python -m benchmarks.speed.algo_speed [--steps 20000] [--n-envs 16] [--policy RbfPolicy] [--torch-threads 1]
[--lanes 256] [--n-rbf 10 30 50] [--set trace_lambda=0.7 ...]`` (``--set``: SarsaAAC keyword arguments as Python
literals; ``--n-rbf`` with no value skips the RBF cost growth, e.g. for ``--policy TilePolicy``)

Single runs on a shared machine: repeat them, and report the load average next to the numbers.
"""

from __future__ import annotations

import argparse
import ast

import gymnasium as gym
import numpy as np
import torch as th
from stable_baselines3 import DQN, PPO
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import VecEnv

import robocup_dribble
from sb3_aac import DiscretizeParameterizedAction, FlattenParameterizedAction, SarsaAAC
from benchmarks.speed.timing import load_average, median_microseconds, steps_per_second
from sb3_aac.common.array_env import ArrayStep


class NullArrayEnv(VecEnv):
    """
    An array env that does no work: uniform observations in the given space, reward 1, and each lane's episode
    terminates with probability ``1 / mean_length`` per step. Only ``step_arrays`` (and ``reset``) are implemented.
    """

    def __init__(self, n_envs: int, observation_space: gym.spaces.Box, action_space: gym.spaces.Space, mean_length: int = 10):
        super().__init__(n_envs, observation_space, action_space)
        self._rng = np.random.default_rng(0)
        self._low, self._high = observation_space.low.astype(np.float64), observation_space.high.astype(np.float64)
        self._lengths = np.zeros(n_envs, dtype=np.int64)
        self._end_probability = 1.0 / mean_length

    def _observations(self) -> np.ndarray:
        return self._rng.uniform(self._low, self._high, (self.num_envs, len(self._low)))

    def reset(self) -> np.ndarray:
        return self._observations()

    def step_arrays(self, action_types: np.ndarray, params: np.ndarray) -> ArrayStep:
        self._lengths += 1
        ended = self._rng.random(self.num_envs) < self._end_probability
        observations = self._observations()
        lengths = self._lengths.copy()
        self._lengths[ended] = 0
        no = np.zeros(self.num_envs, dtype=bool)
        returns = lengths.astype(np.float64)  # reward 1 per step
        return ArrayStep(observations, np.ones(self.num_envs), ended, no, observations, returns, lengths, {})

    def step_async(self, actions: np.ndarray) -> None:
        raise NotImplementedError("NullArrayEnv offers the array path only")

    step_wait = set_attr = env_method = step_async  # type: ignore[assignment]

    def get_attr(self, attr_name: str, indices: object = None) -> list:
        return [None] * self.num_envs

    def env_is_wrapped(self, wrapper_class: type, indices: object = None) -> list[bool]:
        return [False] * self.num_envs

    def close(self) -> None:
        pass


# SarsaAAC keyword arguments from --set (e.g. trace_lambda), for every SarsaAAC measurement.
SARSA_SETTINGS: dict = {}


def build(algo: str, env_id: str, n_envs: int, policy: str, policy_kwargs: dict | None = None):
    if algo == "SarsaAAC":
        env = make_vec_env(env_id, n_envs=n_envs, seed=0)
        return SarsaAAC(policy, env, seed=0, policy_kwargs=policy_kwargs, **SARSA_SETTINGS)
    if algo == "SarsaAAC+NullArrayEnv":
        spaces_env = gym.make(env_id)
        env = NullArrayEnv(n_envs, spaces_env.observation_space, spaces_env.action_space)
        return SarsaAAC(policy, env, seed=0, policy_kwargs=policy_kwargs, **{"info_keywords": (), **SARSA_SETTINGS})
    if algo == "SarsaAAC+DribbleVecEnv":
        profile = gym.spec(env_id).kwargs["profile"]
        env = robocup_dribble.DribbleVecEnv(n_envs, profile=profile)
        return SarsaAAC(policy, env, seed=0, policy_kwargs=policy_kwargs, **SARSA_SETTINGS)
    if algo == "PPO":
        # Defaults, with the rollout kept at 2048 transitions whatever the number of envs.
        env = make_vec_env(env_id, n_envs=n_envs, seed=0, wrapper_class=FlattenParameterizedAction)
        return PPO("MlpPolicy", env, n_steps=max(2048 // n_envs, 64), seed=0, device="cpu")
    env = make_vec_env(env_id, n_envs=n_envs, seed=0, wrapper_class=DiscretizeParameterizedAction)
    return DQN("MlpPolicy", env, buffer_size=100_000, seed=0, device="cpu")


def training_rate(algo: str, env_id: str, n_envs: int, steps: int, policy: str, policy_kwargs: dict | None = None) -> float:
    return steps_per_second(build(algo, env_id, n_envs, policy, policy_kwargs), steps, warmup=min(1000, steps))


def predict_microseconds(model, obs: np.ndarray, repeats: int = 2000) -> float:
    """Median of ``repeats`` single deterministic ``predict`` calls on ``obs``."""
    return median_microseconds(lambda: model.predict(obs, deterministic=True), repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="RoboCupDribblePaper-v0", help="a registered dribbling env id")
    parser.add_argument("--steps", type=int, default=20_000, help="env steps per training measurement")
    parser.add_argument("--n-envs", type=int, nargs="+", default=[16])
    parser.add_argument("--policy", default="RbfPolicy", help="SarsaAAC policy")
    parser.add_argument("--lanes", type=int, default=256, help="lanes of the DribbleVecEnv and NullArrayEnv measurements")
    parser.add_argument(
        "--n-rbf", type=int, nargs="*", default=[10, 30, 50], help="RBFs per input for the cost growth (none: skip it)"
    )
    parser.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE", help="SarsaAAC keyword arguments")
    parser.add_argument(
        "--torch-threads", type=int, default=1, help="torch threads for PPO/DQN (1 is fastest at these sizes on a busy box)"
    )
    args = parser.parse_args()
    th.set_num_threads(args.torch_threads)
    SARSA_SETTINGS.update({key: ast.literal_eval(value) for key, value in (item.split("=", 1) for item in args.set)})
    print(
        f"{args.env}; torch threads {th.get_num_threads()}; {args.steps} steps per measurement; SarsaAAC {args.policy} "
        f"{SARSA_SETTINGS or ''}; "
        f"load average {load_average():.1f}"
    )
    print(
        "SarsaAAC: DummyVecEnv (SB3 step, tuples) and DribbleVecEnv (array path); PPO: DummyVecEnv of "
        "FlattenParameterizedAction; DQN: DummyVecEnv of DiscretizeParameterizedAction (both SB3 step)"
    )
    algos = ("SarsaAAC", "PPO", "DQN", "SarsaAAC+DribbleVecEnv")
    print(
        f"{'n_envs':>6} {'SarsaAAC':>10} {'PPO':>8} {'DQN':>8} {'vs PPO':>7} {'vs DQN':>7} {'SarsaAAC+DribbleVecEnv':>23}"
        "   (env steps/s)"
    )
    for n_envs in args.n_envs:
        rates = {algo: training_rate(algo, args.env, n_envs, args.steps, args.policy) for algo in algos}
        array_rate = rates["SarsaAAC+DribbleVecEnv"]
        print(
            f"{n_envs:>6} {rates['SarsaAAC']:>10.0f} {rates['PPO']:>8.0f} {rates['DQN']:>8.0f} "
            f"{rates['SarsaAAC'] / rates['PPO']:>6.1f}x {rates['SarsaAAC'] / rates['DQN']:>6.1f}x "
            f"{array_rate:>23.0f} ({array_rate / rates['PPO']:.1f}x PPO, {array_rate / rates['DQN']:.1f}x DQN)",
            flush=True,
        )
    lanes = args.lanes
    steps = max(args.steps, 200 * lanes)
    if args.n_rbf:
        print(f"\nSarsaAAC {args.policy} on DribbleVecEnv({lanes}), array path: cost growth with RBFs per input")
    base = None
    for n_rbf in args.n_rbf:
        rate = training_rate("SarsaAAC+DribbleVecEnv", args.env, lanes, steps, args.policy, {"n_rbf": n_rbf})
        base = base or rate
        relative = f"{base / rate:.2f}x the cost at {args.n_rbf[0]}"
        print(f"  {n_rbf:>3} RBFs/input: {rate:>9.0f} env steps/s  ({relative})", flush=True)
    algorithm_only = training_rate("SarsaAAC+NullArrayEnv", args.env, lanes, steps, args.policy)
    print(f"SarsaAAC {args.policy} alone on the array path (NullArrayEnv, {lanes} lanes): {algorithm_only:.0f} env steps/s")
    obs = gym.make(args.env).reset(seed=0)[0]
    sarsa, dqn = build("SarsaAAC", args.env, 1, args.policy), build("DQN", args.env, 1, args.policy)
    print(
        f"predict (one observation, deterministic, median of 2000): "
        f"SarsaAAC {predict_microseconds(sarsa, obs):.1f} us, DQN {predict_microseconds(dqn, obs):.1f} us"
    )


if __name__ == "__main__":
    main()
