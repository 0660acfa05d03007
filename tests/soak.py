"""Soak test, to rerun before a release (not in CI): long runs that look for slow faults no unit test sees.

A script next to the test suite, not a collected test: it takes half an hour, past what CI runs (the suite's slow
tests still run in CI), and it is no part of the benchmark grid.

Usage::

    python tests/soak.py                                      # 10M lane-steps, 1M training steps (~30+ min)
    python tests/soak.py --lane-steps 2000000 --train-steps 100000   # scaled down

Two phases, each reporting the non-finite values it met, the growth of the resident memory (RSS) from the end of a
warm-up to the end, and the files left behind:

1. **train**: SarsaAAC (``RbfPolicy``) on ``DribbleVecEnv(16)`` for ``--train-steps`` steps; every ``--save-every``
   steps the model is saved and exported (atomically) into a scratch directory and both files are loaded back.
   Counts: NaN/inf in the final weights; files in the scratch directory besides ``model.zip`` and ``policy.aacp``.
2. **step**: ``DribbleVecEnv(--lanes)`` for ``--lane-steps`` lane-steps, alternating blocks of random actions
   (types uniform, parameters uniform over their bounds widened by 10% on each side, so clipping is exercised too)
   and the trained policy's greedy actions (:class:`sb3_aac.RuntimePolicy` ``act_batch``). Uses the array path
   (``step_arrays``) when the env offers it, else SB3's ``step``. Counts NaN/inf in observations and rewards.

A healthy run prints zeros for every count and an RSS growth of a few MB at most.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import torch as th  # noqa: E402
from stable_baselines3.common.callbacks import BaseCallback  # noqa: E402

from robocup_dribble import DribbleVecEnv  # noqa: E402
from sb3_aac import RuntimePolicy, SarsaAAC, export_policy  # noqa: E402
from sb3_aac.common.array_env import array_path  # noqa: E402
from sb3_aac.common.model_files import check_model_file  # noqa: E402
from sb3_aac.common.spaces import ParameterizedActionSpec  # noqa: E402

WARM_UP_SHARE = 0.05  # RSS growth is measured from the end of this share of each phase
RANDOM_WIDEN = 0.1  # random parameters reach 10% beyond each bound (the env clips them)
BLOCK_STEPS = 50  # env steps per block of random or learned actions


def rss_mb() -> float:
    """The current resident set size in MB (Linux /proc; elsewhere the peak, from getrusage)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / (1024 * 1024 if sys.platform == "darwin" else 1024)


class SaveAndReload(BaseCallback):
    """Every ``every`` steps: save and export into ``folder``, load both back; remember the RSS after warm-up."""

    def __init__(self, folder: Path, every: int, warm_up_steps: int):
        super().__init__()
        self.folder, self.every, self.warm_up_steps = folder, every, warm_up_steps
        self.next_save, self.saves, self.rss_after_warm_up = every, 0, None

    def _on_step(self) -> bool:
        if self.rss_after_warm_up is None and self.num_timesteps >= self.warm_up_steps:
            self.rss_after_warm_up = rss_mb()
        if self.num_timesteps >= self.next_save:
            self.model.save(self.folder / "model.zip")
            export_policy(self.model, self.folder / "policy.aacp")
            check_model_file(self.folder / "model.zip")
            RuntimePolicy.load(self.folder / "policy.aacp")
            self.saves += 1
            self.next_save += self.every
        return True


def soak_training(steps: int, save_every: int, profile: str, seed: int, folder: Path) -> tuple[dict[str, Any], Path]:
    env = DribbleVecEnv(16, profile=profile)
    model = SarsaAAC("RbfPolicy", env, seed=seed)
    callback = SaveAndReload(folder, save_every, int(WARM_UP_SHARE * steps))
    start = time.perf_counter()
    model.learn(steps, callback=callback)
    seconds = time.perf_counter() - start
    policy_path = export_policy(model, folder / "policy.aacp")
    non_finite = sum(int((~th.isfinite(p)).sum()) for p in model.policy.parameters())
    expected = {"model.zip", "policy.aacp"}
    left = sorted(p.name for p in folder.iterdir() if p.name not in expected)
    return {
        "steps": int(model.num_timesteps),
        "episodes": int(model.episode_num),
        "seconds": round(seconds, 1),
        "steps_per_s": round(model.num_timesteps / seconds),
        "saves_and_reloads": callback.saves,
        "non_finite_weights": non_finite,
        "rss_growth_mb": round(rss_mb() - (callback.rss_after_warm_up or rss_mb()), 1),
        "files_left": left,
    }, policy_path


def soak_stepping(lane_steps: int, lanes: int, policy: RuntimePolicy, profile: str, seed: int) -> dict[str, Any]:
    env = DribbleVecEnv(lanes, profile=profile)
    env.seed(seed)
    obs = env.reset()
    spec = ParameterizedActionSpec.from_space(env.action_space)
    fast = array_path(env)
    rng = np.random.default_rng(seed)
    low, high = spec.low, spec.high
    n_steps = max(1, lane_steps // lanes)
    warm_up = int(WARM_UP_SHARE * n_steps)
    non_finite = episodes = 0
    rss_start = rss_mb()
    start = time.perf_counter()
    for step in range(n_steps):
        if step == warm_up:
            rss_start = rss_mb()
        if (step // BLOCK_STEPS) % 2 == 0:
            types = rng.integers(0, spec.n_types, lanes)
            params = low + (high - low) * rng.uniform(-RANDOM_WIDEN, 1 + RANDOM_WIDEN, (lanes, spec.n_params))
        else:
            types, params = policy.act_batch(obs)
            types = types - policy.type_start
        if fast is not None:
            result = fast.step_arrays(types, params)
            obs, rewards, ended = result.observations, result.rewards, result.terminated | result.truncated
        else:
            obs, rewards, ended, _ = env.step(spec.to_env(types, spec.scale(params)))
        non_finite += int((~np.isfinite(obs)).sum()) + int((~np.isfinite(rewards)).sum())
        episodes += int(np.sum(ended))
    seconds = time.perf_counter() - start
    return {
        "lane_steps": n_steps * lanes,
        "lanes": lanes,
        "path": "step_arrays" if fast is not None else "VecEnv.step",
        "episodes": episodes,
        "seconds": round(seconds, 1),
        "lane_steps_per_s": round(n_steps * lanes / seconds),
        "non_finite_values": non_finite,
        "rss_growth_mb": round(rss_mb() - rss_start, 1),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python tests/soak.py", description=__doc__.split("\n\n")[0])
    parser.add_argument("--lane-steps", type=int, default=10_000_000, help="env lane-steps of the step phase")
    parser.add_argument("--lanes", type=int, default=1024, help="lanes of the stepped DribbleVecEnv")
    parser.add_argument("--train-steps", type=int, default=1_000_000, help="SarsaAAC training steps")
    parser.add_argument("--save-every", type=int, default=100_000, help="training steps between save/export/reload")
    parser.add_argument("--profile", default="v11", choices=("v11", "v19"), help="server profile")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    th.set_num_threads(1)
    print(f"$ python tests/soak.py {' '.join(sys.argv[1:] if argv is None else argv)}")
    rss_begin = rss_mb()
    with tempfile.TemporaryDirectory(prefix="sb3-aac-soak-") as scratch:
        folder = Path(scratch)
        training, policy_path = soak_training(args.train_steps, args.save_every, args.profile, args.seed, folder)
        print("train:", training, flush=True)
        stepping = soak_stepping(args.lane_steps, args.lanes, RuntimePolicy.load(policy_path), args.profile, args.seed)
        print("step: ", stepping, flush=True)
    problems = training["non_finite_weights"] + stepping["non_finite_values"] + len(training["files_left"])
    print(f"non-finite values {training['non_finite_weights'] + stepping['non_finite_values']}, "
          f"files left {len(training['files_left'])}, RSS {rss_begin:.0f} -> {rss_mb():.0f} MB "
          f"(growth after warm-up: train {training['rss_growth_mb']} MB, step {stepping['rss_growth_mb']} MB)")  # fmt: skip
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
