"""How fast the dribbling environment steps: one env, SB3's DummyVecEnv of it, and the batched DribbleVecEnv.

Usage: ``python -m robocup_dribble.speed [--profile v19] [--seconds 2]`` (``sb3-aac bench`` runs it too). It ships
with the package so that an installed copy can measure itself.

Two action streams are timed. "random": uniformly random action types and parameters drawn once from a fixed seed;
the ball is lost within about two steps, so resets run at their worst rate. "holding": KICK_POSITION(0.6, 0.4) every
cycle, which keeps the ball beside the player, so episodes run their full 35 actions as under a good dribbler (a
mix of kicks and dashes costs about the same per step). Each figure is items per second of this process's CPU time
(``time.process_time``: on a shared machine wall time would also count the time other processes hold the core;
everything here runs on one thread), the best of three runs of about ``--seconds`` / 3 each; the ratios compare
runs made seconds apart in the same process.

Targets (one core): a single-env step <= 30 us; ``DribbleVecEnv(4096).step_arrays`` (the array path)
>= 3,000,000 player-steps/s with holding actions and >= 1,500,000 with random actions, and SB3's tuple ``step`` at
N = 64 within 3x of ``step_arrays`` at N = 64. ``DribbleVecEnv(4096, perception="match")`` (the match player's
perception, :mod:`robocup_dribble.perception`) is timed next to it, with the ratio. The load average is printed: on
a shared machine the absolute figures still drop with it (caches are shared), the ratios much less.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import DummyVecEnv

from robocup_dribble import DribbleEnv, DribbleVecEnv, skills

ACTIONS = 4096  # distinct pre-drawn actions, cycled
TARGETS = {"random": 1_500_000, "holding": 3_000_000}  # DribbleVecEnv(4096).step_arrays, player-steps/s


def random_actions(profile: str, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``n`` random action types and parameters inside the action space's bounds."""
    low, high = skills.parameter_bounds(DribbleEnv(profile=profile).profile)
    return rng.integers(skills.N_ACTION_TYPES, size=n), rng.uniform(low, high, size=(n, skills.N_PARAMS))


def as_tuple(kind: int, params: np.ndarray) -> tuple[int, tuple[np.ndarray, ...]]:
    return int(kind), tuple(params[s].astype(np.float32) for s in skills.PARAM_SLICES)


def best_rate(run: Callable[[int], int], seconds: float) -> float:
    """Largest items per CPU second over three runs; ``run(k)`` does k iterations and returns the items processed."""
    iterations = 1
    while True:  # calibrate the iteration count to about a third of the budget
        start = time.process_time()
        run(iterations)
        if time.process_time() - start > seconds / 30 or iterations > 1_000_000:
            break
        iterations *= 4
    rates = []
    for _ in range(3):
        start = time.process_time()
        items = run(iterations * 10)
        rates.append(items / (time.process_time() - start))
    return max(rates)


def array_rate(
    profile: str, n: int, kinds: np.ndarray, params: np.ndarray, seconds: float, perception: str = "full"
) -> tuple[DribbleVecEnv, float]:
    """A reset ``DribbleVecEnv(n)`` and its ``step_arrays`` rate (player-steps/s) on the action stream."""
    vec = DribbleVecEnv(n, profile=profile, perception=perception)
    vec.seed(0)
    vec.reset()
    batches = [
        (np.resize(np.roll(kinds, -j), n), np.resize(np.roll(params, -j, axis=0), (n, skills.N_PARAMS))) for j in range(8)
    ]

    def arrays(k: int) -> int:
        for i in range(k):
            vec.step_arrays(*batches[i % 8])
        return k * n

    return vec, best_rate(arrays, seconds)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profile", default="v19", choices=["v19", "v11"])
    parser.add_argument("--seconds", type=float, default=2.0, help="time budget per measurement")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(0)
    kinds, params = random_actions(args.profile, ACTIONS, rng)
    holding = np.zeros(skills.N_PARAMS)
    holding[[skills.PARAM_POSITION_X, skills.PARAM_POSITION_Y]] = 0.6, 0.4
    streams = {
        "random": (kinds, params),
        "holding": (np.full(ACTIONS, skills.KICK_POSITION), np.tile(holding, (ACTIONS, 1))),
    }
    print(
        f"profile {args.profile}; best of 3 runs per figure; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"
    )
    for name, (stream_kinds, stream_params) in streams.items():
        print(f"\n== {name} actions ==")
        measure(name, args.profile, stream_kinds, stream_params, args.seconds)


def measure(name: str, profile: str, kinds: np.ndarray, params: np.ndarray, seconds: float) -> None:
    """Print single-env, DummyVecEnv and batched figures for one action stream."""
    tuples = [as_tuple(k, p) for k, p in zip(kinds, params, strict=True)]
    env = DribbleEnv(profile=profile)
    env.reset(seed=0)
    counts = {"steps": 0, "episodes": 0}

    def single(k: int) -> int:
        for i in range(k):
            _, _, terminated, truncated, _ = env.step(tuples[i % ACTIONS])
            if terminated or truncated:
                env.reset()
                counts["episodes"] += 1
        counts["steps"] += k
        return k

    dummy = DummyVecEnv([lambda: DribbleEnv(profile=profile)])
    dummy.seed(0)
    dummy.reset()

    def dummy_step(k: int) -> int:
        for i in range(k):
            dummy.step([tuples[i % ACTIONS]])  # type: ignore[arg-type]  # SB3 hints Box/Discrete arrays; Tuple actions are lists
        return k

    single_rate = best_rate(single, seconds)
    dummy_rate = best_rate(dummy_step, seconds)
    print(f"mean episode length {counts['steps'] / max(1, counts['episodes']):.1f} steps")
    print(f"single DribbleEnv.step:             {single_rate:>12,.0f} steps/s         ({1e6 / single_rate:6.1f} us/step)")
    print(f"SB3 DummyVecEnv([DribbleEnv]).step: {dummy_rate:>12,.0f} steps/s         ({1e6 / dummy_rate:6.1f} us/step)")
    array_rates = {}
    for n in (1, 64, 4096):
        vec, rate = array_rate(profile, n, kinds, params, seconds)
        array_rates[n] = rate
        print(f"DribbleVecEnv({n:>4}).step_arrays:    {rate:>12,.0f} player-steps/s  ({rate / dummy_rate:6.1f}x DummyVecEnv)")
        if n == 4096:
            _, perceiving = array_rate(profile, n, kinds, params, seconds, "match")
            print(
                f"  with perception='match':           {perceiving:>12,.0f} player-steps/s  "
                f"({perceiving / rate:.2f}x perception='full')"
            )
        if n == 64:
            tuple_batches = [[tuples[(j + i) % ACTIONS] for i in range(n)] for j in range(8)]

            def via_tuples(k: int, vec: DribbleVecEnv = vec, tuple_batches: list[Any] = tuple_batches, n: int = n) -> int:
                for i in range(k):
                    vec.step(tuple_batches[i % 8])
                return k * n

            rate = best_rate(via_tuples, seconds)
            print(
                f"DribbleVecEnv({n:>4}).step (tuples):  {rate:>12,.0f} player-steps/s  "
                f"({rate / dummy_rate:6.1f}x DummyVecEnv, "
                f"step_arrays is {array_rates[64] / rate:.2f}x faster; target <= 3x)"
            )
    target = TARGETS.get(name)
    if target:
        verdict = "met" if array_rates[4096] >= target else "NOT met"
        print(f"target DribbleVecEnv(4096).step_arrays >= {target:,.0f} player-steps/s: {verdict}")


if __name__ == "__main__":
    main()
