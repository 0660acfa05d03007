"""Engines that run a grid's cells somewhere else than the driver's own process pool: Ray.

:func:`benchmarks.execution.run_grid` hands the cells still to run to an engine (a :class:`CellEngine`:
``engine.run(cells, out, record, run_cell)``, ``run_cell`` the runner's :func:`benchmarks.execution.run_cell_safely`);
without one it uses its local process pool (the default for one machine). An engine calls ``record(cell_id,
state, payload)`` once per cell, as the local pool does: ``state`` is ``"done"`` (``payload`` the cell's result
dict) or ``"failed"`` (``payload`` the error text).

:class:`RayEngine` submits every cell as one Ray task (one CPU each). A task runs the cell in a scratch directory
on whichever node Ray picks and returns the files it wrote as bytes (its model, TensorBoard events, and its cell
file, or its error file); the driver writes them under ``out`` through the runner's atomic writes, the cell file
last. So no filesystem is shared between the nodes, and a cell file still exists only once everything of its cell
is in place. A worker node that is lost takes its running tasks with it; Ray runs them again on another node (up to
``max_retries`` times), and a cell whose retries are exhausted is recorded as failed (``errors/<cell_id>.txt``) and
run again by the next invocation. The tasks belong to the driver: when the driver dies, Ray cancels them, and a
rerun skips the cells whose files were written. A Ray instance the driver started ends with it, ``kill -9`` included
(:mod:`benchmarks.process_reaper` ends what Ray's own fate sharing leaves behind).

Ray is an optional dependency (``pip install sb3-aac[distributed]``, with psutil for the watchdog); it is imported
only when a RayEngine runs.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import socket
import sys
import tempfile
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, Protocol

from benchmarks.presets import Cell
from benchmarks.process_reaper import ProcessReaper
from benchmarks.workers import worker_env
from sb3_aac.common.output_files import replaced_atomically

# How an engine reports a cell to run_grid: ``record(cell_id, state, payload)``, ``state`` "done" (payload the
# cell's result dict) or "failed" (payload the error text).
Record = Callable[[str, str, Any], None]
# How a cell is run, in whatever process: ``run_cell(cell_data, out)`` -> ``(cell_id, state, payload)``
# (:func:`benchmarks.execution.run_cell_safely`).
CellRunner = Callable[[dict[str, Any], str], tuple[str, str, Any]]


class CellEngine(Protocol):
    """Runs cells somewhere else than run_grid's local pool (:class:`RayEngine`), each with ``run_cell``, and reports
    each one through ``record``."""

    name: str

    def run(self, cells: Sequence[Cell], out: Path, record: Record, run_cell: CellRunner) -> None: ...


# How long the driver waits for a Ray cluster named by --address to accept a connection before giving up.
CONNECT_TIMEOUT_S = 10.0
# host:port of a cluster's GCS, or ray://host:port of its client server ("auto" is looked up by Ray itself).
_ADDRESS = re.compile(r"^(?:ray://)?(?P<host>\[[^\]]+\]|[^:/\[\]]+):(?P<port>\d{1,5})$")
# Variables of the driver a cell records (the command line, the invocation's provenance), passed to every task.
FORWARDED_ENV_PREFIX = "SB3_AAC_BENCH_"


def run_cell_in_scratch(
    run_cell: CellRunner, cell_data: dict[str, Any], environ: dict[str, str], scratch_root: str | None = None
) -> dict[str, Any]:
    """Run one cell with ``run_cell`` in a fresh scratch directory (under ``scratch_root``, default the system's
    temporary directory) on this machine; return its outcome and the files it wrote. An attempt killed with its node
    leaves its scratch directory behind on that node.

    :return: ``cell_id``, ``state`` and ``payload`` (as :func:`benchmarks.execution.run_cell_safely`), ``files`` (path
        relative to the results directory -> bytes) and ``node`` (the Ray node id, if in a Ray worker)
    """
    os.environ.update(environ)
    with tempfile.TemporaryDirectory(prefix="sb3-aac-cell-", dir=scratch_root) as scratch:
        cell_id, state, payload = run_cell(cell_data, scratch)
        root = Path(scratch)
        files = {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}
    node = None
    with contextlib.suppress(Exception):
        import ray  # optional (sb3-aac[distributed]): imported only when a Ray engine runs

        node = ray.get_runtime_context().get_node_id()
    return {"cell_id": cell_id, "state": state, "payload": payload, "files": files, "node": node}


def write_cell_files(out: Path, cell_id: str, files: dict[str, bytes]) -> None:
    """Write a cell's files under ``out`` atomically, its cell file (``cells/<cell_id>.json``) last.

    The cell's old TensorBoard directory goes first (a run interrupted before its cell file leaves one behind), and
    its error file once the cell has finished.
    """
    cell_file = f"cells/{cell_id}.json"
    unexpected = [name for name in files if Path(name).is_absolute() or ".." in Path(name).parts]
    if unexpected:
        raise ValueError(f"cell {cell_id} returned files outside its results directory: {unexpected}")
    if cell_file in files:
        shutil.rmtree(out / "tb" / cell_id, ignore_errors=True)
    for name in sorted(files, key=lambda n: n == cell_file):  # the cell file last
        target = out / name
        with replaced_atomically(target) as tmp, open(tmp, "wb") as f:
            f.write(files[name])
            f.flush()
            os.fsync(f.fileno())
    if cell_file in files:
        with contextlib.suppress(FileNotFoundError):
            (out / "errors" / f"{cell_id}.txt").unlink()


def local_ray_root() -> str:
    """A fresh directory for a Ray instance this driver starts (``ray.init(_temp_dir=...)``): ``sb3-aac-ray-*`` in
    the directory Ray itself would use (``$RAY_TMPDIR``, else ``$TMPDIR`` on Linux, else ``/tmp`` on Linux and
    macOS, whose long temporary paths would overflow the length of a Unix socket's path, else the system's). Ray
    keeps its logs there after the run, as it keeps its sessions in ``/tmp/ray``."""
    parent = os.environ.get("RAY_TMPDIR")
    if parent is None and sys.platform.startswith("linux"):
        parent = os.environ.get("TMPDIR")
    if parent is None and sys.platform.startswith(("linux", "darwin")):
        parent = "/tmp"
    return tempfile.mkdtemp(prefix="sb3-aac-ray-", dir=parent)


class RayEngine:
    """Each cell a Ray task (one CPU), results written by the driver.

    :param address: the Ray cluster to join (``ray.init(address=...)``, e.g. ``"auto"`` or ``"ray://host:10001"``);
        None starts a Ray instance on this machine with ``num_cpus`` CPUs. If Ray is already initialised in this
        process (a test's cluster), that connection is used and left open.
    :param num_cpus: CPUs of the local instance (only without ``address``)
    :param max_retries: how often Ray reruns a cell whose worker or node died
    :param scratch_root: where the tasks make their scratch directories, on every node (None: its temporary directory)
    """

    name = "ray"

    def __init__(
        self, address: str | None = None, num_cpus: int | None = None, max_retries: int = 3, scratch_root: str | None = None
    ):
        if max_retries < 0:
            raise ValueError(f"max_retries must be >= 0, got {max_retries}")
        if num_cpus is not None and num_cpus < 1:
            raise ValueError(f"num_cpus must be >= 1, got {num_cpus}")
        self.address, self.num_cpus, self.max_retries, self.scratch_root = address, num_cpus, max_retries, scratch_root
        self.nodes: dict[str, str | None] = {}  # cell id -> the node that ran its recorded attempt

    def check_address(self) -> None:
        """
        Check that a cluster listens at ``address`` (a TCP connection within :data:`CONNECT_TIMEOUT_S`), since Ray
        itself retries an unreachable address for minutes. Nothing to check without an address or for ``"auto"``.

        :raises ConnectionError: saying which address did not answer and how to start a cluster
        """
        if self.address is None or self.address == "auto":
            return
        match = _ADDRESS.match(self.address)
        if match is None:
            raise ConnectionError(f"--address {self.address!r} is not host:port, ray://host:port or 'auto'")
        host, port = match["host"].strip("[]"), int(match["port"])
        try:
            socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S).close()
        except OSError as error:
            raise ConnectionError(
                f"no Ray cluster answers at {self.address} within {CONNECT_TIMEOUT_S:.0f} s "
                f"({error.strerror or error}); start one there (`ray start --head --port {port}`) or drop --address"
            ) from None

    @contextlib.contextmanager
    def connected(self) -> Iterator[None]:
        """
        Ray initialised for the block: the connection this process has (left open), or one opened here and shut
        down at the end. A Ray instance started here (no ``address``) ends with this process however it ends: Ray
        fate-shares its GCS server and raylet with the driver, and a :class:`~benchmarks.process_reaper.ProcessReaper`
        ends the rest (the raylet's agents, a worker being started) if the driver is killed; its temporary directory
        (sockets, logs) is a fresh one of :func:`local_ray_root`'s, claimed for the watchdog before Ray starts.
        """
        import ray  # optional (sb3-aac[distributed]): imported only when a Ray engine runs

        if ray.is_initialized():
            yield
            return
        with contextlib.ExitStack() as stack:
            if self.address is None:
                reaper = stack.enter_context(ProcessReaper())
                root = local_ray_root()
                reaper.claim(root)  # before Ray starts: a process it starts is claimed however early the driver dies
                ray.init(num_cpus=self.num_cpus, include_dashboard=False, log_to_driver=False, _temp_dir=root)
                stack.callback(ray.shutdown)
            else:
                ray.init(address=self.address, log_to_driver=False)
                stack.callback(ray.shutdown)
            yield

    def run(self, cells: Sequence[Cell], out: Path, record: Record, run_cell: CellRunner) -> None:
        with self.connected():
            self._run(cells, out, record, run_cell)

    def _run(self, cells: Sequence[Cell], out: Path, record: Record, run_cell: CellRunner) -> None:
        import ray  # optional (sb3-aac[distributed]): imported only when a Ray engine runs
        from ray.exceptions import RayError  # optional, with ray above

        environ = {k: v for k, v in os.environ.items() if k.startswith(FORWARDED_ENV_PREFIX)}
        task = ray.remote(run_cell_in_scratch).options(
            num_cpus=1,
            max_retries=self.max_retries,
            retry_exceptions=False,  # a cell's own exception is an error file, not a reason to retry
            runtime_env={"env_vars": worker_env()},
        )
        pending = {task.remote(run_cell, cell.to_dict(), environ, self.scratch_root): cell.cell_id for cell in cells}
        try:
            while pending:
                finished, _ = ray.wait(list(pending), num_returns=1)
                ref = finished[0]
                cell_id = pending.pop(ref)
                try:
                    outcome = ray.get(ref)
                except RayError as error:  # retries exhausted (nodes lost again and again) or the task was cancelled
                    text = f"Ray could not run the cell: {type(error).__name__}: {error}\n"
                    write_cell_files(out, cell_id, {f"errors/{cell_id}.txt": text.encode()})
                    record(cell_id, "failed", text)
                    continue
                write_cell_files(out, cell_id, outcome["files"])
                self.nodes[cell_id] = outcome["node"]
                record(cell_id, outcome["state"], outcome["payload"])
        finally:
            for ref in pending:
                with contextlib.suppress(Exception):
                    ray.cancel(ref, force=True)
