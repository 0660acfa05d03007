"""A watchdog that ends the processes a driver started as soon as the driver is gone, however it ended (``kill -9``
included), for the Ray instance :class:`benchmarks.engines.RayEngine` starts on this machine.

Ray ends its GCS server and raylet with the driver that started them, but the raylet's agents (``DashboardAgent``,
``RuntimeEnvAgent``) outlive it: they see the raylet die, then block for minutes reporting it to the dead GCS; and a
worker that was starting at that moment lingers for half a minute.

:class:`ProcessReaper` (a context manager in the driver) starts this file as a script: a child of the driver in a
session of its own, so a Ctrl-C or a signal to the driver's process group does not reach it. The watchdog knows the
driver's processes two ways, both limited to processes started after the watchdog itself:

* by ancestry: it notes the driver's descendants, every :data:`POLL_MIN_SECONDS` while the process tree changes,
  backing off to :data:`POLL_MAX_SECONDS` while it does not (this covers a driver killed while Ray starts);
* by directory: once the driver names a directory (:meth:`ProcessReaper.claim`: the Ray instance's temporary
  directory, named before Ray starts), every process of this user whose command line names it (a starting Ray
  worker) or that has a file open in it (each of Ray's processes writes its log there, the agents included), found
  when the driver is gone, so none started in the last poll escapes (nor another program reading those logs).
  (Ancestry alone misses a worker the raylet started in the last poll: the raylet ends with the driver, and its
  children are nobody's then.)

Processes are held as ``psutil.Process`` objects, which refuse to signal a process whose id was reused. When the
driver is gone (its end of the watchdog's stdin closes without :data:`STOP`), the watchdog sends SIGTERM to every such
process still alive and to their descendants, SIGKILL to those still alive :data:`GRACE_SECONDS` later, looks again
(up to :data:`REAP_ROUNDS` rounds, until it finds none), and exits. A driver that cleaned up itself leaves the
block, which writes :data:`STOP`: the watchdog exits without killing anything.

Needs ``psutil`` (in ``pip install sb3-aac[distributed]``); this file imports nothing else outside the standard library.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import threading
from types import TracebackType
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import psutil  # optional (sb3-aac[distributed]): the watchdog runs only beside a Ray instance

POLL_MIN_SECONDS = 0.1  # the note interval right after the driver's process tree changed
POLL_MAX_SECONDS = 1.0  # ... doubling to this while it stays the same
GRACE_SECONDS = 2.0  # between SIGTERM and SIGKILL of the driver's leftovers
REAP_ROUNDS = 3  # rounds of finding and ending them, until one finds none
STOP = "stop"  # the driver's "I cleaned up myself", a line on the watchdog's stdin
CLAIM = "claim "  # ... and "processes using this directory are mine": CLAIM + path
STOP_TIMEOUT_SECONDS = 10.0  # how long the driver waits for the watchdog to exit after STOP


class ProcessReaper:
    """In the driver, around the code that starts processes: the watchdog (see the module) runs from ``__enter__`` to
    ``__exit__``, and ends the processes the driver started since ``__enter__`` if the driver dies in between."""

    def __init__(self) -> None:
        self._watchdog: subprocess.Popen[str] | None = None

    def __enter__(self) -> ProcessReaper:
        try:
            import psutil  # noqa: F401  (the watchdog's one dependency: fail here, in the driver, with the remedy)
        except ImportError:
            raise ImportError("the Ray engine's process watchdog needs psutil: pip install sb3-aac[distributed]") from None
        self._watchdog = subprocess.Popen(
            [sys.executable, os.path.abspath(__file__), str(os.getpid())],
            stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            start_new_session=True,
            text=True,
        )
        return self

    def claim(self, directory: str) -> None:
        """Tell the watchdog that the processes using ``directory`` (see the module) are the driver's too."""
        self._send(f"{CLAIM}{os.path.abspath(directory)}\n")

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        watchdog = self._watchdog
        if watchdog is None:
            return
        self._send(f"{STOP}\n")
        with contextlib.suppress(OSError):
            watchdog.stdin.close()  # type: ignore[union-attr]
        try:
            watchdog.wait(STOP_TIMEOUT_SECONDS)
        except subprocess.TimeoutExpired:
            watchdog.kill()
            watchdog.wait()
        self._watchdog = None

    def _send(self, line: str) -> None:
        if self._watchdog is None or self._watchdog.stdin is None:
            raise RuntimeError("the watchdog runs only inside the ProcessReaper block")
        with contextlib.suppress(OSError):  # it has exited already
            self._watchdog.stdin.write(line)
            self._watchdog.stdin.flush()

    @property
    def pid(self) -> int | None:
        """The watchdog's process id while it runs."""
        return None if self._watchdog is None else self._watchdog.pid


def watch(driver_pid: int) -> None:
    """The watchdog's loop (in its own process): note the driver's new descendants until the driver stops it or is
    gone; in the second case end them and the processes of the claimed directories."""
    import psutil  # optional (sb3-aac[distributed]): the watchdog runs only beside a Ray instance

    me = psutil.Process()
    started = me.create_time()
    stopped, stdin_closed = threading.Event(), threading.Event()
    claimed: list[str] = []

    def read_stdin() -> None:
        for line in sys.stdin:  # ends at EOF: after STOP, or at the driver's death
            if line.rstrip("\n") == STOP:
                stopped.set()
            elif line.startswith(CLAIM):
                claimed.append(line[len(CLAIM) :].rstrip("\n"))
        stdin_closed.set()

    threading.Thread(target=read_stdin, name="driver-pipe", daemon=True).start()
    noted: dict[int, psutil.Process] = {}
    interval = POLL_MIN_SECONDS
    with contextlib.suppress(psutil.NoSuchProcess):  # the driver is gone
        driver = psutil.Process(driver_pid)
        while not stdin_closed.wait(interval) and driver.is_running():
            new = [p for p in driver.children(recursive=True) if p.pid not in noted and p.pid != me.pid]
            new = [p for p in new if p.create_time() >= started]  # psutil read the start time when it made p
            noted.update((p.pid, p) for p in new)
            interval = POLL_MIN_SECONDS if new else min(2 * interval, POLL_MAX_SECONDS)
    stdin_closed.wait(POLL_MAX_SECONDS)  # the last lines of a driver that said STOP (it waits for us to exit)
    if stopped.is_set():
        return
    for _ in range(REAP_ROUNDS):  # again, for a process that was being started during a round
        found = [p for p in [*noted.values(), *users_of(claimed, started, skip=me.pid)] if running(p)]
        if not found:
            break
        reap(found)


def users_of(directories: list[str], started: float, skip: int) -> list[psutil.Process]:
    """This user's processes started since ``started`` (except ``skip``) whose command line names one of
    ``directories`` or that have a file open inside one."""
    import psutil  # optional (sb3-aac[distributed]): the watchdog runs only beside a Ray instance

    if not directories:
        return []
    inside = tuple(os.path.join(d, "") for d in directories)
    uid = os.getuid() if hasattr(os, "getuid") else None
    found = []
    for process in psutil.process_iter():
        with contextlib.suppress(psutil.NoSuchProcess, psutil.AccessDenied):
            if process.pid == skip or process.create_time() < started or (uid is not None and process.uids().real != uid):
                continue
            if any(d in arg for arg in process.cmdline() for d in directories) or any(
                f.path.startswith(inside) for f in process.open_files()
            ):
                found.append(process)
    return found


def running(process: psutil.Process) -> bool:
    """Whether ``process`` still runs: it exists, is not a zombie, and its id was not reused."""
    import psutil  # optional (sb3-aac[distributed]): the watchdog runs only beside a Ray instance

    try:
        return process.is_running() and process.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def reap(processes: list[psutil.Process]) -> None:
    """SIGTERM to each of ``processes`` still alive and to its descendants, then SIGKILL to those alive
    :data:`GRACE_SECONDS` later."""
    import psutil  # optional (sb3-aac[distributed]): the watchdog runs only beside a Ray instance

    targets: dict[int, psutil.Process] = {}
    for process in processes:
        with contextlib.suppress(psutil.NoSuchProcess):
            if running(process):
                targets[process.pid] = process
                targets.update((p.pid, p) for p in process.children(recursive=True) if running(p))
    for process in targets.values():
        with contextlib.suppress(psutil.NoSuchProcess):
            process.terminate()
    _, alive = psutil.wait_procs(list(targets.values()), timeout=GRACE_SECONDS)
    for process in alive:
        with contextlib.suppress(psutil.NoSuchProcess):
            process.kill()


if __name__ == "__main__":
    watch(int(sys.argv[1]))
