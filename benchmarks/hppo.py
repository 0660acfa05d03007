"""
HybridPPO against SB3's PPO through :class:`~sb3_aac.FlattenParameterizedAction` at equal env steps.

    PYTHONPATH=.:envs python -m benchmarks.hppo --domain platform --seeds 5 --steps 100000
    PYTHONPATH=.:envs python -m benchmarks.hppo --domain paper --seeds 5 --steps 50000
    PYTHONPATH=.:envs python -m benchmarks.hppo --domain nav --seeds 5 --steps 100000
    PYTHONPATH=.:envs python -m benchmarks.hppo --domain platform --algos HybridPPO --seeds 1   # one side only

Both algorithms get the same env steps, lanes and rollout shape: HybridPPO the settings of ``hyperparams/hppo.yml``,
PPO the benchmark's preset (:data:`benchmarks.presets.BASELINES`, 8 lanes, 256 steps each, minibatches of 256),
both with two hidden layers of 64 per network. Scores are greedy: the mean return over ``--episodes`` Platform
episodes (:func:`benchmarks.domains.evaluate`, common random numbers), the mean metres over dribbling episodes of
fresh players, the success rate over navigation episodes. Per algorithm the script prints the per-seed scores,
their IQM with its 95 % percentile-bootstrap CI (over seeds) and the training speed; then Welch's test on the
difference of the means (:func:`benchmarks.significance.compare`, with ``min_seeds`` lowered to the seeds run).
``--jsonl FILE`` appends one JSON line per finished run (so results survive an interrupted run), and
``--summarize FILE ...`` prints the same summaries from such files (seeds split over processes).
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import torch as th
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import VecEnv

from benchmarks import domains, significance
from benchmarks.adapters import FlatActionAdapter, adapter_for, build_baseline
from benchmarks.learning import iqm_ci, navigation_success
from benchmarks.presets import BASELINES, FINAL_SEED, PLATFORM_ID
from benchmarks.zoo_hyperparams import settings
from sb3_aac import FlattenParameterizedAction, HybridPPO
from sb3_aac.common.envs import NavigationEnv

ENV_IDS = {"platform": PLATFORM_ID, "paper": "RoboCupDribblePaper-v0", "v19": "RoboCupDribble-v0", "nav": "sb3_aac/Navigation"}
DEFAULT_STEPS = {"platform": 100_000, "paper": 50_000, "v19": 50_000, "nav": 100_000}


def hppo_env(env_id: str, n_envs: int, seed: int) -> VecEnv:
    if env_id == ENV_IDS["nav"]:
        return make_vec_env(NavigationEnv, n_envs=n_envs, seed=seed)
    return domains.train_env(env_id, n_envs, seed)


def score(env_id: str, policy: Any, n_episodes: int) -> float:
    if env_id == ENV_IDS["nav"]:
        return navigation_success(policy, n_episodes, FINAL_SEED)
    return float(domains.evaluate(env_id, policy, n_episodes, FINAL_SEED)[domains.metric(env_id)])


def train_hppo(env_id: str, seed: int, steps: int) -> tuple[Any, float]:
    kwargs = settings("hppo", env_id)
    env = hppo_env(env_id, kwargs.pop("n_envs", 8), seed)
    model = HybridPPO("MlpPolicy", env, seed=seed, device="cpu", **kwargs)
    start = time.perf_counter()
    model.learn(steps)
    return model, steps / (time.perf_counter() - start)


def train_ppo(env_id: str, seed: int, steps: int) -> tuple[Any, float]:
    if env_id == ENV_IDS["nav"]:
        from stable_baselines3 import PPO

        spec = BASELINES["PPO"]
        env = make_vec_env(NavigationEnv, n_envs=spec["n_envs"], seed=seed, wrapper_class=FlattenParameterizedAction)
        model: Any = PPO("MlpPolicy", env, seed=seed, device="cpu", **spec["kwargs"])
        adapter: Any = FlatActionAdapter(model, NavigationEnv().action_space)
    else:
        model = build_baseline(env_id, "PPO", seed)
        adapter = adapter_for(model, "PPO", env_id)
    start = time.perf_counter()
    model.learn(steps)
    return adapter, steps / (time.perf_counter() - start)


TRAINERS: dict[str, Callable[[str, int, int], tuple[Any, float]]] = {"HybridPPO": train_hppo, "PPO": train_ppo}


def summarize(domain: str, steps: int, results: dict[str, list[float]], speeds: dict[str, list[float]]) -> None:
    """Print each algorithm's scores, IQM and 95 % CI, and the test on the difference when both were run."""
    for algo, scores in results.items():
        low, high = iqm_ci(scores)
        print(
            f"{domain} {algo:9s} steps={steps} scores={[round(s, 3) for s in scores]} mean={np.mean(scores):.3f} "
            f"iqm={float(significance.iqm(np.asarray(scores))):.3f} ci95=[{low:.3f}, {high:.3f}] "
            f"train={np.mean(speeds[algo]):.0f} steps/s",
            flush=True,
        )
    if {"HybridPPO", "PPO"} <= set(results) and min(len(results["HybridPPO"]), len(results["PPO"])) >= 2:
        a, b = results["HybridPPO"], results["PPO"]
        comparison = significance.compare(a, b, min_seeds=min(len(a), len(b)))
        print(
            f"{domain} HybridPPO - PPO: {comparison.outcome} (Welch p={comparison.welch_p:.4f}, mean difference "
            f"{comparison.mean_difference:.3f}, 95% CI [{comparison.mean_difference_ci[0]:.3f}, "
            f"{comparison.mean_difference_ci[1]:.3f}])",
            flush=True,
        )


def summarize_files(paths: list[str]) -> None:
    """:func:`summarize` over the rows of ``--jsonl`` files (runs split over processes), per domain and budget."""
    rows = [json.loads(line) for path in paths for line in open(path) if line.strip()]
    for domain, steps in sorted({(row["domain"], row["steps"]) for row in rows}):
        chosen = sorted((r for r in rows if (r["domain"], r["steps"]) == (domain, steps)), key=lambda r: r["seed"])
        results: dict[str, list[float]] = {}
        speeds: dict[str, list[float]] = {}
        for row in chosen:
            results.setdefault(row["algo"], []).append(row["score"])
            speeds.setdefault(row["algo"], []).append(row["speed"])
        summarize(domain, steps, results, speeds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--domain", choices=list(ENV_IDS))
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--steps", type=int, default=None, help="env steps of training (default: per domain)")
    parser.add_argument("--episodes", type=int, default=500, help="greedy evaluation episodes per trained model")
    parser.add_argument("--algos", default="HybridPPO,PPO", help="comma-separated: HybridPPO, PPO")
    parser.add_argument("--jsonl", default=None, help="append one JSON line per finished run to this file")
    parser.add_argument("--summarize", nargs="+", metavar="FILE", help="only summarise the rows of these --jsonl files")
    args = parser.parse_args()
    if args.summarize:
        summarize_files(args.summarize)
        return
    if args.domain is None:
        parser.error("--domain is required (unless --summarize)")
    th.set_num_threads(1)
    env_id, steps = ENV_IDS[args.domain], args.steps or DEFAULT_STEPS[args.domain]
    results: dict[str, list[float]] = {}
    speeds: dict[str, list[float]] = {}
    for algo in args.algos.split(","):
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            policy, speed = TRAINERS[algo](env_id, seed, steps)
            results.setdefault(algo, []).append(score(env_id, policy, args.episodes))
            speeds.setdefault(algo, []).append(speed)
            row = dict(
                domain=args.domain, algo=algo, seed=seed, steps=steps, score=round(results[algo][-1], 4), speed=round(speed)
            )
            print(json.dumps(row), flush=True)
            if args.jsonl:
                with open(args.jsonl, "a") as out:
                    out.write(json.dumps(row) + "\n")
    summarize(args.domain, steps, results, speeds)


if __name__ == "__main__":
    main()
