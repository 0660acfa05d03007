"""Run the benchmark grid: SarsaAAC's approximators and SB3 baselines on the dribbling envs, resumable and parallel.

Usage::

    python -m benchmarks.run --preset quick|full [--out DIR] [--workers 2] [--only PATTERN[,PATTERN...]]
                             [--engine local|ray [--address ADDR]] [--allow-dirty]
    python -m benchmarks.run --reliability [--out DIR]      # the reliability test of the best policies
    python -m benchmarks.report DIR                         # report.md and figures from the cell files

Each cell (env id x algorithm x config x seed x budget, see :mod:`benchmarks.presets`) trains through SB3's
``learn`` with a TensorBoard logger (``DIR/tb/<cell_id>``) and :class:`DribbleEvalCallback`, which every
``eval_every`` training episodes plays the same ``eval_episodes`` greedy episodes (``evaluate_dribbling`` with a fixed
seed) and logs ``eval/distance_mean``, ``eval/reach20_share`` and ``eval/ball_loss_rate``. A finished cell saves its
model (``DIR/models/<cell_id>.zip``) and then its results (``DIR/cells/<cell_id>.json``), each written to a temporary
file and moved into place with ``os.replace``, so a cell file exists only if the cell finished. A rerun skips the
cells that have one: an interrupted sweep loses only the cells that were running. A cell that raises leaves
``DIR/errors/<cell_id>.txt`` (the traceback) and is tried again by the next run.

Cells run in worker processes (``ProcessPoolExecutor``, spawn); each pins torch and BLAS to one thread, so two
workers use two cores. ``--workers 1`` runs the cells in this process. ``--engine ray`` runs each cell as a Ray task
instead, on a Ray cluster (``--address``) or a Ray instance started here with ``--workers`` CPUs; the driver writes
every cell's files (:mod:`benchmarks.engines`).

A sweep refuses to start when tracked files have uncommitted changes, unless ``--allow-dirty`` (recorded in every
cell with the commit, :mod:`benchmarks.provenance`); ``DIR/runs.jsonl`` logs every invocation when it starts and
when it ends, interrupted ones too.
"""

from __future__ import annotations

import argparse
import contextlib
import fcntl
import json
import multiprocessing
import os
import platform
import shlex
import shutil
import signal
import statistics
import sys
import threading
import time
import traceback
import warnings
from collections.abc import Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any

# One BLAS thread per process: with two workers on two cores, OpenBLAS's own threads make some SarsaAAC configs
# (RbfMlpPolicy with 20 hidden units) up to 7x slower. Set before numpy is imported here; spawned workers inherit it.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import torch as th  # noqa: E402
from stable_baselines3.common.callbacks import BaseCallback  # noqa: E402
from stable_baselines3.common.logger import configure  # noqa: E402

import robocup_dribble  # noqa: E402, F401  (registers the env ids)
from benchmarks.engines import CellEngine, RayEngine  # noqa: E402
from benchmarks import cells  # noqa: E402
from benchmarks.presets import (  # noqa: E402
    BASELINES,
    ENV_PROFILE,
    EVAL_SEED,
    FINAL_SEED,
    ON_POLICY,
    PRESETS,
    RELIABILITY_SEED,
    SARSA_CONFIGS,
    SARSA_N_ENVS,
    Cell,
    build_cells,
    select,
)
from benchmarks.provenance import (  # noqa: E402
    ENV_VAR,
    REPO,
    DirtyTreeError,
    cell_provenance,
    git_state,
    invocation_provenance,
    logged_invocation,
    new_invocation_id,
    require_clean_tree,
)
from robocup_dribble import DribbleVecEnv  # noqa: E402
from robocup_dribble.evaluation import DribbleReport, evaluate_dribbling, reliability_test, running_ceiling  # noqa: E402
from sb3_aac.common import output_files  # noqa: E402
from sb3_aac.common.output_files import replaced_atomically  # noqa: E402

PARENT_POLL_SECONDS = 0.2  # how often a worker checks that the driver still lives
REACH_METRES = 20.0  # the paper's "at least around 20 meters with high reliability" (§4.1)
PREDICT_CALLS = 300  # single-observation predict calls timed per cell (the median is reported)
RELIABILITY_PLAYERS = 10_000
HIST_BIN_METRES = 1.0
HIST_MAX_METRES = 60

# ---------------------------------------------------------------------------------------------------------------------
# Files
# ---------------------------------------------------------------------------------------------------------------------


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (flushed to disk before the rename)."""
    with replaced_atomically(path) as tmp:
        tmp.write_text(text)


def atomic_write_json(path: Path, data: Any) -> None:
    """Serialise first (an unserialisable value raises before anything is written), then write atomically."""
    atomic_write_text(path, json.dumps(data, indent=1, allow_nan=False) + "\n")


def save_model_atomic(model: Any, path: Path) -> None:
    with replaced_atomically(path, suffix=".zip") as tmp:
        model.save(tmp)


def cell_path(out: Path, cell: Cell) -> Path:
    return cells.cell_path(out, cell.cell_id)


def load_cells(out: Path) -> list[dict[str, Any]]:
    """The results of every finished cell in ``out/cells`` (temporaries skipped; a damaged file is named and skipped)."""
    return cells.load_cells(out)


def remove_stale_temporaries(out: Path) -> None:
    """Temporary files a killed process left behind; a live process's temporaries (a concurrent run) stay."""
    for sub in ("cells", "models", "errors"):
        output_files.remove_stale_temporaries(out / sub)


@contextlib.contextmanager
def cell_lock(out: Path, cell_id: str) -> Iterator[bool]:
    """
    Hold ``DIR/locks/<cell_id>.lock`` while a cell runs: yields False if another live process holds it (that
    cell is running elsewhere, so its TensorBoard folder and temporaries must not be touched). The lock is an
    ``flock``, released by the system when its holder dies, so a killed run never blocks a cell.
    """
    lock_dir = out / "locks"
    lock_dir.mkdir(parents=True, exist_ok=True)
    with open(lock_dir / f"{cell_id}.lock", "a") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            yield False
            return
        try:
            yield True
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


# ---------------------------------------------------------------------------------------------------------------------
# Environment description (versions, machine) recorded in every cell
# ---------------------------------------------------------------------------------------------------------------------


def versions() -> dict[str, str]:
    import gymnasium
    import numba
    import stable_baselines3

    import sb3_aac

    return {
        "python": platform.python_version(),
        "sb3_aac": sb3_aac.__version__,
        "git_commit": git_state().label,  # of the checkout this process imports (a Ray worker's own)
        "stable_baselines3": stable_baselines3.__version__,
        "torch": th.__version__,
        "numpy": np.__version__,
        "gymnasium": gymnasium.__version__,
        "numba": numba.__version__,
    }


def machine() -> dict[str, Any]:
    cpu = platform.processor() or platform.machine()
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    return {"cpu": cpu, "cores": os.cpu_count(), "platform": platform.platform(), "torch_threads": th.get_num_threads()}


def loadavg() -> float | None:
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return None


# ---------------------------------------------------------------------------------------------------------------------
# Evaluation
# ---------------------------------------------------------------------------------------------------------------------


def distance_stats(d: np.ndarray) -> dict[str, float]:
    """Mean, median and max of per-episode metres (the keys every result file uses)."""
    return {"distance_mean": float(np.mean(d)), "distance_median": float(np.median(d)), "distance_max": float(np.max(d))}


def report_summary(report: DribbleReport) -> dict[str, float]:
    d = report.distances
    return {
        "episodes": len(d),
        **distance_stats(d),
        "reach20_share": report.share_reaching(REACH_METRES),
        "ball_loss_rate": report.loss_rate,
    }


def predict_microseconds(policy: Any, profile: str, calls: int = PREDICT_CALLS) -> float:
    """Median wall time of ``policy.predict`` on one observation (deterministic), in microseconds."""
    env = DribbleVecEnv(calls, profile=profile)
    env.seed(FINAL_SEED)
    observations = env.reset()
    policy.predict(observations[0], deterministic=True)  # warm-up (lazy setup, caches)
    times = []
    for obs in observations:
        start = time.perf_counter_ns()
        policy.predict(obs, deterministic=True)
        times.append(time.perf_counter_ns() - start)
    return statistics.median(times) / 1e3


class DribbleEvalCallback(BaseCallback):
    """Every ``eval_every`` training episodes: greedy metres on a fixed evaluation set, to the logger and a curve.

    Episodes are counted from the ``dones`` of each ``env.step`` (SarsaAAC's and SB3's on-/off-policy loops all
    expose them), so the same callback serves every algorithm. The first point is taken before training.

    :param policy: what ``evaluate_dribbling`` calls ``predict`` on (the model, or an adapter around it)
    :param profile: the env's server profile
    :param eval_every: training episodes between evaluations
    :param n_episodes: greedy episodes per evaluation
    :param seed: the evaluation seed (the same players, starts and noise at every point)
    """

    def __init__(self, policy: Any, profile: str, eval_every: int, n_episodes: int, seed: int = EVAL_SEED):
        super().__init__()
        self.policy, self.profile = policy, profile
        self.eval_every, self.n_episodes, self.seed = eval_every, n_episodes, seed
        self.episodes = 0
        self.next_eval = eval_every
        self.curve: list[dict[str, Any]] = []
        self.eval_seconds = 0.0
        self._start = 0.0

    def _on_training_start(self) -> None:
        self._start = time.perf_counter()
        self.evaluate()

    def _on_step(self) -> bool:
        self.episodes += int(np.sum(self.locals["dones"]))
        if self.episodes >= self.next_eval:
            self.evaluate()
            self.next_eval = (self.episodes // self.eval_every + 1) * self.eval_every
        return True

    def evaluate(self) -> dict[str, Any]:
        start = time.perf_counter()
        summary = report_summary(evaluate_dribbling(self.policy, self.n_episodes, self.profile, self.seed))
        self.eval_seconds += time.perf_counter() - start
        wall = time.perf_counter() - self._start
        point = {
            "episodes": self.episodes,
            "env_steps": int(self.num_timesteps),
            "wall_s": round(wall, 3),
            "train_s": round(wall - self.eval_seconds, 3),  # training time only, evaluations excluded
            **{k: v for k, v in summary.items() if k != "episodes"},
        }
        self.curve.append(point)
        for key in ("distance_mean", "distance_median", "distance_max", "reach20_share", "ball_loss_rate"):
            self.logger.record(f"eval/{key}", point[key])
        self.logger.record("eval/training_episodes", self.episodes)
        self.logger.dump(self.num_timesteps)
        return point


# ---------------------------------------------------------------------------------------------------------------------
# One cell
# ---------------------------------------------------------------------------------------------------------------------


def build_model(cell: Cell) -> tuple[Any, Any, int | None]:
    """The untrained model, the object evaluation calls ``predict`` on, and the ``log_interval`` for ``learn``."""
    if cell.algo == "SarsaAAC":
        from sb3_aac import SarsaAAC

        _, policy, policy_kwargs = SARSA_CONFIGS[cell.config]
        overrides = dict(cell.overrides)
        n_envs = overrides.pop("n_envs", SARSA_N_ENVS)
        env = DribbleVecEnv(n_envs, profile=cell.profile)
        model = SarsaAAC(policy, env, seed=cell.seed, policy_kwargs=dict(policy_kwargs), **overrides)
        return model, model, 100  # dump the rollout/train keys every 100 episodes
    from benchmarks.adapters import adapter_for, build_baseline

    model = build_baseline(cell.env_id, cell.algo, cell.seed, cell.overrides)
    # On-policy: log_interval counts rollouts (about every 2048 transitions); off-policy: episodes.
    log_interval = max(1, 2048 // (model.n_steps * model.n_envs)) if cell.algo in ON_POLICY else 100
    return model, adapter_for(model, cell.algo, cell.env_id), log_interval


def algo_config(cell: Cell) -> dict[str, Any]:
    """The hyperparameters a cell ran with, as recorded in its file."""
    if cell.algo == "SarsaAAC":
        _, policy, policy_kwargs = SARSA_CONFIGS[cell.config]
        return {"policy": policy, "policy_kwargs": policy_kwargs, "n_envs": SARSA_N_ENVS, "other": "SarsaAAC defaults", **cell.overrides}
    if cell.algo == "Reference":
        return {}
    spec = BASELINES[cell.algo]
    return {"policy": "MlpPolicy", **spec, "kwargs": {**spec["kwargs"], **cell.overrides}, "other": "SB3 defaults"}


def run_reference(cell: Cell) -> dict[str, Any]:
    """The no-learning references of an env: the hand-coded dribbler and the physical running ceiling."""
    from robocup_dribble.dribbler import HandCodedDribbler

    start = time.perf_counter()
    dribbler = HandCodedDribbler(profile=cell.profile)
    curve_set = report_summary(evaluate_dribbling(dribbler, cell.eval_episodes, cell.profile, EVAL_SEED))
    final = report_summary(evaluate_dribbling(dribbler, cell.final_episodes, cell.profile, FINAL_SEED))
    handcoded_s = time.perf_counter() - start
    ceiling = running_ceiling(cell.profile)
    return {
        "handcoded": {
            "eval": curve_set,
            "final": final,
            "predict_us": predict_microseconds(dribbler, cell.profile),
            "wall_s": round(handcoded_s, 3),
        },
        "ceiling": {
            "players": len(ceiling),
            "mean": float(np.mean(ceiling)),
            "median": float(np.median(ceiling)),
            "min": float(np.min(ceiling)),
            "max": float(np.max(ceiling)),
            "cycles": 35,
        },
    }


def run_cell(cell_data: dict[str, Any], out: str) -> dict[str, Any]:
    """Train and evaluate one cell and write its files; returns its result. Runs in a worker process."""
    th.set_num_threads(1)
    cell = Cell.from_dict(cell_data)
    out_dir = Path(out)
    started = time.time()
    start = time.perf_counter()
    load_start = loadavg()
    result: dict[str, Any] = {
        "cell_id": cell.cell_id,
        "cell": cell.to_dict(),
        "family": cell.family,
        "algo_config": algo_config(cell),
        "eval_seed": EVAL_SEED,
        "final_seed": FINAL_SEED,
        "command": os.environ.get("SB3_AAC_BENCH_COMMAND", ""),
        "versions": versions(),
        "provenance": cell_provenance(),
        "machine": machine(),
        "started": time.strftime("%Y-%m-%dT%H:%M:%S", time.localtime(started)),
    }
    if cell.algo == "Reference":
        result["references"] = run_reference(cell)
    else:
        tb_dir = out_dir / "tb" / cell.cell_id
        shutil.rmtree(tb_dir, ignore_errors=True)  # a run interrupted before its cell file was written
        model, policy, log_interval = build_model(cell)
        model.set_logger(configure(str(tb_dir), ["tensorboard"]))
        callback = DribbleEvalCallback(policy, cell.profile, cell.eval_every, cell.eval_episodes)
        model.learn(cell.budget, callback=callback, log_interval=log_interval)
        if callback.curve[-1]["env_steps"] < model.num_timesteps:
            callback.evaluate()  # the curve ends where training ended
        train_wall = time.perf_counter() - start
        final = report_summary(evaluate_dribbling(policy, cell.final_episodes, cell.profile, FINAL_SEED))
        for key in ("distance_mean", "reach20_share", "ball_loss_rate"):
            model.logger.record(f"eval/final_{key}", final[key])
        model.logger.dump(model.num_timesteps)
        model.logger.close()
        model_path = out_dir / "models" / f"{cell.cell_id}.zip"
        save_model_atomic(model, model_path)
        result.update(
            curve=callback.curve,
            final=final,
            env_steps=int(model.num_timesteps),
            episodes=callback.episodes,
            train_wall_s=round(train_wall, 3),
            eval_wall_s=round(callback.eval_seconds, 3),
            predict_us=predict_microseconds(policy, cell.profile),
            model=str(model_path.relative_to(out_dir)),
            tensorboard=str(tb_dir.relative_to(out_dir)),
        )
    result["wall_s"] = round(time.perf_counter() - start, 3)
    result["loadavg"] = {"start": load_start, "end": loadavg()}
    atomic_write_json(cell_path(out_dir, cell), result)
    return result


def run_cell_safely(cell_data: dict[str, Any], out: str) -> tuple[str, str, dict[str, Any] | str]:
    """``run_cell`` under the cell's lock, with an exception turned into ``errors/<cell_id>.txt`` and a ``"failed"``
    status; ``"busy"`` if another live process is running the cell."""
    cell = Cell.from_dict(cell_data)
    error_file = Path(out) / "errors" / f"{cell.cell_id}.txt"
    with cell_lock(Path(out), cell.cell_id) as locked:
        if not locked:
            return cell.cell_id, "busy", "running in another process"
        try:
            result = run_cell(cell_data, out)
        except Exception:
            text = traceback.format_exc()
            atomic_write_text(error_file, text)
            return cell.cell_id, "failed", text
        with contextlib.suppress(FileNotFoundError):
            error_file.unlink()
    return cell.cell_id, "done", result


def exit_with_parent(parent: int, poll_seconds: float = PARENT_POLL_SECONDS) -> threading.Thread:
    """
    End this process (``os._exit``) as soon as its parent ``parent`` is gone, however it ended (``kill -9``
    included): a daemon thread polls the parent's process id, which changes when an orphan is adopted. Portable,
    and unlike Linux's ``PR_SET_PDEATHSIG`` it does not depend on which of the parent's threads started this
    process. ``parent`` is the id the parent had when it started us: if it died while we were still starting
    (importing torch takes seconds), we are already adopted and exit at the first poll.
    """

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(poll_seconds)
        os._exit(1)

    thread = threading.Thread(target=watch, name="exit-with-parent", daemon=True)
    thread.start()
    return thread


def _init_worker(driver: int) -> None:
    exit_with_parent(driver)
    th.set_num_threads(1)


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """Cancel what has not started and end the running workers now (their cells' temporaries go with them)."""
    pool.shutdown(wait=False, cancel_futures=True)
    for process in list((getattr(pool, "_processes", None) or {}).values()):  # no public API before Python 3.14
        with contextlib.suppress(OSError, ValueError):
            process.terminate()
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        with contextlib.suppress(OSError, ValueError, AssertionError):
            process.join(5)


# ---------------------------------------------------------------------------------------------------------------------
# The grid
# ---------------------------------------------------------------------------------------------------------------------


def estimated_cost(cell: Cell) -> float:
    """Rough seconds of a cell (to start the longest first, so two workers finish together)."""
    rate = {"SarsaAAC": 10000, "PPO": 1600, "A2C": 2000, "SAC": 1000, "TD3": 1300, "DDPG": 1300, "DQN": 1800}
    return 30.0 if cell.algo == "Reference" else cell.budget / rate.get(cell.algo, 1000)


def _summary_line(result: dict[str, Any]) -> str:
    if "references" in result:
        ref = result["references"]
        return f"hand-coded {ref['handcoded']['final']['distance_mean']:.1f} m, ceiling {ref['ceiling']['mean']:.1f} m"
    f = result["final"]
    return (
        f"{f['distance_mean']:.1f} m, >=20 m {100 * f['reach20_share']:.0f}%, lost {100 * f['ball_loss_rate']:.0f}% "
        f"({result['episodes']} episodes, {result['wall_s']:.0f} s)"
    )


def run_grid(
    grid: list[Cell], out: str | Path, workers: int = 2, progress: bool = True, engine: CellEngine | None = None
) -> dict[str, list[str]]:
    """
    Run the cells that have no sound result file yet (a damaged one is named in a warning and computed again);
    returns the ids ``done``, ``skipped`` (finished before), ``failed`` and ``busy`` (running in another process).

    ``engine`` runs them elsewhere (:class:`benchmarks.engines.RayEngine`); None: the local process pool of ``workers``,
    whose processes end with this process, however it ends: on an exception or interrupt here they are terminated,
    and each worker exits by itself when this process is killed (:func:`exit_with_parent`).
    """
    from tqdm import tqdm

    out = Path(out)
    for sub in ("cells", "models", "tb", "errors"):
        (out / sub).mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(out)
    status: dict[str, list[str]] = {"done": [], "skipped": [], "failed": [], "busy": []}
    todo = []
    for cell in grid:
        (status["skipped"] if cells.is_finished(out, cell) else todo).append(cell)
    status["skipped"] = [c.cell_id for c in status["skipped"]]
    todo.sort(key=estimated_cost, reverse=True)
    os.environ.setdefault("SB3_AAC_BENCH_COMMAND", "(called from Python)")
    bar = tqdm(total=len(todo), desc="cells", unit="cell", disable=not progress, dynamic_ncols=True)
    if status["skipped"] and progress:
        tqdm.write(f"{len(status['skipped'])} finished cells skipped, {len(todo)} to run in {out}")

    def record(cell_id: str, state: str, payload: Any) -> None:
        status[state].append(cell_id)
        bar.update(1)
        if progress:
            text = {"done": _summary_line, "busy": str}.get(state, lambda p: "FAILED: " + p.strip().splitlines()[-1])(payload)
            tqdm.write(f"{cell_id}: {text}")

    try:
        if engine is not None:
            engine.run(todo, out, record)
        elif workers <= 1:
            for cell in todo:
                record(*run_cell_safely(cell.to_dict(), str(out)))
        else:
            context = multiprocessing.get_context("spawn")
            with ProcessPoolExecutor(workers, mp_context=context, initializer=_init_worker, initargs=(os.getpid(),)) as pool:
                pending = {pool.submit(run_cell_safely, cell.to_dict(), str(out)) for cell in todo}
                try:
                    while pending:
                        finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                        for future in finished:
                            record(*future.result())
                except BaseException:
                    _stop_workers(pool)
                    raise
    finally:
        bar.close()
    return status


# ---------------------------------------------------------------------------------------------------------------------
# Reliability test (paper Figs. 9-10)
# ---------------------------------------------------------------------------------------------------------------------


def histogram(distances: np.ndarray) -> dict[str, Any]:
    edges = np.arange(0.0, HIST_MAX_METRES + HIST_BIN_METRES, HIST_BIN_METRES)
    counts, _ = np.histogram(np.clip(distances, 0.0, HIST_MAX_METRES - 1e-9), edges)
    return {"bin_metres": HIST_BIN_METRES, "counts": counts.tolist()}


def best_cell(results: list[dict[str, Any]], env_id: str, algos: tuple[str, ...]) -> dict[str, Any] | None:
    """The best policy of ``algos`` on ``env_id``: the config with the highest mean final distance over its seeds,
    then that config's seed with the highest final distance. The final evaluation set (FINAL_SEED) picks it; the
    reliability test then runs on 10,000 other players (RELIABILITY_SEED)."""
    candidates = [r for r in results if r["cell"]["env_id"] == env_id and r["cell"]["algo"] in algos and "final" in r]
    if not candidates:
        return None
    by_config: dict[tuple[str, str, int], list[dict[str, Any]]] = {}
    for r in candidates:
        by_config.setdefault((r["cell"]["algo"], r["cell"]["config"], r["cell"]["budget"]), []).append(r)
    best_runs = max(by_config.values(), key=lambda runs: np.mean([r["final"]["distance_mean"] for r in runs]))
    return max(best_runs, key=lambda r: r["final"]["distance_mean"])


def load_policy(out: Path, result: dict[str, Any]) -> Any:
    """A trained cell's model, ready for ``evaluate_dribbling`` (baselines through their adapter); a damaged model
    file is one ValueError naming it."""
    from sb3_aac.common.model_files import load_checked

    cell = Cell.from_dict(result["cell"])
    path = out / result["model"]
    if cell.algo == "SarsaAAC":
        from sb3_aac import SarsaAAC

        return load_checked(SarsaAAC, path, device="cpu")
    from benchmarks.adapters import ALGOS, adapter_for

    return adapter_for(load_checked(ALGOS[cell.algo], path, device="cpu"), cell.algo, cell.env_id)


def reliability_entry(policy: Any, profile: str, n_players: int, source: dict[str, Any]) -> dict[str, Any]:
    start = time.perf_counter()
    report = reliability_test(policy, n_players, profile, seed=RELIABILITY_SEED, n_lanes=500)
    d = report.distances
    return {
        **source,
        "players": len(d),
        **distance_stats(d),
        "share_at_least": {str(m): float(np.mean(d >= m)) for m in (8, 16, 18, 20, 25)},
        "ball_loss_rate": report.loss_rate,
        "histogram": histogram(d),
        "kept_histogram": histogram(d[~report.ball_lost]),  # players that still had the ball after 35 actions
        "wall_s": round(time.perf_counter() - start, 3),
    }


def run_reliability(out: str | Path, n_players: int = RELIABILITY_PLAYERS, progress: bool = True) -> dict[str, Any]:
    """The reliability test (``n_players`` fresh players, one episode each) of the best SarsaAAC policy, the best
    baseline and the hand-coded dribbler of each env; cached in ``DIR/reliability.json`` (recomputed only for an
    entry whose policy or player count changed)."""
    from robocup_dribble.dribbler import HandCodedDribbler

    th.set_num_threads(1)
    out = Path(out)
    results = load_cells(out)
    cache_path = out / "reliability.json"
    try:
        cache = cells.read_json_object(cache_path) if cache_path.exists() else {}
    except ValueError as error:
        warnings.warn(f"{error}; recomputing the reliability test", stacklevel=2)
        cache = {}
    env_ids = sorted({r["cell"]["env_id"] for r in results if "final" in r})
    data: dict[str, Any] = {"seed": RELIABILITY_SEED, "command": os.environ.get("SB3_AAC_BENCH_COMMAND", ""), "envs": {}}
    for env_id in env_ids:
        profile = ENV_PROFILE[env_id]
        entries = {}
        picks = {"sarsa_aac": best_cell(results, env_id, ("SarsaAAC",)), "baseline": best_cell(results, env_id, tuple(BASELINES))}
        for name, pick in picks.items():
            if pick is None:
                continue
            model_path = out / pick["model"]
            source = {"cell_id": pick["cell_id"], "model_mtime": os.path.getmtime(model_path)}
            old = cache.get("envs", {}).get(env_id, {}).get(name)
            if old and old["cell_id"] == source["cell_id"] and old["model_mtime"] == source["model_mtime"] and old["players"] == n_players:
                entries[name] = old
                continue
            if progress:
                print(f"reliability test ({n_players} players) of {pick['cell_id']} ...", flush=True)
            entries[name] = reliability_entry(load_policy(out, pick), profile, n_players, source)
        old = cache.get("envs", {}).get(env_id, {}).get("handcoded")
        if old and old["players"] == n_players:
            entries["handcoded"] = old
        else:
            if progress:
                print(f"reliability test ({n_players} players) of the hand-coded dribbler on {env_id} ...", flush=True)
            entries["handcoded"] = reliability_entry(HandCodedDribbler(profile=profile), profile, n_players, {"cell_id": "hand-coded"})
        data["envs"][env_id] = entries
    atomic_write_json(cache_path, data)
    return data


# ---------------------------------------------------------------------------------------------------------------------
# CLI
# ---------------------------------------------------------------------------------------------------------------------


def _exit_on_sigterm(signum: int, frame: Any) -> None:
    raise SystemExit(128 + signum)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.run", description=__doc__.split("\n\n")[0])
    parser.add_argument("--preset", choices=sorted(PRESETS), help="the grid to run")
    parser.add_argument("--out", default=None, help="results directory (default: runs/bench-<preset>)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes (1: run in this process)")
    parser.add_argument("--only", default=None, help="comma-separated glob patterns of cell ids (a plain word matches as a substring)")
    parser.add_argument("--list", action="store_true", help="list the cells (and whether they are finished), run nothing")
    parser.add_argument("--reliability", action="store_true", help="run the reliability test of the best policies in --out")
    parser.add_argument("--players", type=int, default=RELIABILITY_PLAYERS, help="players of the reliability test")
    parser.add_argument("--engine", choices=("local", "ray"), default="local", help="local process pool, or one Ray task per cell")
    parser.add_argument("--address", default=None, help="the Ray cluster to join (default: start Ray here with --workers CPUs)")
    parser.add_argument("--allow-dirty", action="store_true", help="run although tracked files have uncommitted changes (recorded in each cell)")
    args = parser.parse_args(argv)
    signal.signal(signal.SIGTERM, _exit_on_sigterm)  # `kill` runs the cleanup of run_grid (workers end with us)
    if not args.preset and not args.reliability:
        parser.error("give --preset (run the grid) and/or --reliability")
    if args.address and args.engine != "ray":
        parser.error("--address needs --engine ray")
    out = Path(args.out or f"runs/bench-{args.preset or 'full'}")
    os.environ["SB3_AAC_BENCH_COMMAND"] = "python -m benchmarks.run " + " ".join(shlex.quote(a) for a in (sys.argv[1:] if argv is None else argv))
    if args.preset:
        grid = select(build_cells(args.preset), args.only)
        if args.list:
            for cell in grid:
                print(f"{'done' if cells.is_finished(out, cell) else 'todo'}  {cell.cell_id}")
            return 0
        start = time.time()
        invocation = new_invocation_id()
        fields = {"command": os.environ["SB3_AAC_BENCH_COMMAND"], "workers": args.workers, "engine": args.engine, "allow_dirty": args.allow_dirty}
        try:
            with logged_invocation(out, invocation=invocation, **fields) as log:
                state = require_clean_tree(REPO, args.allow_dirty, ignore=(out,))
                os.environ[ENV_VAR] = json.dumps(invocation_provenance(invocation, state, args.allow_dirty))
                engine = RayEngine(args.address, num_cpus=args.workers) if args.engine == "ray" else None
                try:
                    status = run_grid(grid, out, args.workers, engine=engine)
                finally:
                    del os.environ[ENV_VAR]  # later run_grid calls of this process are not this invocation's
                log.update({k: len(v) for k, v in status.items()})
        except DirtyTreeError as error:
            print(f"refused: {error}", file=sys.stderr)
            return 2
        print(f"{len(status['done'])} cells done, {len(status['skipped'])} skipped, {len(status['failed'])} failed in {time.time() - start:.0f} s; results in {out}")
        if status["failed"]:
            print("failed (tracebacks in errors/): " + ", ".join(status["failed"]))
        if status["busy"]:
            print("running in another process (not started here): " + ", ".join(status["busy"]))
    if args.reliability:
        run_reliability(out, args.players)
        print(f"reliability test written to {out / 'reliability.json'}")
    return 1 if args.preset and status["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
