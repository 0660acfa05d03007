"""Running cells: train and evaluate one cell and write its files (:func:`run_cell`), safely under its lock
(:func:`run_cell_safely`), and the grid of them in worker processes that end with their driver (:func:`run_grid`)."""

from __future__ import annotations

import contextlib
import os
import shutil
import time
import traceback
from pathlib import Path
from typing import Any

import numpy as np
import torch as th
from robocup_dribble.dribbler import HandCodedDribbler
from robocup_dribble.evaluation import evaluate_dribbling
from stable_baselines3.common.callbacks import BaseCallback, CallbackList
from stable_baselines3.common.logger import configure
from tqdm import tqdm

from benchmarks import cells, domains
from benchmarks.cells import atomic_write_json, atomic_write_text, cell_lock, remove_stale_temporaries, save_model_atomic
from benchmarks.cost import cell_seconds
from benchmarks.engines import CellEngine
from benchmarks.evaluation import EvalCallback, TrainingTimeLimit, predict_microseconds
from benchmarks.models import build_model, peer_settings, peer_settings_source

from benchmarks.presets import BASELINES, EVAL_SEED, FINAL_SEED, PEERS, SARSA_CONFIGS, SARSA_N_ENVS, Cell, is_tuned
from benchmarks.provenance import cell_provenance, loadavg, machine, versions
from benchmarks.tuned import TUNED_PARAMS, TUNING_RECORD, tuned_cell
from benchmarks.workers import run_in_pool
from sb3_aac.common.episode_stats import EpisodeKeywordsCallback


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
            engine.run(todo, out, record, run_cell_safely)
        else:
            run_in_pool(run_cell_safely, [(cell.to_dict(), str(out)) for cell in todo], workers, record)
    finally:
        bar.close()
    return status
