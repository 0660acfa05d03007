"""The figures of a uniformly random and a scripted policy on every ``hybrid_domains`` env (docs/hybrid_domains.md).

Each policy plays the same ``--episodes`` episodes per env (episode ``j`` from ``reset(seed=--seed + j)``; the random
policy's action space is seeded with ``--seed``), through ``gym.make`` with its default wrappers. Prints a Markdown
table: mean (std) return, success share (P(goal) on Goal-v0, stopped in the target on Moving/Sliding, caught on
CatchPoint), actions per episode and env steps per CPU second (policy included; the process's CPU time, so a
loaded machine does not lower it).

Usage: ``python -m benchmarks.domain_baselines [--episodes 1000] [--seed 0]``
"""

from __future__ import annotations

import argparse

import gymnasium as gym

import hybrid_domains
from hybrid_domains.baselines import policy_figures, random_policy, scripted_policy


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(f"{args.episodes} episodes per row, episode j from reset(seed={args.seed} + j)\n")
    print("| env | policy | return mean (std) | success share | actions / episode | env steps / CPU s |")
    print("|---|---|---|---|---|---|")
    for env_id in hybrid_domains.ENV_CLASSES:
        policies = {
            "uniform random": random_policy(gym.make(env_id).action_space, args.seed),
            "scripted": scripted_policy(env_id),
        }
        for name, policy in policies.items():
            f = policy_figures(env_id, policy, args.episodes, args.seed)
            print(
                f"| {env_id} | {name} | {f['return_mean']:.3f} ({f['return_std']:.3f}) | {f['success_share']:.3f} "
                f"| {f['length_mean']:.1f} | {f['steps_per_second']:,.0f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
