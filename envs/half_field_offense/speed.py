"""How fast Half Field Offense steps: the single Gymnasium env, and the batched vector env's array path.

Usage: ``python -m half_field_offense.speed [--seconds 2]``.

Three action streams: "holding" (DASH(100, 0) every cycle: the agent runs; trials end when the ball has been
untouched for 100 cycles, so restarts are rare), "random" (uniformly random actions drawn once from a fixed seed),
and "agent" (the hand-coded offense agent choosing every action from the observations, its cost included: whole
trials that end in goals). Each figure is items per second of this process's CPU time, the best of three runs
(:func:`robocup_dribble.speed.best_rate`).

Targets (one core): ``HalfFieldOffenseVecEnv(4096).step_arrays`` >= 1,000,000 agent-steps/s with holding actions,
and >= 20,000 steps/s through the single env's Gymnasium ``step``.
"""

from __future__ import annotations

import argparse
import os

import numpy as np

from half_field_offense import actions
from half_field_offense.agent import HandCodedOffense
from half_field_offense.env import HalfFieldOffenseEnv
from half_field_offense.vec_env import HalfFieldOffenseVecEnv
from robocup_dribble.speed import best_rate

ACTIONS = 4096  # distinct pre-drawn actions, cycled
TARGETS = {"vector, holding": 1_000_000, "single": 20_000}


def streams(n: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The fixed action streams (``n`` action types and parameters each)."""
    rng = np.random.default_rng(0)
    holding = np.zeros(actions.n_params(False))
    holding[actions.PARAM_STARTS[actions.DASH]] = 100.0
    return {
        "holding": (np.full(n, actions.DASH), np.tile(holding, (n, 1))),
        "random": (rng.integers(0, 3, n), rng.uniform(actions.PARAM_LOW[:5], actions.PARAM_HIGH[:5], (n, 5))),
    }


def vector_rate(n: int, kinds: np.ndarray | None, params: np.ndarray | None, seconds: float) -> float:
    """``HalfFieldOffenseVecEnv(n).step_arrays`` agent-steps/s on a stream (the hand-coded agent's when None)."""
    vec = HalfFieldOffenseVecEnv(n)
    vec.seed(0)
    obs = np.asarray(vec.reset())
    agent = HandCodedOffense()

    def run(k: int) -> int:
        nonlocal obs
        for i in range(k):
            if kinds is None or params is None:
                obs = vec.step_arrays(*agent.act(obs)).observations
            else:
                j = (i * 7) % (len(kinds) - n + 1)
                vec.step_arrays(kinds[j : j + n], params[j : j + n])
        return k * n

    return best_rate(run, seconds)


def single_rate(kinds: np.ndarray, params: np.ndarray, seconds: float) -> float:
    """The single env's Gymnasium ``step`` (restarting ended trials) steps/s on a stream."""
    env = HalfFieldOffenseEnv()
    env.reset(seed=0)
    tuples = [
        (int(k), tuple(p[s].astype(np.float32) for s in actions.PARAM_SLICES[:3])) for k, p in zip(kinds, params, strict=True)
    ]

    def run(k: int) -> int:
        for i in range(k):
            _, _, terminated, truncated, _ = env.step(tuples[i % len(tuples)])
            if terminated or truncated:
                env.reset()
        return k

    return best_rate(run, seconds)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=2.0, help="time budget per measurement")
    args = parser.parse_args(argv)
    print(f"best of 3 runs per figure; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    figures = {}
    for name, (kinds, params) in streams(ACTIONS + 4096).items():
        figures[f"single, {name}"] = single_rate(kinds, params, args.seconds)
        print(f"single HalfFieldOffenseEnv.step, {name:8}  {figures[f'single, {name}']:>12,.0f} steps/s")
        for n in (64, 4096):
            rate = vector_rate(n, kinds, params, args.seconds)
            figures[f"vector, {name}"] = rate
            print(f"HalfFieldOffenseVecEnv({n:>4}).step_arrays, {name:8} {rate:>12,.0f} agent-steps/s")
    rate = vector_rate(4096, None, None, args.seconds)
    print(f"HalfFieldOffenseVecEnv(4096) with the hand-coded agent     {rate:>12,.0f} agent-steps/s (agent included)")
    single = min(figures["single, holding"], figures["single, random"])
    for name, value in (("vector, holding", figures["vector, holding"]), ("single", single)):
        verdict = "met" if value >= TARGETS[name] else "NOT met"
        print(f"target {name} >= {TARGETS[name]:,.0f}: {verdict} ({value:,.0f})")


if __name__ == "__main__":
    main()
