"""
Nanoseconds per greedy decision in C (``sb3_aac/runtime/c/aacp.h``, timed by ``benchmarks/speed/c/aacp_speed.c``) next to
:meth:`sb3_aac.RuntimePolicy.act` (numba and numpy-only) in the same run, for each policy kind; and how closely the C
decisions follow ``RuntimePolicy.act`` (type mismatches, largest parameter difference).

Every SarsaAAC policy, and P-DQN / MP-DQN (``"PDQN"``, ``"MPDQN"`` in the policy column), is trained briefly on
``RoboCupDribblePaper-v0`` (the weights' values do not change the cost), exported, and run on the same observations
(uniform over the observation space widened by 20% on each side, as tests/test_c_runtime.py draws them). The C timer
is compiled here with the machine's ``cc`` (``--cflags``, default ``-O2``); each C figure is the best of
``--repeats`` runs of ``--calls`` decisions cycling through the observations (CPU time), each Python figure the best
of ``--repeats`` timeit runs; report the load average with the numbers.

Usage: ``python -m benchmarks.speed.c_runtime_speed [--quick] [--calls 200000] [--repeats 5] [--cflags "-O2"]``

Target: <= 1 us per decision in C for RbfPolicy with 10 RBFs per input, decisions identical to
``RuntimePolicy.act`` (types identical, parameters within 1e-5: also tested in ``tests/test_c_runtime.py``).
"""

from __future__ import annotations

import argparse
import shlex
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

import robocup_dribble
from benchmarks.speed.timing import load_average, microseconds
from benchmarks.speed.runtime_speed import trained_model
from sb3_aac import RuntimePolicy, export_policy
from sb3_aac.runtime.c import header_path

ENV_PROFILE = "v11"  # the paper's env, RoboCupDribblePaper-v0
TIMER = Path(__file__).resolve().parent / "c" / "aacp_speed.c"
N_OBS = 10_000  # observations compared (and cycled through by the timers)
CONFIGS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("RbfPolicy", {"n_rbf": 10}),
    ("RbfPolicy", {"n_rbf": 30}),
    ("RbfPolicy", {"n_rbf": 50}),
    ("MlpPolicy", {"hidden_units": 2}),
    ("MlpPolicy", {}),
    ("RbfMlpPolicy", {}),
    ("TilePolicy", {}),
    ("DeepPolicy", {}),
    ("PDQN", {}),
    ("MPDQN", {}),
    ("MPDQN", {"net_arch": [64, 64]}),
)
QUICK_CONFIGS = (CONFIGS[0], CONFIGS[2], CONFIGS[5], *CONFIGS[6:10])


def build_timer(folder: Path, cflags: list[str]) -> Path:
    compiler = shutil.which("cc")
    if compiler is None:
        raise SystemExit("no C compiler (cc) on PATH")
    out = folder / "aacp_speed"
    command = [compiler, "-std=c99", *cflags, "-I", str(header_path().parent), str(TIMER), "-o", str(out), "-lm"]
    subprocess.run(command, check=True)
    return out


def observations(n: int, seed: int = 1) -> np.ndarray:
    space = robocup_dribble.DribbleEnv(profile=ENV_PROFILE).observation_space
    span = space.high - space.low
    low, high = space.low - 0.2 * span, space.high + 0.2 * span
    return np.random.default_rng(seed).uniform(low, high, (n, *space.shape)).astype(np.float32).astype(np.float64)


def c_decisions(path: Path, obs: np.ndarray, folder: Path) -> tuple[np.ndarray, list[np.ndarray]]:
    """The C runtime's types and parameters for ``obs``, through the test driver's ``act`` mode."""
    driver = Path(__file__).resolve().parents[2] / "tests" / "c_runtime" / "aacp_check.c"
    binary = folder / "aacp_check"
    if not binary.exists():
        command = ["cc", "-std=c99", "-O2", "-I", str(header_path().parent), str(driver), "-o", str(binary), "-lm"]
        subprocess.run(command, check=True)
    obs.tofile(folder / "obs.bin")
    subprocess.run(
        [str(binary), "act", str(path), str(folder / "obs.bin"), str(folder / "out.bin")],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    out = np.fromfile(folder / "out.bin").reshape(len(obs), -1)
    return out[:, 0].astype(np.int64), [row[1:][~np.isnan(row[1:])] for row in out]


def python_us(policy: RuntimePolicy, obs: np.ndarray, calls: int, repeats: int) -> float:
    rows = iter(range(1 << 62))

    def one() -> Any:
        return policy.act(obs[next(rows) % len(obs)])

    return microseconds(one, calls, repeats)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer policies, calls and training steps (seconds)")
    parser.add_argument("--calls", type=int, default=200_000, help="C decisions per timing run")
    parser.add_argument("--repeats", type=int, default=5, help="timing runs per figure (the best is reported)")
    parser.add_argument("--train-steps", type=int, default=2000, help="training steps before export")
    parser.add_argument("--cflags", default="-O2", help="flags the C timer is compiled with (default: %(default)s)")
    args = parser.parse_args(argv)
    if args.quick:
        args.calls, args.repeats, args.train_steps = min(args.calls, 20_000), min(args.repeats, 3), min(args.train_steps, 200)
    python_calls = max(args.calls // 40, 200)
    obs = observations(N_OBS)
    load = load_average()
    print(f"ns per decision, one observation (C: best of {args.repeats} x {args.calls} calls, cc {args.cflags}; "
          f"Python: best of {args.repeats} x {python_calls}; load average {load:.2f})")  # fmt: skip
    print(f"equivalence: {N_OBS} observations per policy, C against RuntimePolicy.act (params cast to float32 there)\n")
    columns = ("C ns", 8), ("act ns (numba)", 15), ("act ns (numpy)", 15), ("type mismatches", 16), ("max |dparam|", 13)
    print(f"{'policy':28s}" + "".join(f" {name:>{width}s}" for name, width in columns))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        timer = build_timer(folder, shlex.split(args.cflags))
        obs.tofile(folder / "timing.bin")
        for policy_name, kwargs in QUICK_CONFIGS if args.quick else CONFIGS:
            model = trained_model(policy_name, args.train_steps, **kwargs)
            path = export_policy(model, folder / "policy.aacp")
            timed = subprocess.run(
                [str(timer), str(path), str(folder / "timing.bin"), str(args.calls), str(args.repeats)],
                capture_output=True, text=True, check=True,
            )  # fmt: skip
            c_ns = float(timed.stdout.split()[0])
            fast, reference = RuntimePolicy.load(path), RuntimePolicy.load(path, backend="numpy")
            fast_ns = 1000 * python_us(fast, obs, python_calls, args.repeats)
            numpy_ns = 1000 * python_us(reference, obs, python_calls, args.repeats)
            types, params = c_decisions(path, obs, folder)
            mismatches, worst = 0, 0.0
            for o, k, p in zip(obs, types, params, strict=True):
                want_k, want_p = fast.act(o)
                if k != want_k:
                    mismatches += 1
                elif len(p):
                    worst = max(worst, float(np.max(np.abs(p - want_p.astype(np.float64)))))
            label = policy_name + "".join(f" {k}={v}" for k, v in kwargs.items())
            label += "" if fast.backend == "numba" else " (numpy)"
            print(f"{label:28s} {c_ns:8.1f} {fast_ns:15.1f} {numpy_ns:15.1f} {mismatches:16d} {worst:13.2e}")


if __name__ == "__main__":
    main()
