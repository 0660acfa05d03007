"""
Learning targets of SarsaAAC (issue 8): train each (task, policy) on several seeds and print the greedy score.

    PYTHONPATH=.:envs python -m benchmarks.learning --seeds 3
    PYTHONPATH=.:envs python -m benchmarks.learning --only paper-mlp2,nav-tile --seeds 5
    PYTHONPATH=.:envs python -m benchmarks.learning --only paper-rbf10 --set gamma=0.95 exploration_fraction=0.3

Scores: the mean dribbled distance in metres over 500 greedy episodes on fresh players (the dribbling envs), the
mean return over 200 greedy episodes (Platform-v0, the toy env), the greedy success rate over 500 episodes (the
navigation env). Each line prints the per-seed scores, their mean and their interquartile mean (IQM), the
training episodes and env steps, and the training speed. Runs are single-threaded and seeded.
"""

from __future__ import annotations

import argparse
import ast
import os
import time
from collections.abc import Callable
from typing import Any

# One BLAS thread: on a busy two-core machine OpenBLAS's own threads made SarsaAAC's small matrix products up to 70x
# slower (256 lanes, RbfPolicy: 15 ms instead of 0.2 ms per forward pass). Set before numpy is imported.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import torch as th  # noqa: E402
from scipy import stats  # noqa: E402
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402
from stable_baselines3.common.evaluation import evaluate_policy  # noqa: E402
from stable_baselines3.common.vec_env import VecEnv  # noqa: E402

from sb3_aac import SarsaAAC, SelectObservation  # noqa: E402
from sb3_aac.common.envs import NavigationEnv, ParameterizedTargetEnv  # noqa: E402

# name: (policy, policy_kwargs)
POLICIES: dict[str, tuple[str, dict[str, Any]]] = {
    "mlp2": ("MlpPolicy", {"hidden_units": 2}),
    "rbfmlp2": ("RbfMlpPolicy", {"n_rbf": 10, "hidden_units": 2}),
    "rbf10": ("RbfPolicy", {"n_rbf": 10}),
    "rbf50": ("RbfPolicy", {"n_rbf": 50}),
    "tile": ("TilePolicy", {}),
}


def dribble_env(profile: str) -> Callable[[int], VecEnv]:
    def make(seed: int) -> VecEnv:
        from robocup_dribble import DribbleVecEnv

        env = DribbleVecEnv(16, profile=profile)
        env.seed(seed)
        return env

    return make


def dribble_score(profile: str) -> Callable[[SarsaAAC], float]:
    def score(model: SarsaAAC) -> float:
        from robocup_dribble.evaluation import evaluate_dribbling

        report = evaluate_dribbling(model, n_episodes=500, profile=profile, seed=10_000)
        return float(np.mean(report.distances))

    return score


def platform_env(n_envs: int, seed: int) -> VecEnv:
    import gymnasium as gym
    import gym_platform  # noqa: F401  (registers Platform-v0)

    return make_vec_env(lambda: SelectObservation(gym.make("Platform-v0"), 0), n_envs=n_envs, seed=seed)


def mean_return(make: Callable[[int, int], VecEnv], episodes: int) -> Callable[[SarsaAAC], float]:
    def score(model: SarsaAAC) -> float:
        return float(evaluate_policy(model, make(1, 10_000), n_eval_episodes=episodes, deterministic=True)[0])

    return score


def navigation_success(model: SarsaAAC) -> float:
    env = make_vec_env(NavigationEnv, n_envs=50, seed=10_000)
    obs, successes, episodes = env.reset(), 0, 0
    while episodes < 500:
        obs, _, dones, infos = env.step(model.predict(obs, deterministic=True)[0])
        for done, info in zip(dones, infos, strict=True):
            if done:
                successes += bool(info["is_success"])
                episodes += 1
    return successes / episodes


def vec(env_class: type, n_envs: int) -> Callable[[int], VecEnv]:
    return lambda seed: make_vec_env(env_class, n_envs=n_envs, seed=seed)


def toy(n_envs: int, seed: int) -> VecEnv:
    return make_vec_env(ParameterizedTargetEnv, n_envs=n_envs, seed=seed)


# name: (make env from seed, training steps, SarsaAAC keyword arguments, score)
TASKS: dict[str, tuple[Callable[[int], VecEnv], int, dict[str, Any], Callable[[SarsaAAC], float]]] = {
    "paper": (dribble_env("v11"), 150_000, {}, dribble_score("v11")),
    "v19": (dribble_env("v19"), 150_000, {}, dribble_score("v19")),
    "platform": (lambda seed: platform_env(16, seed), 100_000, {"info_keywords": ()}, mean_return(platform_env, 200)),
    "nav": (vec(NavigationEnv, 16), 300_000, {"info_keywords": ()}, navigation_success),
    "toy": (lambda seed: toy(4, seed), 20_000, {}, mean_return(toy, 200)),
}


def iqm(values: list[float]) -> float:
    return float(stats.trim_mean(values, 0.25))


def run(
    task: str, policy_name: str, seeds: list[int], steps: int | None, rate: float | None, settings: dict[str, Any]
) -> None:
    make_env, budget, kwargs, score = TASKS[task]
    if rate is not None:
        kwargs = {**kwargs, "learning_rate": rate, "q_learning_rate": rate, "param_learning_rate": rate}
    kwargs = {**kwargs, **settings}
    policy, policy_kwargs = POLICIES[policy_name]
    budget = steps or budget
    scores, episodes, speeds = [], [], []
    for seed in seeds:
        model = SarsaAAC(policy, make_env(seed), seed=seed, policy_kwargs=policy_kwargs, **kwargs)
        start = time.perf_counter()
        model.learn(budget, log_interval=None)
        speeds.append(budget / (time.perf_counter() - start))
        episodes.append(model._episode_num)
        scores.append(score(model))
    extra = "".join(f" {key}={value}" for key, value in settings.items())
    print(
        f"{task:9s} {policy_name:8s} rate={rate or 'default'}{extra} steps={budget:>7d} episodes~{int(np.mean(episodes)):>6d} "
        f"scores={[round(s, 3) for s in scores]} mean={np.mean(scores):.3f} iqm={iqm(scores):.3f} "
        f"train={np.mean(speeds) / 1e3:.0f}k steps/s",
        flush=True,
    )


DEFAULT_RUNS = (
    "paper-mlp2,paper-rbfmlp2,paper-rbf10,paper-tile,v19-rbf10,v19-tile,platform-rbf10,platform-tile,"
    "nav-rbf10,nav-tile,toy-rbf10,toy-tile"
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", default=DEFAULT_RUNS, help="comma-separated task-policy pairs")
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=None, help="override every task's training steps")
    parser.add_argument("--rate", type=float, default=None, help="set the three learning rates (default: SarsaAAC's)")
    parser.add_argument(
        "--set", nargs="*", default=[], metavar="KEY=VALUE", help="SarsaAAC keyword arguments (Python literals)"
    )
    args = parser.parse_args()
    th.set_num_threads(1)
    settings = {key: ast.literal_eval(value) for key, value in (item.split("=", 1) for item in args.set)}
    for pair in args.only.split(","):
        task, policy_name = pair.split("-")
        if task not in TASKS or policy_name not in POLICIES:
            raise SystemExit(f"unknown pair {pair!r}: tasks {list(TASKS)}, policies {list(POLICIES)}")
        run(task, policy_name, list(range(args.seeds)), args.steps, args.rate, settings)


if __name__ == "__main__":
    main()
