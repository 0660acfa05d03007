"""
P-DQN / MP-DQN on the dribbling env: greedy dribbling figures at given env-step budgets, per seed.

One training run per seed on ``robocup_dribble.DribbleVecEnv`` (``--n-envs`` lanes; the algorithm uses the array
path when the env offers it), evaluated with :func:`robocup_dribble.evaluation.evaluate_dribbling` on 1,000
fresh players (evaluation seed 20000, as the benchmark's final evaluations) each time training passes a budget
in ``--budgets``. Hyperparameters: ``hyperparams/mpdqn.yml`` (``RoboCupDribblePaper-v0``). Prints one JSON line per
(seed, budget) and a summary line per budget (mean over seeds).

Usage: ``python -m benchmarks.pdqn_dribble [--algo mpdqn|pdqn] [--budgets 150000 1000000] [--seeds 0 1 2]``
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import torch as th
from stable_baselines3.common.callbacks import BaseCallback

from robocup_dribble import ENV_PROFILES, DribbleVecEnv
from robocup_dribble.evaluation import evaluate_dribbling
from benchmarks.presets import FINAL_SEED
from benchmarks.zoo_hyperparams import settings
from sb3_aac import MPDQN, PDQN


class EvaluateAtBudgets(BaseCallback):
    def __init__(self, budgets: list[int], profile: str, episodes: int, seed: int, start: float):
        super().__init__()
        self.budgets, self.profile, self.episodes, self.seed, self.start = sorted(budgets), profile, episodes, seed, start
        self.rows: list[dict] = []

    def _on_step(self) -> bool:
        while self.budgets and self.num_timesteps >= self.budgets[0]:
            budget = self.budgets.pop(0)
            eval_start = time.perf_counter()
            train_s = eval_start - self.start
            report = evaluate_dribbling(self.model, self.episodes, profile=self.profile, seed=FINAL_SEED)
            row = dict(
                algo=type(self.model).__name__,
                seed=self.seed,
                budget=budget,
                env_steps=self.num_timesteps,
                episodes=self.model.episode_num,
                train_s=round(train_s, 1),
                distance_mean=round(float(report.mean_distance), 2),
                distance_median=round(float(np.median(report.distances)), 2),
                reach20_share=round(float(report.share_reaching(20)), 3),
                ball_loss_rate=round(float(report.loss_rate), 3),
            )
            self.rows.append(row)
            print(json.dumps(row), flush=True)
            self.start += time.perf_counter() - eval_start  # evaluation time is not training time
        return bool(self.budgets)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[1])
    parser.add_argument("--algo", choices=["mpdqn", "pdqn"], default="mpdqn")
    parser.add_argument("--env", choices=list(ENV_PROFILES), default="RoboCupDribblePaper-v0")
    parser.add_argument("--budgets", type=int, nargs="+", default=[150_000])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--episodes", type=int, default=1000, help="evaluation episodes per budget")
    args = parser.parse_args()
    th.set_num_threads(1)

    algo = MPDQN if args.algo == "mpdqn" else PDQN
    kwargs = settings(args.algo, args.env)
    n_envs = kwargs.pop("n_envs")
    rows = []
    for seed in args.seeds:
        env = DribbleVecEnv(n_envs, profile=ENV_PROFILES[args.env])
        model = algo("MlpPolicy", env, seed=seed, device="cpu", **kwargs)
        callback = EvaluateAtBudgets(args.budgets, ENV_PROFILES[args.env], args.episodes, seed, time.perf_counter())
        model.learn(max(args.budgets), callback=callback)
        rows += callback.rows
    for budget in sorted(args.budgets):
        distances = [row["distance_mean"] for row in rows if row["budget"] == budget]
        summary = dict(algo=algo.__name__, env=args.env, budget=budget, seeds=len(distances), hyperparameters=kwargs)
        summary.update(distance_mean=round(float(np.mean(distances)), 2), per_seed=distances)
        print(json.dumps(summary, default=str), flush=True)


if __name__ == "__main__":
    main()
