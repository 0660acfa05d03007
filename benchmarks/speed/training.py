"""
Training throughput (env steps per second) of the learners next to SB3's on the same env, machine and run; one
comparison per subcommand (``python -m benchmarks.speed.training COMPARISON --help`` for its options):

* ``sarsa``: SarsaAAC next to PPO and DQN, its cost growth with the number of RBFs, and ``predict`` latency;
* ``deep``: SarsaAAC's ``DeepPolicy`` next to TD3;
* ``hppo``: HybridPPO next to PPO;
* ``pdqn``: P-DQN and MP-DQN next to TD3 and DQN, and ``predict`` latency;
* ``fused``: the torch learners' outcomes over seeds with the fused optimizer against the per-tensor loop.

``predict`` latency is :func:`benchmarks.evaluation.predict_microseconds` (the median of single calls on the final
evaluation set's first observations), as the grid records it. Single runs on a shared machine: repeat them, and
report the load average (printed) with the numbers.

Usage: ``python -m benchmarks.speed.training sarsa|deep|hppo|pdqn|fused [options]``
"""

from __future__ import annotations

import argparse
import ast
import statistics
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
import torch as th
from scipy import stats
from stable_baselines3 import DQN, PPO, TD3
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.vec_env import VecEnv

import robocup_dribble
from benchmarks.evaluation import PREDICT_CALLS, predict_microseconds
from benchmarks.speed.timing import load_average, steps_per_second
from sb3_aac import MPDQN, PDQN, DiscretizeParameterizedAction, FlattenParameterizedAction, HybridPPO, SarsaAAC
from sb3_aac.common.array_env import ArrayStep
from sb3_aac.common.envs import NavigationEnv, register_toy_env

SARSA_DOC = """Training throughput (env steps per second) of SarsaAAC next to SB3's PPO and DQN on the dribbling env, and
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

Usage: ``python -m benchmarks.speed.training sarsa [--steps 20000] [--n-envs 16] [--policy RbfPolicy] [--torch-threads 1]
[--lanes 256] [--n-rbf 10 30 50] [--set trace_lambda=0.7 ...]`` (``--set``: SarsaAAC keyword arguments as Python
literals; ``--n-rbf`` with no value skips the RBF cost growth, e.g. for ``--policy TilePolicy``)

Single runs on a shared machine: repeat them, and report the load average next to the numbers."""

DEEP_DOC = """Training throughput (env steps per second) of SarsaAAC with ``DeepPolicy`` next to SB3's TD3, in the same run.

Both learn the same env in SB3's ``DummyVecEnv``: TD3 (default ``MlpPolicy``, 400 x 300, one gradient step of a
256-sample batch per transition: SB3's defaults ``train_freq=1, gradient_steps=1``) through
:class:`sb3_aac.FlattenParameterizedAction`, on one lane; ``DeepPolicy`` (defaults: three networks of two hidden
layers of 64) on the env's own actions, on one lane and on ``--lanes`` lanes. Each algorithm first runs ``--warmup``
steps (TD3's replay buffer fills past ``learning_starts``, numba and numpy warm up), then ``--steps`` steps are
timed; the figure is the best of ``--repeats`` timings. One torch and one BLAS thread.

Usage: ``python -m benchmarks.speed.training deep [--env navigation|RoboCupDribblePaper-v0] [--steps 3000] [--lanes 16]
[--parameter-update cacla|critic] [--policy DeepPolicy] [--set KEY=VALUE ...]`` (SarsaAAC's ``parameter_update``: the
paper's CACLA, the default, or with the critic of the parameters). ``--policy`` times another SarsaAAC policy in
DeepPolicy's place, with its defaults (DeepPolicy with ``trace_lambda=0.8``); ``--set`` overrides SarsaAAC's
arguments, e.g. ``--policy MlpPolicy --set replay_ratio=0`` against the default replay.

Target: every SarsaAAC policy >= 10x TD3's env steps per second on the paper env. Single runs on a shared machine:
report the load average (printed) with the numbers."""

HPPO_DOC = """Training throughput (env steps per second) of HybridPPO next to SB3's PPO on the same env with the same network
sizes (the target: HybridPPO within 1.5x of PPO, i.e. ratio >= 0.67).

Both learn ``--env`` in SB3's ``DummyVecEnv`` with ``--n-envs`` envs and the same rollout shape (256 steps per env,
minibatches of 256, 10 epochs): HybridPPO on the env's own Tuple actions, PPO through
:class:`sb3_aac.FlattenParameterizedAction`. Networks: PPO's default (``pi`` and ``vf`` of 64x64 each); HybridPPO
with its default (three networks of 64x64: discrete actor, parameter actor, critic) and with the actors sharing
their 64x64 layers (``net_arch=dict(shared=[64, 64], type=[], params=[])``, the same layer sizes as PPO's). A last
column gives HybridPPO on the batched :class:`robocup_dribble.DribbleVecEnv` (the array path) for the dribbling envs.
The measurements are interleaved and repeated (``--repeats``); the medians are printed, so that a load change on a
shared machine hits both sides alike.

Usage: ``python -m benchmarks.speed.training hppo [--env RoboCupDribblePaper-v0] [--steps 8192] [--repeats 3]``

Note, for comparison: before the fast rollouts (main at 337ec70; AMD EPYC, torch 2.13 CPU, load average 0.4), HybridPPO
with this rollout shape on one env (``--n-envs 1``) gave 1219 env steps/s."""

PDQN_DOC = """Training throughput (env steps per second) and single-observation ``predict`` latency of P-DQN and MP-DQN next to
SB3's TD3 and DQN, on the same env, machine and run.

P-DQN and MP-DQN act in the env's own Tuple actions; TD3 learns through :class:`sb3_aac.FlattenParameterizedAction`
(a Box) and DQN through :class:`sb3_aac.DiscretizeParameterizedAction` (a Discrete grid, 5 values per parameter), as
in the benchmark's baselines. All four take one gradient step per step of the vectorized env (``train_freq=1``,
``gradient_steps=1``: one per ``n_envs`` transitions) on minibatches of 128 with two hidden layers of 64 units, so the
figures compare the cost of the algorithms, not of their default settings.

Usage: ``python -m benchmarks.speed.training pdqn [--env RoboCupDribblePaper-v0] [--steps 5000] [--n-envs 1 16]``

Single runs on a shared machine: repeat them, and report the load average next to the numbers.

Note, for comparison: before the fast gradient steps (main at 337ec70; AMD EPYC, torch 2.13 CPU, load average 0.4),
``--n-envs 1`` gave P-DQN 355 and MP-DQN 229 env steps/s."""

FUSED_DOC = """Do the torch learners learn as well with torch's fused optimizer (their default,
:func:`sb3_aac.common.updates.make_optimizer`) as with the per-tensor loop (``optimizer_kwargs=dict(foreach=False)``,
torch's CPU default before)? The two compute the same update rounded differently, so seeded runs part after the
first steps; this compares the outcomes over seeds.

For each learner and each of ``--seeds`` seeds, one run per arithmetic (the same seed, hyperparameters and env) of
``--steps`` env steps on ``--env``, then the greedy policy's mean return over ``--eval-episodes`` episodes (SB3's
``evaluate_policy``, deterministic). Printed per learner: the mean and standard deviation of each arithmetic's
scores, the paired difference (fused - loop) with its 95% confidence interval, and the p-values of the paired
Wilcoxon signed-rank test and of the Mann-Whitney U test. Equivalence at this resolution: the interval holds 0 and
both p-values exceed 0.05 (a check for a broken update, not a proof of equality: small differences need more seeds).

Usage: ``python -m benchmarks.speed.training fused [--algos PDQN MPDQN HybridPPO] [--seeds 10] [--steps 3000]``"""


# ---------------------------------------------------------------- sarsa


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


def sarsa_model(algo: str, env_id: str, n_envs: int, policy: str, policy_kwargs: dict | None = None):
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


def sarsa_rate(algo: str, env_id: str, n_envs: int, steps: int, policy: str, policy_kwargs: dict | None = None) -> float:
    return steps_per_second(sarsa_model(algo, env_id, n_envs, policy, policy_kwargs), steps, warmup=min(1000, steps))


def sarsa_main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(prog="training sarsa", description=SARSA_DOC)
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
    args = parser.parse_args(argv)
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
        rates = {algo: sarsa_rate(algo, args.env, n_envs, args.steps, args.policy) for algo in algos}
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
        rate = sarsa_rate("SarsaAAC+DribbleVecEnv", args.env, lanes, steps, args.policy, {"n_rbf": n_rbf})
        base = base or rate
        relative = f"{base / rate:.2f}x the cost at {args.n_rbf[0]}"
        print(f"  {n_rbf:>3} RBFs/input: {rate:>9.0f} env steps/s  ({relative})", flush=True)
    algorithm_only = sarsa_rate("SarsaAAC+NullArrayEnv", args.env, lanes, steps, args.policy)
    print(f"SarsaAAC {args.policy} alone on the array path (NullArrayEnv, {lanes} lanes): {algorithm_only:.0f} env steps/s")
    sarsa, dqn = sarsa_model("SarsaAAC", args.env, 1, args.policy), sarsa_model("DQN", args.env, 1, args.policy)
    print(
        f"predict (one observation, deterministic, median of {PREDICT_CALLS}): "
        f"SarsaAAC {predict_microseconds(sarsa, args.env):.1f} us, DQN {predict_microseconds(dqn, args.env):.1f} us"
    )


# ---------------------------------------------------------------- deep


def deep_main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(prog="training deep", description=DEEP_DOC)
    parser.add_argument("--env", default="navigation", help="'navigation' (NavigationEnv) or a registered env id")
    parser.add_argument("--steps", type=int, default=3000, help="timed env steps per run")
    parser.add_argument("--warmup", type=int, default=500, help="untimed env steps first (TD3 learns from step 100)")
    parser.add_argument("--repeats", type=int, default=2, help="timed runs (the best is reported)")
    parser.add_argument("--lanes", type=int, default=16, help="lanes of the second DeepPolicy run")
    parser.add_argument("--parameter-update", default="cacla", help="SarsaAAC's parameter_update: cacla or critic")
    parser.add_argument("--policy", default="DeepPolicy", help="the SarsaAAC policy timed")
    parser.add_argument("--set", nargs="*", default=[], metavar="KEY=VALUE", help="SarsaAAC keyword arguments")
    args = parser.parse_args(argv)
    th.set_num_threads(1)
    settings = {"trace_lambda": 0.8} if args.policy == "DeepPolicy" else {}
    settings |= {key: ast.literal_eval(value) for key, value in (item.split("=", 1) for item in args.set)}
    env_id = NavigationEnv if args.env == "navigation" else args.env
    print(f"env steps/s on {args.env} (best of {args.repeats} x {args.steps} steps; load average {load_average():.2f})")

    td3_env = make_vec_env(env_id, n_envs=1, seed=0, wrapper_class=FlattenParameterizedAction)
    td3 = steps_per_second(TD3("MlpPolicy", td3_env, seed=0, device="cpu"), args.steps, args.warmup, args.repeats)
    print(f"{'TD3 (1 lane, 1 gradient step per transition)':64s} {td3:10.0f}")
    for lanes in (1, args.lanes):
        env = make_vec_env(env_id, n_envs=lanes, seed=0)
        model = SarsaAAC(args.policy, env, seed=0, parameter_update=args.parameter_update, **settings)
        deep = steps_per_second(model, args.steps, args.warmup, args.repeats)
        described = ", ".join(f"{key}={value}" for key, value in settings.items())
        name = f"SarsaAAC {args.policy} ({lanes} lanes, {described + ', ' if described else ''}{args.parameter_update})"
        print(f"{name:64s} {deep:10.0f}   {deep / td3:6.1f}x TD3")


# ---------------------------------------------------------------- hppo

HPPO_ROLLOUT = dict(n_steps=256, batch_size=256, n_epochs=10)


SHARED_ACTORS = dict(net_arch=dict(shared=[64, 64], type=[], params=[], vf=[64, 64]))


def hppo_model(column: str, env_id: str, n_envs: int) -> Any:
    if column == "PPO":
        env = make_vec_env(env_id, n_envs=n_envs, seed=0, wrapper_class=FlattenParameterizedAction)
        return PPO("MlpPolicy", env, seed=0, device="cpu", **HPPO_ROLLOUT)
    if column == "HybridPPO+DribbleVecEnv":
        env = robocup_dribble.DribbleVecEnv(n_envs, profile=gym.spec(env_id).kwargs["profile"])
        return HybridPPO("MlpPolicy", env, seed=0, device="cpu", **HPPO_ROLLOUT)
    env = make_vec_env(env_id, n_envs=n_envs, seed=0)
    policy_kwargs = SHARED_ACTORS if column == "HybridPPO shared" else None
    return HybridPPO("MlpPolicy", env, seed=0, device="cpu", policy_kwargs=policy_kwargs, **HPPO_ROLLOUT)


def hppo_rate(column: str, env_id: str, n_envs: int, steps: int) -> float:
    # warm-up: one rollout per env (compiled kernels, first allocations)
    return steps_per_second(hppo_model(column, env_id, n_envs), steps, warmup=n_envs * HPPO_ROLLOUT["n_steps"])


def hppo_main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(prog="training hppo", description=HPPO_DOC)
    parser.add_argument("--env", default="RoboCupDribblePaper-v0")
    parser.add_argument("--n-envs", type=int, default=8)
    parser.add_argument("--steps", type=int, default=8192)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    th.set_num_threads(1)
    register_toy_env()
    columns = ["PPO", "HybridPPO", "HybridPPO shared"]
    if args.env in robocup_dribble.ENV_PROFILES:
        columns.append("HybridPPO+DribbleVecEnv")
    rates: dict[str, list[float]] = {column: [] for column in columns}
    for _ in range(args.repeats):
        for column in columns:
            rates[column].append(hppo_rate(column, args.env, args.n_envs, args.steps))
    medians = {column: statistics.median(values) for column, values in rates.items()}
    print(f"{args.env}, {args.n_envs} envs, {args.steps} steps x {args.repeats} (medians; load {load_average():.1f})")
    for column in columns:
        ratio = medians[column] / medians["PPO"]
        runs = ", ".join(f"{value:.0f}" for value in rates[column])
        print(f"  {column:24s} {medians[column]:7.0f} steps/s  {ratio:5.2f}x PPO  (runs: {runs})")


# ---------------------------------------------------------------- pdqn

PDQN_COLUMNS = ("PDQN", "MPDQN", "TD3", "DQN")


PDQN_SETTINGS = dict(learning_starts=100, batch_size=128, train_freq=1, gradient_steps=1, seed=0, device="cpu")


def pdqn_model(algo: str, env_id: str, n_envs: int):
    if algo in ("PDQN", "MPDQN"):
        cls = PDQN if algo == "PDQN" else MPDQN
        return cls(
            "MlpPolicy", make_vec_env(env_id, n_envs=n_envs, seed=0), policy_kwargs=dict(net_arch=[64, 64]), **PDQN_SETTINGS
        )
    if algo == "TD3":
        env = make_vec_env(env_id, n_envs=n_envs, seed=0, wrapper_class=FlattenParameterizedAction)
        return TD3("MlpPolicy", env, policy_kwargs=dict(net_arch=[64, 64]), **PDQN_SETTINGS)
    env = make_vec_env(env_id, n_envs=n_envs, seed=0, wrapper_class=DiscretizeParameterizedAction)
    return DQN("MlpPolicy", env, policy_kwargs=dict(net_arch=[64, 64]), **PDQN_SETTINGS)


def pdqn_main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(prog="training pdqn", description=PDQN_DOC)
    parser.add_argument("--env", default="RoboCupDribblePaper-v0", help="a registered parameterized-action env id")
    parser.add_argument("--steps", type=int, default=5000, help="env steps per training measurement")
    parser.add_argument("--n-envs", type=int, nargs="+", default=[1, 16])
    args = parser.parse_args(argv)
    th.set_num_threads(1)
    print(f"{args.env}; torch threads 1; {args.steps} steps per measurement; load average {load_average():.1f}")
    print(
        f"{'n_envs':>6} "
        + " ".join(f"{algo:>8}" for algo in PDQN_COLUMNS)
        + "   (env steps/s; one gradient step per n_envs env steps)"
    )
    for n_envs in args.n_envs:
        rates = [steps_per_second(pdqn_model(algo, args.env, n_envs), args.steps, warmup=500) for algo in PDQN_COLUMNS]
        print(f"{n_envs:>6} " + " ".join(f"{rate:>8.0f}" for rate in rates), flush=True)
    latencies = {algo: predict_microseconds(pdqn_model(algo, args.env, 1), args.env) for algo in PDQN_COLUMNS}
    print(
        f"predict (one observation, deterministic, median of {PREDICT_CALLS}): "
        + ", ".join(f"{a} {us:.0f} us" for a, us in latencies.items())
    )


# ---------------------------------------------------------------- fused


ARITHMETIC = {"loop": dict(foreach=False), "fused": None}


def fused_score(
    algo: str, env_id: str, seed: int, steps: int, episodes: int, optimizer_kwargs: dict[str, bool] | None
) -> float:
    env = make_vec_env(env_id, n_envs=1, seed=seed)
    policy_kwargs = {} if optimizer_kwargs is None else dict(optimizer_kwargs=optimizer_kwargs)
    if algo == "HybridPPO":
        if optimizer_kwargs is not None:  # keep the policy's default Adam eps (1e-5), which optimizer_kwargs replace
            policy_kwargs = dict(optimizer_kwargs=dict(optimizer_kwargs, eps=1e-5))
        model = HybridPPO("MlpPolicy", env, n_steps=256, batch_size=64, seed=seed, device="cpu", policy_kwargs=policy_kwargs)
    else:
        cls = PDQN if algo == "PDQN" else MPDQN
        model = cls("MlpPolicy", env, learning_starts=500, seed=seed, device="cpu", policy_kwargs=policy_kwargs)
    model.learn(steps)
    returns, _ = evaluate_policy(model, make_vec_env(env_id, n_envs=1, seed=10_000 + seed), episodes, deterministic=True)
    return float(returns)


def fused_main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(prog="training fused", description=FUSED_DOC)
    parser.add_argument("--env", default="RoboCupDribblePaper-v0")
    parser.add_argument("--algos", nargs="+", default=["PDQN", "MPDQN", "HybridPPO"])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--eval-episodes", type=int, default=20)
    args = parser.parse_args(argv)
    th.set_num_threads(1)
    print(f"{args.env}; {args.steps} steps; {args.seeds} seeds; greedy mean return over {args.eval_episodes} episodes")
    for algo in args.algos:
        scores = {
            name: np.array([fused_score(algo, args.env, s, args.steps, args.eval_episodes, kw) for s in range(args.seeds)])
            for name, kw in ARITHMETIC.items()
        }
        diff = scores["fused"] - scores["loop"]
        half = stats.t.ppf(0.975, len(diff) - 1) * diff.std(ddof=1) / np.sqrt(len(diff))
        wilcoxon = stats.wilcoxon(diff).pvalue if np.any(diff != 0) else 1.0
        mann_whitney = stats.mannwhitneyu(scores["fused"], scores["loop"]).pvalue
        print(
            f"{algo:10s} loop {scores['loop'].mean():8.3f} +- {scores['loop'].std(ddof=1):.3f}  "
            f"fused {scores['fused'].mean():8.3f} +- {scores['fused'].std(ddof=1):.3f}  "
            f"fused - loop {diff.mean():+.3f} [{diff.mean() - half:+.3f}, {diff.mean() + half:+.3f}]  "
            f"Wilcoxon p {wilcoxon:.2f}  Mann-Whitney p {mann_whitney:.2f}",
            flush=True,
        )


COMPARISONS: dict[str, Callable[[list[str]], None]] = {
    "sarsa": sarsa_main,
    "deep": deep_main,
    "hppo": hppo_main,
    "pdqn": pdqn_main,
    "fused": fused_main,
}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[1], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("comparison", choices=list(COMPARISONS))
    parser.add_argument("options", nargs=argparse.REMAINDER, help="the comparison's options (COMPARISON --help)")
    args = parser.parse_args(argv)
    COMPARISONS[args.comparison](args.options)


if __name__ == "__main__":
    main()
