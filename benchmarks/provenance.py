"""Provenance of a benchmark sweep: which source ran it, and a log of every invocation.

* :func:`git_state` / :func:`require_clean_tree`: a sweep refuses to start from a git tree with uncommitted changes
  to tracked files (the results then name a commit that did not produce them), unless told ``--allow-dirty``.
  Changes inside the results directory itself do not count (a sweep writing into a committed results directory
  would otherwise refuse its own second invocation); untracked files do not count either.
* :func:`cell_provenance`: what every cell file records under ``"provenance"``: the invocation's id, the driver's
  commit (``+dirty`` when the tree had changes), the changed files, and whether ``--allow-dirty`` was given.
* :func:`logged_invocation` / :func:`invocations`: ``runs.jsonl`` gets a ``start`` record when an invocation starts
  and an ``end`` record (its status, wall time and cell counts) when it stops, also by an exception or Ctrl-C; an
  invocation killed outright (``SIGKILL``, power loss) keeps its start record and reads as ``"killed"``. Each
  record names the host it ran on.
* :func:`merges`: the ``merge`` records :mod:`benchmarks.merge` appends to ``runs.jsonl`` when it puts the results
  folders of several machines together (the folders, hosts, commits, versions and machines of the merged cells).
"""

from __future__ import annotations

import contextlib
import json
import os
import platform
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium
import numba
import numpy as np
import stable_baselines3
import torch as th

import sb3_aac

REPO = Path(__file__).resolve().parents[1]
ENV_VAR = "SB3_AAC_BENCH_PROVENANCE"  # the invocation's provenance, JSON, for the cells it runs (workers inherit it)
RUN_LOG = "runs.jsonl"
MERGE_EVENT = "merge"  # the event of a record benchmarks.merge appends to RUN_LOG


class DirtyTreeError(RuntimeError):
    """The source tree has uncommitted changes and the sweep was not told ``--allow-dirty``."""


@dataclass(frozen=True)
class GitState:
    """The checkout a sweep runs from: ``commit`` is ``"unknown"`` outside a git repository."""

    commit: str
    changed_files: tuple[str, ...]

    @property
    def dirty(self) -> bool:
        return bool(self.changed_files)

    @property
    def label(self) -> str:
        """The commit, with ``+dirty`` when tracked files have uncommitted changes."""
        return self.commit + ("+dirty" if self.dirty else "")


def _git(repo: Path, *args: str) -> str:
    return subprocess.run(["git", *args], cwd=repo, capture_output=True, text=True, timeout=10, check=True).stdout


def git_state(repo: Path = REPO, ignore: tuple[Path, ...] = ()) -> GitState:
    """The commit of ``repo`` and its tracked files with uncommitted changes, except those under ``ignore``."""
    try:
        commit = _git(repo, "rev-parse", "HEAD").strip()
        top = Path(_git(repo, "rev-parse", "--show-toplevel").strip()).resolve()
        status = _git(repo, "status", "--porcelain", "--untracked-files=no", "-z")
    except (OSError, subprocess.SubprocessError):
        return GitState("unknown", ())
    ignored = [p.resolve() for p in ignore]
    changed = []
    entries = iter(status.split("\0"))
    for entry in entries:  # "XY path"; a rename or copy (X = R or C) is followed by its source path
        if not entry:
            continue
        if entry[0] in "RC":
            next(entries, None)
        path = (top / entry[3:]).resolve()
        if not any(path == d or d in path.parents for d in ignored):
            changed.append(entry[3:])
    return GitState(commit, tuple(changed))


def require_clean_tree(repo: Path = REPO, allow_dirty: bool = False, ignore: tuple[Path, ...] = ()) -> GitState:
    """``git_state``, raising :class:`DirtyTreeError` if tracked files (outside ``ignore``) have uncommitted changes
    and ``allow_dirty`` is False."""
    state = git_state(repo, ignore)
    if state.dirty and not allow_dirty:
        files = state.changed_files
        shown = ", ".join(files[:10]) + (f" and {len(files) - 10} more" if len(files) > 10 else "")
        raise DirtyTreeError(
            f"the source tree {repo} has uncommitted changes ({shown}): commit them so the results name the code that "
            "produced them, or pass --allow-dirty (recorded in every cell)"
        )
    return state


def new_invocation_id() -> str:
    return uuid.uuid4().hex[:12]


def invocation_provenance(invocation: str, state: GitState, allow_dirty: bool) -> dict[str, Any]:
    """The record of one invocation that each of its cells carries; :func:`cell_provenance` reads it back."""
    return {
        "invocation": invocation,
        "git_commit": state.label,
        "changed_files": list(state.changed_files),
        "allow_dirty": allow_dirty,
    }


def cell_provenance() -> dict[str, Any]:
    """The provenance a cell records: its invocation's (from :data:`ENV_VAR`), or, for cells run by calling
    ``run_grid`` from Python (no invocation, no clean-tree check), this checkout's commit and ``allow_dirty: None``."""
    text = os.environ.get(ENV_VAR)
    if text:
        return dict(json.loads(text))
    state = git_state()
    return {"invocation": None, "git_commit": state.label, "changed_files": list(state.changed_files), "allow_dirty": None}


def append_record(path: Path, record: dict[str, Any]) -> None:
    """One JSON line, appended and flushed to disk (a later kill cannot take it back)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as f:
        f.write(json.dumps(record) + "\n")
        f.flush()
        os.fsync(f.fileno())


@contextlib.contextmanager
def logged_invocation(out: Path, **fields: Any) -> Iterator[dict[str, Any]]:
    """Log one invocation in ``out/runs.jsonl``: a ``start`` record now, an ``end`` record when the block exits.

    Yields a dict the caller fills with what the end record should add (cell counts). The end record's ``status``
    is ``"finished"``, ``"interrupted"`` (KeyboardInterrupt), ``"refused"`` (:class:`DirtyTreeError`) or
    ``"failed: <exception type>"``; the exception still propagates.
    """
    start = time.time()
    base = {"invocation": fields.pop("invocation", None) or new_invocation_id(), **fields, "host": platform.node()}
    base["start"] = time.strftime("%Y-%m-%dT%H:%M:%S", time.localtime(start))
    append_record(out / RUN_LOG, {"event": "start", **base})
    extra: dict[str, Any] = {}
    status = "finished"
    try:
        yield extra
    except KeyboardInterrupt:
        status = "interrupted"
        raise
    except DirtyTreeError:
        status = "refused"
        raise
    except BaseException as error:
        status = f"failed: {type(error).__name__}"
        raise
    finally:
        append_record(
            out / RUN_LOG, {"event": "end", **base, "status": status, "wall_s": round(time.time() - start, 1), **extra}
        )


def read_records(out: Path) -> list[dict[str, Any]]:
    """The records of ``out/runs.jsonl`` in file order (none if it is missing); a torn line (a writer killed
    mid-line) is skipped with a warning naming it."""
    path = out / RUN_LOG
    if not path.exists():
        return []
    records = []
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if not line.strip():
            continue
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            print(f"warning: {path}:{number} is not a JSON record (a torn line?); skipped", file=sys.stderr)
    return records


def invocations(out: Path) -> list[dict[str, Any]]:
    """Every invocation logged in ``out/runs.jsonl``, in start order: its end record if it has one, else its start
    record with ``status`` ``"killed"`` and ``wall_s`` None. Lines written before start/end records existed (no
    ``event`` key) are invocations that finished; merge records (:func:`merges`) are no invocations."""
    entries: list[dict[str, Any]] = []
    index: dict[str, int] = {}
    for record in read_records(out):
        event = record.pop("event", None)
        if event == MERGE_EVENT:
            continue
        if event is None:
            entries.append({"status": "finished", **record})
        elif event == "start":
            index[record["invocation"]] = len(entries)
            entries.append({**record, "status": "killed", "wall_s": None})
        elif event == "end" and record.get("invocation") in index:
            entries[index[record["invocation"]]] = record
        else:
            entries.append(record)  # an end record whose start line was lost
    return entries


def merges(out: Path) -> list[dict[str, Any]]:
    """The merge records of ``out/runs.jsonl`` (:mod:`benchmarks.merge`), in the order they were made."""
    return [record for record in read_records(out) if record.get("event") == MERGE_EVENT]


# ---------------------------------------------------------------- where a cell ran: versions, machine, load


def versions() -> dict[str, str]:
    """The versions of Python and the packages a cell ran with, and the checkout's commit."""
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
    """The CPU, its cores, the platform and torch's threads."""
    cpu = platform.processor() or platform.machine()
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    return {"cpu": cpu, "cores": os.cpu_count(), "platform": platform.platform(), "torch_threads": th.get_num_threads()}


def loadavg() -> float | None:
    """The one-minute load average, or None where the platform has none."""
    try:
        return round(os.getloadavg()[0], 2)
    except OSError:
        return None
