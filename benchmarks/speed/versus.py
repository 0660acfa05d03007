"""
Training throughput of the torch learners in this checkout against an earlier commit of the repository, measured
side by side on the same machine in the same run (the same-run ratio that a speed-up target asks for)::

    python -m benchmarks.speed.versus 20f1865                       # P-DQN, MP-DQN, HybridPPO; 3 pairs each
    python -m benchmarks.speed.versus 20f1865 --algos MPDQN --repeats 5

The earlier commit is checked out into a temporary git worktree (removed at the end). For each repeat and learner,
two processes train at once, one per tree and one thread each (so two free cores give each its own), on
``RoboCupDribblePaper-v0`` in SB3's ``DummyVecEnv`` with one env and the settings of ``benchmarks.speed.training``
(P-DQN and MP-DQN: nets of 64x64, one gradient step per env step on minibatches of 128; HybridPPO: its defaults with
rollouts of 256 steps and minibatches of 256), through the public API both trees share. Each process prints its env
steps per second after a warm-up; the script prints every pair and the median ratio (this checkout / the earlier
one) per learner, with the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from benchmarks.speed.timing import load_average
from benchmarks.speed.training import HPPO_ROLLOUT, PDQN_SETTINGS

ALGOS = ("PDQN", "MPDQN", "HybridPPO")
STEPS = {"PDQN": 3000, "MPDQN": 3000, "HybridPPO": 16 * HPPO_ROLLOUT["n_steps"]}  # timed env steps
WARMUP = {"PDQN": 500, "MPDQN": 500, "HybridPPO": 2 * HPPO_ROLLOUT["n_steps"]}  # untimed env steps first
# The constructor settings of benchmarks.speed.training (P-DQN's nets of 64x64 as its pdqn_model gives them).
SETTINGS: dict[str, dict[str, object]] = {
    "PDQN": {**PDQN_SETTINGS, "policy_kwargs": {"net_arch": [64, 64]}},
    "MPDQN": {**PDQN_SETTINGS, "policy_kwargs": {"net_arch": [64, 64]}},
    "HybridPPO": {**HPPO_ROLLOUT, "seed": 0, "device": "cpu"},
}

# Run with ``python -c`` in either tree: only the API that both trees have; the settings come as JSON.
MEASURE = """
import json, sys, time
import torch as th
th.set_num_threads(1)
import robocup_dribble  # noqa: F401  (registers the env ids)
from stable_baselines3.common.env_util import make_vec_env
import sb3_aac
algo, steps, warmup, settings = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), json.loads(sys.argv[4])
env = make_vec_env("RoboCupDribblePaper-v0", n_envs=1, seed=0)
model = getattr(sb3_aac, algo)("MlpPolicy", env, **settings)
model.learn(warmup)
start = time.perf_counter()
model.learn(steps, reset_num_timesteps=False)
print(steps / (time.perf_counter() - start))
"""


def launch(tree: Path, algo: str, steps: int) -> subprocess.Popen[str]:
    """One measuring process on ``tree``'s packages (its root and its ``envs`` first on the path)."""
    env = {**os.environ, "PYTHONPATH": f"{tree}{os.pathsep}{tree / 'envs'}", "OMP_NUM_THREADS": "1"}
    argv = [algo, str(steps), str(WARMUP[algo]), json.dumps(SETTINGS[algo])]
    return subprocess.Popen([sys.executable, "-c", MEASURE, *argv], cwd=tree, env=env, stdout=subprocess.PIPE, text=True)


def rate(process: subprocess.Popen[str], tree: Path) -> float:
    out, _ = process.communicate()
    if process.returncode != 0:
        raise RuntimeError(f"the measurement on {tree} exited with {process.returncode}")
    return float(out.strip().splitlines()[-1])


def compare(here: Path, there: Path, algos: list[str], repeats: int, scale: float) -> dict[str, float]:
    """Per learner the median of this checkout's rates over the earlier tree's, printing every pair."""
    ratios = {}
    for algo in algos:
        pairs = []
        for _ in range(repeats):
            steps = max(int(STEPS[algo] * scale), 1)
            now, before = launch(here, algo, steps), launch(there, algo, steps)
            pairs.append((rate(now, here), rate(before, there)))
            print(f"  {algo:9s} this checkout {pairs[-1][0]:7.0f}  earlier {pairs[-1][1]:7.0f} env steps/s", flush=True)
        ratios[algo] = statistics.median(now / before for now, before in pairs)
    return ratios


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.speed.versus", description=__doc__.split("\n\n")[0])
    parser.add_argument("revision", help="the earlier commit (anything git rev-parse takes)")
    parser.add_argument("--algos", nargs="+", choices=ALGOS, default=list(ALGOS))
    parser.add_argument("--repeats", type=int, default=3, help="pairs of runs per learner (default 3)")
    parser.add_argument("--scale", type=float, default=1.0, help="multiply the timed env steps (default 1)")
    args = parser.parse_args(argv)
    if args.repeats < 1 or not args.scale > 0:
        parser.error("--repeats must be >= 1 and --scale > 0")
    here = Path(__file__).resolve().parents[2]
    commit = f"{args.revision}^{{commit}}"
    known = subprocess.run(["git", "rev-parse", "--verify", "-q", commit], cwd=here, capture_output=True)
    if known.returncode != 0:
        parser.error(f"{args.revision!r} names no commit of the repository at {here}")
    with tempfile.TemporaryDirectory() as tmp:
        there = Path(tmp) / "earlier"
        subprocess.run(["git", "worktree", "add", "--detach", "-q", str(there), args.revision], cwd=here, check=True)
        try:
            print(f"this checkout against {args.revision}; load average {load_average():.1f}")
            ratios = compare(here, there, args.algos, args.repeats, args.scale)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(there)], cwd=here, check=True)
    for algo, ratio in ratios.items():
        print(f"{algo}: {ratio:.2f}x the earlier commit's env steps/s (median of {args.repeats} pairs)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
