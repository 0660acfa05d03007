"""How fast the dribbling environment steps: one env, SB3's DummyVecEnv of it, and the batched DribbleVecEnv.

Usage: ``python benchmarks/env_speed.py [--profile v19] [--seconds 2]``

Every figure steps the same kind of actions: uniformly random action types and parameters drawn once from a fixed
seed (episodes are short under random actions, so resets are included at their worst rate). Each measurement is
the best of three runs of about ``--seconds`` / 3 each, which damps a shared machine's noise; the ratios compare
runs made seconds apart in the same process. Targets (issue 2): a single-env step <= 30 us, >= 1,000,000
player-steps/s at N = 4096 on one core.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np
from stable_baselines3.common.vec_env import DummyVecEnv

from robocup_dribble import DribbleEnv, DribbleVecEnv, skills

ACTIONS = 4096  # distinct pre-drawn actions, cycled


def random_actions(profile: str, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``n`` random action types and parameters inside the action space's bounds."""
    low, high = skills.parameter_bounds(DribbleEnv(profile=profile).profile)
    return rng.integers(skills.N_ACTION_TYPES, size=n), rng.uniform(low, high, size=(n, skills.N_PARAMS))


def as_tuple(kind: int, params: np.ndarray):
    return int(kind), tuple(params[s].astype(np.float32) for s in skills.PARAM_SLICES)


def best_rate(run: Callable[[int], int], seconds: float) -> float:
    """Largest items/s over three runs; ``run(k)`` does k iterations and returns the items processed."""
    iterations = 1
    while True:  # calibrate the iteration count to about a third of the budget
        start = time.perf_counter()
        run(iterations)
        if time.perf_counter() - start > seconds / 30 or iterations > 1_000_000:
            break
        iterations *= 4
    rates = []
    for _ in range(3):
        start = time.perf_counter()
        items = run(iterations * 10)
        rates.append(items / (time.perf_counter() - start))
    return max(rates)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profile", default="v19", choices=["v19", "v11"])
    parser.add_argument("--seconds", type=float, default=2.0, help="time budget per measurement")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    kinds, params = random_actions(args.profile, ACTIONS, rng)
    tuples = [as_tuple(k, p) for k, p in zip(kinds, params)]

    env = DribbleEnv(profile=args.profile)
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

    dummy = DummyVecEnv([lambda: DribbleEnv(profile=args.profile)])
    dummy.seed(0)
    dummy.reset()

    def dummy_step(k: int) -> int:
        for i in range(k):
            dummy.step([tuples[i % ACTIONS]])
        return k

    single_rate = best_rate(single, args.seconds)
    dummy_rate = best_rate(dummy_step, args.seconds)
    mean_length = counts["steps"] / max(1, counts["episodes"])
    print(f"profile {args.profile}; random actions, {mean_length:.1f} steps per episode on average (resets included)")
    print(f"single DribbleEnv.step:           {single_rate:>12,.0f} steps/s   ({1e6 / single_rate:6.1f} us/step)")
    print(f"SB3 DummyVecEnv([DribbleEnv]):     {dummy_rate:>12,.0f} steps/s   ({1e6 / dummy_rate:6.1f} us/step)")
    for n in (1, 64, 4096):
        vec = DribbleVecEnv(n, profile=args.profile)
        vec.seed(0)
        vec.reset()
        batches = [(np.roll(kinds, -j)[:n] if n <= ACTIONS else rng.integers(4, size=n),
                    np.roll(params, -j, axis=0)[:n] if n <= ACTIONS else rng.uniform(-1, 1, (n, 7))) for j in range(8)]

        def packed(k: int, vec=vec, batches=batches, n=n) -> int:
            for i in range(k):
                vec.step_packed(*batches[i % 8])
            return k * n

        rate = best_rate(packed, args.seconds)
        print(f"DribbleVecEnv({n:>4}).step_packed: {rate:>12,.0f} player-steps/s  ({rate / dummy_rate:6.1f}x DummyVecEnv)")
        if n == 64:
            tuple_batches = [[tuples[(j + i) % ACTIONS] for i in range(n)] for j in range(8)]

            def via_tuples(k: int, vec=vec, tuple_batches=tuple_batches, n=n) -> int:
                for i in range(k):
                    vec.step(tuple_batches[i % 8])
                return k * n

            rate = best_rate(via_tuples, args.seconds)
            print(f"DribbleVecEnv({n:>4}).step (tuples):{rate:>12,.0f} player-steps/s  ({rate / dummy_rate:6.1f}x DummyVecEnv)")


if __name__ == "__main__":
    main()
