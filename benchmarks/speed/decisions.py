"""
Microseconds per greedy decision of an exported policy next to the model's ``predict``; one measurement per
subcommand (``python -m benchmarks.speed.decisions WHICH --help`` for its options):

* ``python``: :class:`sb3_aac.RuntimePolicy` (numba and numpy-only) next to ``predict`` and SB3's ``DQN.predict``, and
  its growth with the number of RBFs;
* ``c``: the C runtime (``sb3_aac/runtime/c/aacp.h``, timed by ``benchmarks/speed/c/aacp_speed.c``) next to
  ``RuntimePolicy.act``, and how closely its decisions follow.

Usage: ``python -m benchmarks.speed.decisions python|c [options]``
"""

from __future__ import annotations

import argparse
import os
import shlex
import shutil
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3 import DQN

import robocup_dribble
from benchmarks.speed.timing import load_average, microseconds
from sb3_aac import MPDQN, PDQN, RuntimePolicy, SarsaAAC, export_policy
from sb3_aac.runtime.c import header_path

PYTHON_DOC = """Microseconds per greedy decision on one observation: an exported policy
(:class:`sb3_aac.RuntimePolicy`) next to the model's ``predict`` and SB3's ``DQN.predict``, in the same run; and how
the exported policy's cost grows with the
number of RBFs (the paper's O(n), Uc-Cetina 2013 Sec. 4.3).

Every SarsaAAC policy, and P-DQN / MP-DQN, is trained briefly on ``RoboCupDribblePaper-v0`` (the weights' values do
not change the cost), exported, and loaded twice: with the numba backend (``"auto"`` when numba is installed) and with the
numpy-only reference. DQN (default ``MlpPolicy``, two hidden layers of 64) acts on the same observation space with
a ``Discrete`` grid of 4 types x 9 parameter values standing in for the dribbling actions. Each figure is the best
of ``--repeats`` runs of ``--calls`` decisions, which damps a shared machine's noise; report the load average with
the numbers.

Usage: ``python -m benchmarks.speed.decisions python [--quick] [--calls 5000] [--repeats 5]``

Targets: <= 10 us per decision for the RBF policy with 10, 30 and 50 RBFs per input; <= 5 us at 50 RBFs
per input with the default RBF window; <= 10 us for ``DeepPolicy`` (default networks, two hidden layers of 64);
decisions identical to ``model.predict`` (tested in ``tests/test_export.py``, ``tests/test_export_networks.py`` and
``tests/test_pdqn_export.py``). P-DQN / MP-DQN have no target of their own; their rows show what the two networks in
series (and MP-DQN's K passes) cost."""

C_DOC = """Nanoseconds per greedy decision in C (``sb3_aac/runtime/c/aacp.h``, timed by
``benchmarks/speed/c/aacp_speed.c``) next to :meth:`sb3_aac.RuntimePolicy.act` (numba and numpy-only) in the same
run, for each policy kind; and how closely the C
decisions follow ``RuntimePolicy.act`` (type mismatches, largest parameter difference).

Every SarsaAAC policy, and P-DQN / MP-DQN (``"PDQN"``, ``"MPDQN"`` in the policy column), is trained briefly on
``RoboCupDribblePaper-v0`` (the weights' values do not change the cost), exported, and run on the same observations
(uniform over the observation space widened by 20% on each side, as tests/test_c_runtime.py draws them). The C timer
is compiled here with the machine's ``cc`` (``--cflags``, default ``-O2``); each C figure is the best of
``--repeats`` runs of ``--calls`` decisions cycling through the observations (CPU time), each Python figure the best
of ``--repeats`` timeit runs; report the load average with the numbers.

Usage: ``python -m benchmarks.speed.decisions c [--quick] [--calls 200000] [--repeats 5] [--cflags "-O2"]``

Target: <= 1 us per decision in C for RbfPolicy with 10 RBFs per input, decisions identical to
``RuntimePolicy.act`` (types identical, parameters within 1e-5: also tested in ``tests/test_c_runtime.py``)."""


# ---------------------------------------------------------------- python

ENV_PROFILE = "v11"  # the paper's env, RoboCupDribblePaper-v0


DQN_ACTIONS = 36  # 4 types x 9 parameter values


class ObservationOnlyEnv(gym.Env):
    """The dribbling observation space with a Discrete action grid, just to build a DQN of the right size."""

    def __init__(self, observation_space: spaces.Box):
        self.observation_space, self.action_space = observation_space, spaces.Discrete(DQN_ACTIONS)

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        return self.observation_space.sample(), {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict]:
        return self.observation_space.sample(), 0.0, False, False, {}


def trained_model(policy: str, train_steps: int, **policy_kwargs: Any) -> SarsaAAC | PDQN:
    """A SarsaAAC model with ``policy``, or for ``policy`` "PDQN" / "MPDQN" that algorithm's, trained ``train_steps``
    env steps (0: its initial weights)."""
    env = robocup_dribble.DribbleVecEnv(8, profile=ENV_PROFILE)
    env.seed(0)
    if policy in ("PDQN", "MPDQN"):
        algorithm = PDQN if policy == "PDQN" else MPDQN
        model: SarsaAAC | PDQN = algorithm("MlpPolicy", env, seed=0, learning_starts=100, policy_kwargs=policy_kwargs)
    else:
        model = SarsaAAC(policy, env, seed=0, policy_kwargs=policy_kwargs)
    return model.learn(train_steps) if train_steps > 0 else model


def python_main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(prog="decisions python", description=PYTHON_DOC)
    parser.add_argument("--quick", action="store_true", help="fewer calls, sizes and training steps (a few seconds)")
    parser.add_argument("--calls", type=int, default=5000, help="decisions per timing run")
    parser.add_argument("--repeats", type=int, default=5, help="timing runs per figure (the best is reported)")
    parser.add_argument("--train-steps", type=int, default=2000, help="training steps before export")
    args = parser.parse_args(argv)
    if args.quick:
        args.calls, args.repeats, args.train_steps = min(args.calls, 500), min(args.repeats, 3), min(args.train_steps, 200)
    th.set_num_threads(1)
    rng = np.random.default_rng(0)
    obs_space = robocup_dribble.DribbleEnv(profile=ENV_PROFILE).observation_space
    obs = rng.uniform(obs_space.low, obs_space.high).astype(np.float32)
    print(f"us per decision, one observation (best of {args.repeats} x {args.calls} calls; load average {load_average():.2f})")

    configs: list[tuple[str, dict[str, Any]]] = [
        ("RbfPolicy", {"n_rbf": n}) for n in ((10, 50) if args.quick else (10, 30, 50))
    ]
    configs += [("DeepPolicy", {}), ("PDQN", {}), ("MPDQN", {})]
    if not args.quick:
        configs += [("MlpPolicy", {"hidden_units": 2}), ("MlpPolicy", {}), ("RbfMlpPolicy", {})]
        configs += [("DeepPolicy", {"net_arch": [128, 128]}), ("MPDQN", {"net_arch": [64, 64]})]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for policy, kwargs in configs:
            model = trained_model(policy, args.train_steps, **kwargs)
            path = export_policy(model, os.path.join(tmp, "policy.aacp"))
            fast, reference = RuntimePolicy.load(path), RuntimePolicy.load(path, backend="numpy")
            label = policy + "".join(f" {k}={v}" for k, v in kwargs.items())
            rows.append(
                (
                    label,
                    microseconds(lambda r=fast: r.act(obs), args.calls, args.repeats),
                    microseconds(lambda r=reference: r.act(obs), args.calls, args.repeats),
                    microseconds(lambda m=model: m.predict(obs, deterministic=True), max(args.calls // 5, 100), args.repeats),
                    fast.backend,
                )
            )
        dqn = DQN("MlpPolicy", ObservationOnlyEnv(obs_space), seed=0, device="cpu")
        dqn_us = microseconds(lambda: dqn.predict(obs, deterministic=True), max(args.calls // 5, 100), args.repeats)

        print(f"\n{'policy':32s} {'RuntimePolicy.act':>18s} {'act (numpy only)':>17s} {'model.predict':>17s}")
        for label, fast_us, numpy_us, predict_us, backend in rows:
            print(f"{label:32s} {fast_us:13.2f} ({backend}) {numpy_us:17.2f} {predict_us:17.2f}")
        print(f"{'SB3 DQN.predict (MLP 64x64)':32s} {'':18s} {'':17s} {dqn_us:17.2f}")

        sizes = (5, 10, 25, 50, 100) if args.quick else (5, 10, 20, 30, 50, 100, 200)
        print("\nScaling with the number of RBFs (RbfPolicy; n = 10 inputs x RBFs per input features per approximator)")
        print(f"{'RBFs/input':>10s} {'n':>6s} {'act us':>8s} {'numpy us':>9s}")
        features, costs = [], []
        for n_rbf in sizes:
            model = trained_model("RbfPolicy", 0 if args.quick else 200, n_rbf=n_rbf)
            path = export_policy(model, os.path.join(tmp, "policy.aacp"))
            fast, reference = RuntimePolicy.load(path), RuntimePolicy.load(path, backend="numpy")
            fast_us = microseconds(lambda r=fast: r.act(obs), args.calls, args.repeats)
            numpy_us = microseconds(lambda r=reference: r.act(obs), args.calls, args.repeats)
            n = obs_space.shape[0] * n_rbf
            features.append(n)
            costs.append(fast_us)
            print(f"{n_rbf:10d} {n:6d} {fast_us:8.2f} {numpy_us:9.2f}")
        slope, intercept = np.polyfit(features, costs, 1)
        fitted = np.polyval([slope, intercept], features)
        r2 = 1 - np.sum((np.array(costs) - fitted) ** 2) / np.sum((np.array(costs) - np.mean(costs)) ** 2)
        print(f"linear fit of act: {intercept:.2f} us + {1000 * slope:.2f} ns x n   (R^2 = {r2:.3f}; O(n) if close to 1)")


# ---------------------------------------------------------------- c


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


def c_main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(prog="decisions c", description=C_DOC)
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


MEASUREMENTS: dict[str, Callable[[list[str]], None]] = {"python": python_main, "c": c_main}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[1], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("which", choices=list(MEASUREMENTS))
    parser.add_argument("options", nargs=argparse.REMAINDER, help="the measurement's options (WHICH --help)")
    args = parser.parse_args(argv)
    MEASUREMENTS[args.which](args.options)


if __name__ == "__main__":
    main()
