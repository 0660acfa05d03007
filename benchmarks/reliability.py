"""The reliability test of the best policies (paper Figs. 9-10): fresh players, one greedy episode each, cached in
``DIR/reliability.json``."""

from __future__ import annotations

import os
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import torch as th
from robocup_dribble import ENV_PROFILES
from robocup_dribble.dribbler import HandCodedDribbler
from robocup_dribble.evaluation import reliability_test

import sb3_aac
from benchmarks import cells
from benchmarks.adapters import ALGOS, adapter_for
from benchmarks.cells import atomic_write_json
from benchmarks.domains import distance_stats
from benchmarks.presets import BASELINES, PEERS, RELIABILITY_SEED, Cell

RELIABILITY_PLAYERS = 10_000
HIST_BIN_METRES = 1.0
HIST_MAX_METRES = 60


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
    if cell.algo == "SarsaAAC" or cell.algo in PEERS:
        return load_checked(getattr(sb3_aac, cell.algo), path, device="cpu")
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
    parameterized peer (P-DQN, MP-DQN, HybridPPO), the best SB3 baseline and the hand-coded dribbler of each dribbling
    env; cached in ``DIR/reliability.json`` (recomputed only for an entry whose policy or player count changed)."""
    th.set_num_threads(1)
    out = Path(out)
    results = cells.load_cells(out)
    cache_path = out / "reliability.json"
    try:
        cache = cells.read_json_object(cache_path) if cache_path.exists() else {}
    except ValueError as error:
        warnings.warn(f"{error}; recomputing the reliability test", stacklevel=2)
        cache = {}
    env_ids = sorted({r["cell"]["env_id"] for r in results if "final" in r and r["cell"]["env_id"] in ENV_PROFILES})
    data: dict[str, Any] = {"seed": RELIABILITY_SEED, "command": os.environ.get("SB3_AAC_BENCH_COMMAND", ""), "envs": {}}
    for env_id in env_ids:
        profile = ENV_PROFILES[env_id]
        entries = {}
        picks = {
            "sarsa_aac": best_cell(results, env_id, ("SarsaAAC",)),
            "peer": best_cell(results, env_id, tuple(PEERS)),
            "baseline": best_cell(results, env_id, tuple(BASELINES)),
        }
        for name, pick in picks.items():
            if pick is None:
                continue
            model_path = out / pick["model"]
            source = {"cell_id": pick["cell_id"], "model_mtime": os.path.getmtime(model_path)}
            old = cache.get("envs", {}).get(env_id, {}).get(name)
            if (
                old
                and old["cell_id"] == source["cell_id"]
                and old["model_mtime"] == source["model_mtime"]
                and old["players"] == n_players
            ):
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
            entries["handcoded"] = reliability_entry(
                HandCodedDribbler(profile=profile), profile, n_players, {"cell_id": "hand-coded"}
            )
        data["envs"][env_id] = entries
    atomic_write_json(cache_path, data)
    return data
