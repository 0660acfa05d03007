"""The Ray engine of the benchmark runner (benchmarks/engines.py) on a local two-node Ray cluster.

One cluster serves the module (Ray takes several seconds to start): a head node and one worker node with one CPU
each. The tests skip, with the reason, only when Ray is not installed or cannot start on this machine.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from benchmarks import run as bench_run
from benchmarks.engines import RayEngine, write_cell_files
from benchmarks.execution import run_cell_safely
from benchmarks.presets import Cell

ENV_ID = "RoboCupDribblePaper-v0"
EVAL = {"eval_every": 50, "eval_episodes": 5, "final_episodes": 10}
NODE = {"num_cpus": 1, "object_store_memory": 80 * 1024**2}


def tiny_cells(n: int, budget: int = 300) -> list[Cell]:
    return [Cell(ENV_ID, "SarsaAAC", "rbf10", seed, budget, **EVAL, overrides={"n_envs": 2}) for seed in range(n)]


@pytest.fixture(scope="module")
def cluster():
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install sb3-aac[distributed])")
    from ray.cluster_utils import Cluster

    try:
        cluster = Cluster(initialize_head=True, head_node_args={**NODE, "include_dashboard": False})
        cluster.add_node(**NODE)
        ray.init(address=cluster.address, log_to_driver=False)
        cluster.wait_for_nodes()
    except Exception as error:  # no shared memory, no free ports, ...
        pytest.skip(f"Ray cannot start a local cluster here: {type(error).__name__}: {error}")
    yield cluster
    ray.shutdown()
    cluster.shutdown()


def test_a_tiny_grid_runs_on_ray_and_matches_the_local_run(cluster, tmp_path):
    cells = [
        *tiny_cells(2),
        Cell(ENV_ID, "SarsaAAC", "rbf10", 9, 300, **EVAL, overrides={"gamma": 5.0}),
    ]  # the last one raises
    status = bench_run.run_grid(cells, tmp_path / "ray", progress=False, engine=RayEngine())
    assert sorted(status["done"]) == sorted(c.cell_id for c in cells[:2])
    assert (
        status["failed"] == [cells[2].cell_id]
        and "gamma" in (tmp_path / "ray" / "errors" / f"{cells[2].cell_id}.txt").read_text()
    )
    for cell in cells[:2]:
        result = json.loads((tmp_path / "ray" / "cells" / f"{cell.cell_id}.json").read_text())
        assert (tmp_path / "ray" / result["model"]).stat().st_size > 1000  # the model came back as bytes
        assert any((tmp_path / "ray" / result["tensorboard"]).glob("events.out.tfevents.*"))
    assert not [p.name for p in (tmp_path / "ray").rglob(".*.tmp*")]
    # the same cell in the local pool: the engine changes where a cell runs, not what it computes
    local = bench_run.run_grid(cells[:1], tmp_path / "local", workers=1, progress=False)
    assert local["done"] == [cells[0].cell_id]
    on_ray, here = (json.loads((tmp_path / d / "cells" / f"{cells[0].cell_id}.json").read_text()) for d in ("ray", "local"))
    assert on_ray["final"] == here["final"] and on_ray["env_steps"] == here["env_steps"]
    # a rerun (as after a killed driver) skips the finished cells and retries the failed one
    again = bench_run.run_grid(cells, tmp_path / "ray", progress=False, engine=RayEngine())
    assert sorted(again["skipped"]) == sorted(status["done"]) and again["failed"] == [cells[2].cell_id]


def test_a_node_killed_mid_grid_loses_no_cell(cluster, tmp_path):
    """When the first cell has come back and both nodes are running the next ones (4 cells, 2 CPUs), the worker node
    is killed. Its cell runs again on the head node, and every cell of the grid ends with its files."""
    (worker,) = cluster.worker_nodes
    # a short first cell, then long ones: when the short one comes back, the other node's cell and the next one have
    # seconds left, far longer than the kill takes, so the worker is inside its cell when it dies
    short, *long = tiny_cells(4, budget=40_000)
    cells = [Cell.from_dict({**short.to_dict(), "budget": 1_000}), *long]
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    engine = RayEngine(max_retries=3, scratch_root=str(scratch))
    recorded: list[tuple[str, str]] = []
    running_at_kill: set[str] = set()

    def running() -> set[str]:
        """The cells whose attempt holds its lock in a scratch directory (one CPU per node: one per node)."""
        return {lock.stem for lock in scratch.glob("*/locks/*.lock")} - {cell_id for cell_id, _ in recorded}

    def record(cell_id, state, payload):
        recorded.append((cell_id, state))
        if len(recorded) == 1:
            deadline = time.monotonic() + 60
            while len(running()) < 2 and time.monotonic() < deadline:
                time.sleep(0.02)  # both nodes busy: the head and the worker each run a cell
            running_at_kill.update(running())
            cluster.remove_node(worker, allow_graceful=False)  # killed, as a lost machine

    try:
        engine.run(cells, tmp_path / "out", record, run_cell_safely)
    finally:
        cluster.add_node(**NODE)  # the module's cluster gets its second node back
        cluster.wait_for_nodes()
    assert sorted(recorded) == sorted((c.cell_id, "done") for c in cells)
    for cell in cells:
        result = json.loads((tmp_path / "out" / "cells" / f"{cell.cell_id}.json").read_text())
        assert (tmp_path / "out" / result["model"]).is_file()
    # both cells in flight at the kill (one of them the worker's) were finished by the head: the lost one was rerun
    assert len(running_at_kill) == 2
    assert all(engine.nodes[cell_id] != worker.node_id for cell_id in running_at_kill)
    # after the kill the grid went on without the worker node
    later = [engine.nodes[cell_id] for cell_id, _ in recorded[1:]]
    assert sum(node != worker.node_id for node in later) >= 2


def test_cell_files_stay_inside_the_results_directory(tmp_path):
    with pytest.raises(ValueError, match="outside"):
        write_cell_files(tmp_path, "x", {"../escape.txt": b"no"})
    assert not (tmp_path.parent / "escape.txt").exists()


def test_bad_engine_settings_are_refused():
    with pytest.raises(ValueError, match="max_retries"):
        RayEngine(max_retries=-1)
    with pytest.raises(ValueError, match="num_cpus"):
        RayEngine(num_cpus=0)


def test_a_local_instance_is_claimed_for_the_watchdog_before_ray_starts(monkeypatch, tmp_path):
    """The watchdog finds what a killed driver's Ray instance left by its directory; a directory named only after
    ``ray.init`` returns misses a worker started in between (the raylet ends with the driver, its children with no one)."""
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install sb3-aac[distributed])")
    from benchmarks import engines

    events: list[tuple[str, str | None]] = []

    class RecordingReaper:
        def __enter__(self):
            return self

        def __exit__(self, *exc_info):
            events.append(("exit", None))

        def claim(self, directory):
            events.append(("claim", directory))

    monkeypatch.setattr(engines, "ProcessReaper", RecordingReaper)
    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    monkeypatch.setattr(ray, "init", lambda **kwargs: events.append(("init", kwargs.get("_temp_dir"))))
    monkeypatch.setattr(ray, "shutdown", lambda: events.append(("shutdown", None)))
    monkeypatch.setenv("RAY_TMPDIR", str(tmp_path))
    with RayEngine(num_cpus=1).connected():
        events.append(("inside", None))
    assert [name for name, _ in events] == ["claim", "init", "inside", "shutdown", "exit"]
    claimed, started_in = events[0][1], events[1][1]
    assert claimed == started_in and claimed is not None and Path(claimed).parent == tmp_path and Path(claimed).is_dir()
