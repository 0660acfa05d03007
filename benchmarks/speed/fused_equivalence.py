"""
Do the torch learners learn as well with torch's fused optimizer (their default, :func:`sb3_aac.common.updates.make_optimizer`)
as with the per-tensor loop (``optimizer_kwargs=dict(foreach=False)``, torch's CPU default before)? The two compute the
same update rounded differently, so seeded runs part after the first steps; this compares the outcomes over seeds.

For each learner and each of ``--seeds`` seeds, one run per arithmetic (the same seed, hyperparameters and env) of
``--steps`` env steps on ``--env``, then the greedy policy's mean return over ``--eval-episodes`` episodes (SB3's
``evaluate_policy``, deterministic). Printed per learner: the mean and standard deviation of each arithmetic's
scores, the paired difference (fused - loop) with its 95% confidence interval, and the p-values of the paired
Wilcoxon signed-rank test and of the Mann-Whitney U test. Equivalence at this resolution: the interval holds 0 and
both p-values exceed 0.05 (a check for a broken update, not a proof of equality: small differences need more seeds).

Usage: ``python -m benchmarks.speed.fused_equivalence [--algos PDQN MPDQN HybridPPO] [--seeds 10] [--steps 3000]``
"""

from __future__ import annotations

import argparse
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import torch as th  # noqa: E402
from scipy import stats  # noqa: E402
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402
from stable_baselines3.common.evaluation import evaluate_policy  # noqa: E402

import robocup_dribble  # noqa: E402, F401  (registers the env ids)
from sb3_aac import MPDQN, PDQN, HybridPPO  # noqa: E402

ARITHMETIC = {"loop": dict(foreach=False), "fused": None}


def score(algo: str, env_id: str, seed: int, steps: int, episodes: int, optimizer_kwargs: dict[str, bool] | None) -> float:
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="RoboCupDribblePaper-v0")
    parser.add_argument("--algos", nargs="+", default=["PDQN", "MPDQN", "HybridPPO"])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--eval-episodes", type=int, default=20)
    args = parser.parse_args()
    th.set_num_threads(1)
    print(f"{args.env}; {args.steps} steps; {args.seeds} seeds; greedy mean return over {args.eval_episodes} episodes")
    for algo in args.algos:
        scores = {
            name: np.array([score(algo, args.env, s, args.steps, args.eval_episodes, kw) for s in range(args.seeds)])
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


if __name__ == "__main__":
    main()
