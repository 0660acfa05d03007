"""``sb3-aac bench``: quick speed figures of this installation, from the installed packages alone: env steps per
second (:mod:`robocup_dribble.speed`) and microseconds per decision of an exported policy next to
``SarsaAAC.predict``. The repository's ``benchmarks/speed/`` scripts measure more (DQN, the growth with the number
of RBFs)."""

from __future__ import annotations

import argparse
import os
import tempfile
from functools import partial
from typing import Any

from sb3_aac.cli.arguments import positive_float
from sb3_aac.common.timing import load_average, microseconds

DECISION_PROFILE = "v11"  # the paper's env, RoboCupDribblePaper-v0
QUICK_CONFIGS: tuple[tuple[str, dict[str, Any]], ...] = (("RbfPolicy", {"n_rbf": 10}), ("RbfPolicy", {"n_rbf": 50}))
FULL_CONFIGS = (
    *QUICK_CONFIGS,
    ("RbfPolicy", {"n_rbf": 30}),
    ("MlpPolicy", {"hidden_units": 2}),
    ("MlpPolicy", {}),
    ("RbfMlpPolicy", {}),
    ("TilePolicy", {}),
)


def add_bench_command(add: Any) -> None:
    """Add ``bench`` through ``add(name, help, example)``."""
    bench = add("bench", "quick speed benchmarks: env steps/s and us per decision of an exported policy", "sb3-aac bench")
    bench.add_argument(
        "--seconds", type=positive_float, default=0.3, help="env benchmark budget per figure (default: %(default)s)"
    )
    bench.add_argument("--only", choices=("env", "runtime"), help="run one of the two benchmarks")
    bench.add_argument("--full", action="store_true", help="more policies and calls in the decision benchmark (a minute)")
    bench.set_defaults(func=cmd_bench)


def cmd_bench(args: argparse.Namespace) -> None:
    if args.only in (None, "env"):
        from robocup_dribble import speed

        print(f"$ python -m robocup_dribble.speed --seconds {args.seconds}", flush=True)
        speed.main(["--seconds", str(args.seconds)])
    if args.only in (None, "runtime"):
        decision_costs(
            FULL_CONFIGS if args.full else QUICK_CONFIGS, calls=5000 if args.full else 500, repeats=5 if args.full else 3
        )


def decision_costs(configs: tuple[tuple[str, dict[str, Any]], ...], calls: int, repeats: int) -> None:
    """Print us per greedy decision on one observation for each (policy, policy_kwargs): the exported policy with its
    fastest backend and numpy-only, and ``SarsaAAC.predict``. The models are untrained: weights do not change the cost."""
    import torch as th

    from robocup_dribble import DribbleVecEnv
    from sb3_aac import RuntimePolicy, SarsaAAC, export_policy

    th.set_num_threads(1)
    env = DribbleVecEnv(8, profile=DECISION_PROFILE)
    env.observation_space.seed(0)
    obs = env.observation_space.sample()  # uniform inside the bounds
    print(f"\nus per decision, one observation (best of {repeats} x {calls} calls; load average {load_average():.2f})")
    print(f"{'policy':32s} {'RuntimePolicy.act':>18s} {'act (numpy only)':>17s} {'SarsaAAC.predict':>17s}")
    with tempfile.TemporaryDirectory() as tmp:
        for policy, kwargs in configs:
            model = SarsaAAC(policy, env, seed=0, policy_kwargs=kwargs)
            path = export_policy(model, os.path.join(tmp, "policy.aacp"))
            fast, reference = RuntimePolicy.load(path), RuntimePolicy.load(path, backend="numpy")
            fast_us = microseconds(partial(fast.act, obs), calls, repeats)
            numpy_us = microseconds(partial(reference.act, obs), calls, repeats)
            predict_us = microseconds(partial(model.predict, obs, deterministic=True), max(calls // 5, 100), repeats)
            label = policy + "".join(f" {k}={v}" for k, v in kwargs.items())
            print(f"{label:32s} {fast_us:13.2f} ({fast.backend}) {numpy_us:17.2f} {predict_us:17.2f}")
