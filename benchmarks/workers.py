"""The worker pool of the grid and the tuning stage: tasks run in spawned processes, one BLAS thread each, that end
with their driver (:func:`run_in_pool`), and what a Ray task's process needs to behave the same (:func:`worker_env`).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any

import torch as th

from benchmarks import SINGLE_THREAD_ENV

PARENT_POLL_SECONDS = 0.2  # how often a worker checks that the driver still lives


def worker_env() -> dict[str, str]:
    """The variables a Ray task's process starts with: one BLAS/OpenMP thread (as the local pool's workers), and the
    driver's ``PYTHONPATH`` made absolute (the repository checkout when run with ``PYTHONPATH=.:envs``)."""
    value = os.environ.get("PYTHONPATH")
    if not value:
        return dict(SINGLE_THREAD_ENV)
    return {**SINGLE_THREAD_ENV, "PYTHONPATH": os.pathsep.join(os.path.abspath(p) for p in value.split(os.pathsep) if p)}


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
