"""
P-DQN / MP-DQN on Platform-v0 (PyPI ``hybrid-platform``) or Goal-v0 (``hybrid_domains``): the greedy score against
env steps.

The hyperparameters and env wrappers are the reference MP-DQN code's settings for the env (``hyperparams/mpdqn.yml``),
except the training length: the reference trains 20,000 episodes; this script trains ``--steps`` env steps and
evaluates the greedy policy every ``--eval-every`` steps on ``--eval-episodes`` fresh episodes, then once more on
``--final-episodes`` (1,000 in the papers). The score is the domain's published metric (:mod:`benchmarks.domains`:
mean return on Platform, P(goal) on Goal), on the env as it is (rewards unscaled). It prints one line per evaluation
and a final JSON line.

``--reference-init`` (Goal-v0) starts the parameter actor as the reference code does (:mod:`benchmarks.reference_init`).

Usage: ``python -m benchmarks.pdqn_platform [--env Platform-v0|Goal-v0] [--algo mpdqn|pdqn] [--steps 100000] [--seed 0]
[--reference-init]``
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import torch as th

from benchmarks import domains
from benchmarks.reference_init import with_reference_start
from benchmarks.zoo_hyperparams import settings, zoo_env
from sb3_aac import MPDQN, PDQN
from sb3_aac.common.checkpoints import GreedyCheckpoints

ENVS = ("Platform-v0", "Goal-v0")


class GreedyEvaluation(GreedyCheckpoints):
    """Scores the greedy policy (:func:`benchmarks.domains.evaluate`) every ``every`` env steps and records (steps,
    episodes, the domain's metric)."""

    def __init__(self, env_id: str, every: int, episodes: int, seed: int):
        self.key = domains.metric(env_id)
        super().__init__(every, lambda model: domains.evaluate(env_id, model, episodes, seed)[self.key])
        self.history: list[dict] = []

    def on_checkpoint(self, score: float) -> bool:
        row = dict(steps=self.num_timesteps, episodes=self.model.episode_num, **{self.key: round(score, 4)})
        self.history.append(row)
        print(json.dumps(row), flush=True)
        return True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[1])
    parser.add_argument("--env", choices=ENVS, default="Platform-v0")
    parser.add_argument("--algo", choices=["mpdqn", "pdqn"], default="mpdqn")
    parser.add_argument("--steps", type=int, default=100_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--exploration-fraction", type=float, default=None, help="default: the yml's")
    parser.add_argument("--eval-every", type=int, default=10_000)
    parser.add_argument("--eval-episodes", type=int, default=100)
    parser.add_argument("--final-episodes", type=int, default=1000)
    parser.add_argument(
        "--reference-init",
        action="store_true",
        help="Goal-v0: start the parameter actor at the reference code's linear function of the state "
        "(benchmarks.reference_init) instead of the yml's constant initial_params",
    )
    args = parser.parse_args()
    if args.reference_init and args.env != "Goal-v0":
        parser.error("--reference-init is the reference code's Goal-v0 start; it has none for " + args.env)
    th.set_num_threads(1)

    algo = MPDQN if args.algo == "mpdqn" else PDQN
    kwargs = settings(args.algo, args.env)
    if args.exploration_fraction is not None:
        kwargs["exploration_fraction"] = args.exploration_fraction
    policy: Any = "MlpPolicy"
    if args.reference_init:
        policy, kwargs = with_reference_start(kwargs)
    model = algo(policy, zoo_env(args.algo, args.env, 1, args.seed), seed=args.seed, device="cpu", **kwargs)
    evaluation = GreedyEvaluation(args.env, args.eval_every, args.eval_episodes, 1000 + args.seed)
    start = time.perf_counter()
    model.learn(args.steps, callback=evaluation)
    seconds = time.perf_counter() - start
    final = domains.evaluate(args.env, model, args.final_episodes, 2000 + args.seed)
    key = domains.metric(args.env)
    print(
        json.dumps(
            dict(
                algo=algo.__name__,
                env=args.env,
                reference_init=args.reference_init,
                seed=args.seed,
                env_steps=model.num_timesteps,
                episodes=model.episode_num,
                train_seconds=round(seconds, 1),
                **{f"final_{name}": round(final[name], 4) for name in dict.fromkeys([key, "return_mean"])},
                final_episodes=final["episodes"],
                history=evaluation.history,
            )
        )
    )


if __name__ == "__main__":
    main()
