"""Running cells: train and evaluate one cell and write its files (:func:`run_cell`), safely under its lock
(:func:`run_cell_safely`), and the grid of them in worker processes that end with their driver (:func:`run_grid`)."""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import shutil
import threading
import time
import traceback
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any, Protocol

# One BLAS thread per process: with two workers on two cores, OpenBLAS's own threads make some SarsaAAC configs
# (RbfMlpPolicy with 20 hidden units) up to 7x slower. Set before numpy is imported here; spawned workers inherit it.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import torch as th  # noqa: E402
from stable_baselines3.common.callbacks import BaseCallback, CallbackList  # noqa: E402
from stable_baselines3.common.logger import configure  # noqa: E402

import robocup_dribble  # noqa: E402, F401  (registers the env ids)
from benchmarks import cells  # noqa: E402
from benchmarks.cost import cell_seconds  # noqa: E402
from benchmarks.cells import atomic_write_json, atomic_write_text, cell_lock, remove_stale_temporaries, save_model_atomic  # noqa: E402
from benchmarks import domains  # noqa: E402
from benchmarks.evaluation import EvalCallback, predict_microseconds  # noqa: E402
from benchmarks.platform_info import loadavg, machine, versions  # noqa: E402
from benchmarks.presets import (  # noqa: E402
    BASELINES,
    EVAL_SEED,
    FINAL_SEED,
    ON_POLICY,
    ON_POLICY_PEERS,
    PEERS,
    SARSA_CONFIGS,
    SARSA_N_ENVS,
    Cell,
    is_tuned,
)
from benchmarks.provenance import cell_provenance  # noqa: E402
from benchmarks.tuned import TUNED_PARAMS, TUNING_RECORD, tuned_cell  # noqa: E402
from benchmarks.wall_clock import TrainingTimeLimit  # noqa: E402
from benchmarks.reference_init import with_reference_start  # noqa: E402
from benchmarks.zoo_hyperparams import has_settings, settings, zoo_env  # noqa: E402
from robocup_dribble.evaluation import evaluate_dribbling  # noqa: E402
from sb3_aac.common.episode_stats import EpisodeKeywordsCallback  # noqa: E402

PARENT_POLL_SECONDS = 0.2  # how often a worker checks that the driver still lives

# How an engine reports a cell to :func:`run_grid`: ``record(cell_id, state, payload)``, ``state`` "done" (payload the
# cell's result dict) or "failed" (payload the error text).
Record = Callable[[str, str, Any], None]


class CellEngine(Protocol):
    """Runs cells somewhere else than :func:`run_grid`'s local pool (:class:`benchmarks.engines.RayEngine`) and reports
    each one through ``record``."""

    name: str

    def run(self, cells: Sequence[Cell], out: Path, record: Record) -> None: ...


def peer_settings_source(cell: Cell) -> str:
    """Where a peer's settings come from: ``hyperparams/<yml>.yml``'s entry for the env, the entry of the env's
    fallback (:data:`PEERS`), or the algorithm's defaults."""
    spec = PEERS[cell.algo]
    path = f"hyperparams/{spec['yml']}.yml"
    start = ", the reference code's initial parameter policy" if cell.env_id in spec.get("reference_start", ()) else ""
    if has_settings(spec["yml"], cell.env_id):
        return f"{path} ({cell.env_id}{start})"
    if spec["fallback"] is not None:
        return f"{path} ({spec['fallback']}; no entry for {cell.env_id})"
    return f"{cell.algo} defaults (no entry for {cell.env_id} in {path})"


def peer_settings(cell: Cell) -> dict[str, Any]:
    """P-DQN / MP-DQN / HybridPPO constructor arguments: ``hyperparams/<yml>.yml``'s entry (:func:`peer_settings_source`),
    then :data:`PEERS`, then overrides."""
    spec = PEERS[cell.algo]
    entry = cell.env_id if has_settings(spec["yml"], cell.env_id) else spec["fallback"]
    base = settings(spec["yml"], entry) if entry is not None else {}
    return {**base, "n_envs": spec["n_envs"], **spec["kwargs"], **cell.overrides}


def build_model(cell: Cell) -> tuple[Any, Any, int | None]:
    """The untrained model, the object evaluation calls ``predict`` on, and the ``log_interval`` for ``learn``.

    A tuned config (``<config>-tuned``) builds ``<config>`` with its study's best settings (:mod:`benchmarks.tuned`).
    """
    if is_tuned(cell.config):
        cell = tuned_cell(cell)
    if cell.algo == "SarsaAAC":
        from sb3_aac import SarsaAAC

        _, policy, policy_kwargs, config_kwargs = SARSA_CONFIGS[cell.config]
        overrides = {**config_kwargs, **cell.overrides}
        env = domains.train_env(cell.env_id, overrides.pop("n_envs", SARSA_N_ENVS), cell.seed)
        overrides.setdefault("info_keywords", domains.info_keywords(cell.env_id))
        policy_kwargs = {**policy_kwargs, **overrides.pop("policy_kwargs", {})}
        model = SarsaAAC(policy, env, seed=cell.seed, policy_kwargs=policy_kwargs, **overrides)
        return model, model, 100  # dump the rollout/train keys every 100 episodes
    if cell.algo in PEERS:
        import sb3_aac

        spec, kwargs = PEERS[cell.algo], peer_settings(cell)
        n_envs = kwargs.pop("n_envs")
        if domains.is_dribbling(cell.env_id) or not has_settings(spec["yml"], cell.env_id):
            env = domains.train_env(cell.env_id, n_envs, cell.seed)
        else:  # the env of its own entry: the entry's env_wrapper chain (Goal: the reference's reward scale too)
            env = zoo_env(spec["yml"], cell.env_id, n_envs, cell.seed)
        kwargs.setdefault("info_keywords", domains.info_keywords(cell.env_id))
        policy: Any = "MlpPolicy"
        if cell.env_id in spec.get("reference_start", ()):
            policy, kwargs = with_reference_start(kwargs)
        model = getattr(sb3_aac, cell.algo)(policy, env, seed=cell.seed, device="cpu", **kwargs)
        return model, model, _log_interval(model, cell.algo)
    from benchmarks.adapters import adapter_for, build_baseline

    model = build_baseline(cell.env_id, cell.algo, cell.seed, cell.overrides)
    return model, adapter_for(model, cell.algo, cell.env_id), _log_interval(model, cell.algo)


def _log_interval(model: Any, algo: str) -> int:
    """``learn``'s ``log_interval``: on-policy it counts rollouts (about every 2048 transitions); off-policy episodes."""
    return max(1, 2048 // (model.n_steps * model.n_envs)) if algo in (*ON_POLICY, *ON_POLICY_PEERS) else 100


def algo_config(cell: Cell) -> dict[str, Any]:
    """The hyperparameters a cell ran with, as recorded in its file."""
    if is_tuned(cell.config):
        tuned = {key: cell.overrides.get(key) for key in (TUNED_PARAMS, TUNING_RECORD)}
        return {**algo_config(tuned_cell(cell, kwargs_as_text=True)), **tuned, "other": "tuned (benchmarks.tuning)"}
    if cell.algo == "SarsaAAC":
        _, policy, policy_kwargs, config_kwargs = SARSA_CONFIGS[cell.config]
        return {
            "policy": policy,
            "policy_kwargs": policy_kwargs,
            "n_envs": SARSA_N_ENVS,
            "other": "SarsaAAC defaults",
            **config_kwargs,
            **cell.overrides,
        }
    if cell.algo == "Reference":
        return {}
    if cell.algo in PEERS:
        return {"policy": "MlpPolicy", "kwargs": peer_settings(cell), "other": peer_settings_source(cell)}
    spec = BASELINES[cell.algo]
    return {"policy": "MlpPolicy", **spec, "kwargs": {**spec["kwargs"], **cell.overrides}, "other": "SB3 defaults"}


def run_reference(cell: Cell) -> dict[str, Any]:
    """The no-learning references of a dribbling env on the benchmark's evaluation episodes: the hand-coded dribbler
    and the per-episode running bound."""
    from robocup_dribble.dribbler import HandCodedDribbler

    start = time.perf_counter()
    dribbler = HandCodedDribbler(profile=cell.profile)
    curve_set = domains.evaluate(cell.env_id, dribbler, cell.eval_episodes, EVAL_SEED)
    report = evaluate_dribbling(dribbler, cell.final_episodes, cell.profile, FINAL_SEED)
    final = domains.summarize(cell.env_id, report.distances, report.ball_lost)
    handcoded_s = time.perf_counter() - start
    return {
        "handcoded": {
            "eval": curve_set,
            "final": final,
            "predict_us": predict_microseconds(dribbler, cell.env_id),
            "wall_s": round(handcoded_s, 3),
        },
        "bound": bound_summary(report.distance_bounds),
    }


BOUND_LABEL = "upper bound (any policy)"


def bound_summary(bounds: np.ndarray) -> dict[str, Any]:
    """The final set's per-episode upper bounds on the distance (``robocup_dribble.evaluation.distance_bound``: no
    policy can exceed them on those episodes), summarised."""
    return {
        "label": BOUND_LABEL,
        "episodes": len(bounds),
        "mean": float(np.mean(bounds)),
        "median": float(np.median(bounds)),
        "min": float(np.min(bounds)),
        "max": float(np.max(bounds)),
        "episode_bounds": [round(float(b), 4) for b in bounds],
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
        callback = EvalCallback(policy, cell.env_id, cell.eval_every, cell.eval_episodes)
        limit = TrainingTimeLimit(cell.seconds, callback) if cell.seconds else None
        callbacks: list[BaseCallback] = [callback, *([limit] if limit else [])]
        if cell.algo in BASELINES:  # SB3's algorithms log the env's info keys through a callback, ours themselves
            callbacks.append(EpisodeKeywordsCallback(domains.info_keywords(cell.env_id)))
        model.learn(cell.budget, callback=CallbackList(callbacks), log_interval=log_interval)
        if callback.curve[-1]["env_steps"] < model.num_timesteps:
            callback.evaluate()  # the curve ends where training ended
        train_wall = time.perf_counter() - start
        final = domains.evaluate(cell.env_id, policy, cell.final_episodes, FINAL_SEED)
        for key, value in final.items():
            if key not in ("episodes", "episode_scores"):
                model.logger.record(f"eval/final_{key}", value)
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
            predict_us=predict_microseconds(policy, cell.env_id),
            model=str(model_path.relative_to(out_dir)),
            tensorboard=str(tb_dir.relative_to(out_dir)),
        )
        if limit is not None:
            result["stopped_by"] = "time" if limit.reached else "env steps"
    result["wall_s"] = round(time.perf_counter() - start, 3)
    result["loadavg"] = {"start": load_start, "end": loadavg()}
    atomic_write_json(cells.cell_path(out_dir, cell.cell_id), result)
    return result


def run_cell_safely(cell_data: dict[str, Any], out: str) -> tuple[str, str, dict[str, Any] | str]:
    """``run_cell`` under the cell's lock, with an exception turned into ``errors/<cell_id>.txt`` and a ``"failed"``
    status; ``"busy"`` if another live process is running the cell, ``"skipped"`` if another process finished it
    since this run listed its cells (two invocations sharing one results folder never run a cell twice)."""
    cell = Cell.from_dict(cell_data)
    error_file = Path(out) / "errors" / f"{cell.cell_id}.txt"
    with cell_lock(Path(out), cell.cell_id) as locked:
        if not locked:
            return cell.cell_id, "busy", "running in another process"
        if cells.is_finished(Path(out), cell):
            return cell.cell_id, "skipped", "finished by another process"
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


def run_in_pool(function: Callable[..., tuple[Any, ...]], tasks: Sequence[tuple[Any, ...]], workers: int,
                on_result: Callable[..., None]) -> None:  # fmt: skip
    """
    ``on_result(*function(*task))`` for every task, in this process (``workers <= 1``) or in a pool of ``workers``
    spawned processes (each pinned to one BLAS thread and ending with this process), as the tasks finish. On any
    exception (Ctrl-C included) the workers are stopped before it propagates.
    """
    if workers <= 1:
        for task in tasks:
            on_result(*function(*task))
        return
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(workers, mp_context=context, initializer=_init_worker, initargs=(os.getpid(),)) as pool:
        pending = {pool.submit(function, *task) for task in tasks}
        try:
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    on_result(*future.result())
        except BaseException:
            _stop_workers(pool)
            raise


def _summary_line(result: dict[str, Any]) -> str:
    if "references" in result:
        ref = result["references"]
        return f"hand-coded {ref['handcoded']['final']['distance_mean']:.1f} m, upper bound {ref['bound']['mean']:.1f} m"
    f = result["final"]
    env_id = result["cell"]["env_id"]
    score = f"{f[domains.metric(env_id)]:.3g} ({domains.metric_label(env_id)})"
    return f"{score} ({result['episodes']} episodes, {result['wall_s']:.0f} s)"


def run_grid(
    grid: list[Cell], out: str | Path, workers: int = 2, progress: bool = True, engine: CellEngine | None = None
) -> dict[str, list[str]]:
    """
    Run the cells that have no sound result file yet (a damaged one is named in a warning and computed again);
    returns the ids ``done``, ``skipped`` (finished before, or by another process meanwhile), ``failed`` and ``busy``
    (running in another process).

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
    todo.sort(key=cell_seconds, reverse=True)  # the longest first, so the workers finish together
    os.environ.setdefault("SB3_AAC_BENCH_COMMAND", "(called from Python)")
    bar = tqdm(total=len(todo), desc="cells", unit="cell", disable=not progress, dynamic_ncols=True)
    if status["skipped"] and progress:
        tqdm.write(f"{len(status['skipped'])} finished cells skipped, {len(todo)} to run in {out}")

    def record(cell_id: str, state: str, payload: Any) -> None:
        status[state].append(cell_id)
        bar.update(1)
        if progress:
            text = {"done": _summary_line, "busy": str, "skipped": str}.get(
                state, lambda p: "FAILED: " + p.strip().splitlines()[-1]
            )(payload)
            tqdm.write(f"{cell_id}: {text}")

    try:
        if engine is not None:
            engine.run(todo, out, record)
        else:
            run_in_pool(run_cell_safely, [(cell.to_dict(), str(out)) for cell in todo], workers, record)
    finally:
        bar.close()
    return status
