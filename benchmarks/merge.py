"""Put the results folders of one sweep, run on several machines, together into one: one report, one provenance log.

Usage::

    python -m benchmarks.merge SOURCE [SOURCE ...] --out DIR [--allow-mixed-commits]
    python -m benchmarks.report DIR

Each machine runs its shard into its own folder (``python -m benchmarks.run --preset P --shard I/N --out
runs/shard-I``, :mod:`benchmarks.shards`), and the folders are copied here. The merge takes the union of their
finished cells: each cell's model and TensorBoard folder, then its cell file (as in a run, a cell file exists only
once its cell's other files are in place); the error file of a cell that no folder finished (the newest, if several
have one); and every record of their ``runs.jsonl`` (every machine's invocations, each naming its host), to which it
appends one ``merge`` record: the folders, the hosts, and the commits, package versions and machines of the merged
cells (:func:`benchmarks.provenance.merges`; the report shows it).

Refused before anything is written, saying what to do: a cell finished in two folders with different results (the
very same result twice is kept once); cells of different commits (the shards of one sweep run one commit;
``--allow-mixed-commits`` takes them, and the merge record says so); a source that is no results folder, a source
given twice, ``--out`` among the sources. Cells that ran with different package versions or on different CPUs are
merged with a warning: their seconds (the report's time axes, the equal wall-clock budget) then compare machines
as well as learners.

``--out`` may hold an earlier merge (or a run): its cells count as one more source and only what it lacks is
copied, so the same command again adds the shards that finished since, or completes a merge that was killed.
``reliability.json`` and reports are not copied: the reliability test picks the best policies among all the cells,
so it runs on the merged folder (``python -m benchmarks.run --reliability --out DIR``).
"""

from __future__ import annotations

import argparse
import json
import platform
import shlex
import shutil
import sys
import time
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from benchmarks import cells
from benchmarks.provenance import MERGE_EVENT, RUN_LOG, append_record, read_records
from sb3_aac.common.output_files import check_writable_dir, replaced_atomically


class MergeError(ValueError):
    """The folders cannot be merged as they are; the message says why and what to do."""


def merge(
    sources: Sequence[str | Path], out: str | Path, allow_mixed_commits: bool = False, command: str = ""
) -> dict[str, Any]:
    """
    Merge the results folders ``sources`` into ``out`` (see the module's docstring); returns the merge record
    appended to ``out/runs.jsonl``.

    :raises MergeError: if the folders cannot be merged, before anything is written
    """
    folders, out = [Path(s) for s in sources], Path(out)
    _check_folders(folders, out)
    present = _finished(out)
    found = {folder: _finished(folder) for folder in folders}
    _check_conflicts({out: present, **found})
    copy: dict[str, Path] = {}  # cell id -> the folder its files come from
    for folder, results in found.items():
        for cell_id in results:
            if cell_id not in present:
                copy.setdefault(cell_id, folder)
    merged = {**present, **{cell_id: found[folder][cell_id] for cell_id, folder in copy.items()}}
    commits = Counter(_commit(result) for result in merged.values())
    if len(commits) > 1 and not allow_mixed_commits:
        shown = ", ".join(f"{commit} ({n} cells)" for commit, n in commits.most_common())
        raise MergeError(
            f"the cells come from {len(commits)} commits: {shown}; the shards of one sweep run one commit: rerun the "
            "odd cells at the others' commit, or pass --allow-mixed-commits (recorded in the merge record)"
        )
    versions = _distinct(  # the packages' (the commits are counted above)
        {name: version for name, version in result.get("versions", {}).items() if name != "git_commit"}
        for result in merged.values()
    )
    machines = _distinct(result.get("machine", {}) for result in merged.values())
    if len(versions) > 1:
        _warn(f"the cells ran with {len(versions)} sets of package versions; the report lists each")
    if len({m.get("cpu") for m in machines}) > 1:
        _warn(
            f"the cells ran on {len(machines)} kinds of machine; their seconds (time axes, the equal wall-clock budget) "
            "compare machines as well as learners"
        )
    try:
        check_writable_dir(out, "--out")
    except ValueError as error:
        raise MergeError(str(error)) from None
    for cell_id, folder in sorted(copy.items()):
        _copy_cell(folder, out, cell_id)
    _copy_errors([out, *folders], out, set(merged))
    log = _merge_logs(folders, out)
    record = {
        "event": MERGE_EVENT,
        "merged": time.strftime("%Y-%m-%dT%H:%M:%S"),
        "host": platform.node(),
        "command": command,
        "sources": [str(folder) for folder in folders],
        "cells": len(merged),
        "copied": len(copy),
        "hosts": sorted({r["host"] for r in log if r.get("host") and r.get("event") != MERGE_EVENT}),
        "commits": dict(commits.most_common()),
        "versions": versions,
        "machines": machines,
        "allow_mixed_commits": allow_mixed_commits,
    }
    append_record(out / RUN_LOG, record)
    return record


def _check_folders(folders: list[Path], out: Path) -> None:
    """Every source a results folder, none given twice, and ``out`` none of them, with nothing in the way of a merge."""
    wrong = [f"{str(f)!r} is not a results folder (it has no cells/ folder)" for f in folders if not (f / "cells").is_dir()]
    resolved = [f.resolve() for f in folders]
    wrong += [f"{str(f)!r} is given twice" for i, f in enumerate(folders) if resolved[i] in resolved[:i]]
    if out.resolve() in resolved:
        wrong.append(f"--out {str(out)!r} is also a source (give a new folder, or an earlier merge's)")
    if wrong:
        raise MergeError("; ".join(wrong) + ": the sources are the --out folders of benchmarks.run")
    if out.exists() and not out.is_dir():
        raise MergeError(f"--out {str(out)!r} is a file; give a folder")
    try:
        cells.check_results_folder(out, (RUN_LOG,))
    except ValueError as error:
        raise MergeError(str(error)) from None


def _finished(folder: Path) -> dict[str, dict[str, Any]]:
    """The sound cell results of ``folder`` by cell id; each damaged cell file is named in a warning and not merged."""
    results, damaged = cells.read_cells(folder)
    for message in damaged:
        _warn(f"{message}; not merged")
    return {result["cell_id"]: result for result in results}


def _canonical(data: Any) -> str:
    return json.dumps(data, sort_keys=True)


def _check_conflicts(folders: dict[Path, dict[str, dict[str, Any]]]) -> None:
    """:raises MergeError: naming every cell that finished in two folders with different results."""
    holders: dict[str, dict[str, Path]] = {}  # cell id -> canonical result -> the first folder holding it
    for folder, results in folders.items():
        for cell_id, result in results.items():
            holders.setdefault(cell_id, {}).setdefault(_canonical(result), folder)
    conflicts = []
    for cell_id, versions in sorted(holders.items()):
        if len(versions) > 1:
            shown = " and ".join(
                f"{str(folder)!r} (started {data.get('started', '?')}, commit {_commit(data)})"
                for folder, data in ((folder, json.loads(text)) for text, folder in versions.items())
            )
            conflicts.append(f"{cell_id}: {shown}")
    if conflicts:
        listed = "; ".join(conflicts[:10]) + (f"; and {len(conflicts) - 10} more" if len(conflicts) > 10 else "")
        raise MergeError(
            f"{len(conflicts)} cells finished in more than one folder with different results: {listed}. A cell's "
            "result must come from one run: remove its files (cells/<id>.json, models/<id>.zip, tb/<id>) from all "
            "folders but one, then merge again"
        )


def _commit(result: dict[str, Any]) -> str:
    """The commit a cell's invocation ran (``+dirty`` with uncommitted changes), or ``"unknown"``."""
    return str((result.get("provenance") or {}).get("git_commit", "unknown"))


def _distinct(values: Any) -> list[Any]:
    """The distinct values (JSON objects) in their first order."""
    seen: dict[str, Any] = {}
    for value in values:
        seen.setdefault(_canonical(value), value)
    return list(seen.values())


def _warn(message: str) -> None:
    print(f"warning: {message}", file=sys.stderr)


def _copy_file(source: Path, target: Path) -> None:
    """Copy ``source`` (its times too) to ``target`` atomically."""
    with replaced_atomically(target, suffix=target.suffix) as tmp:
        shutil.copy2(source, tmp)


def _copy_cell(folder: Path, out: Path, cell_id: str) -> None:
    """A cell's model and TensorBoard folder (where ``folder`` has them), then its cell file."""
    model = Path("models") / f"{cell_id}.zip"
    if (folder / model).is_file():
        _copy_file(folder / model, out / model)
    events = Path("tb") / cell_id
    if (folder / events).is_dir():
        shutil.rmtree(out / events, ignore_errors=True)  # a merge killed while copying it
        shutil.copytree(folder / events, out / events)
    _copy_file(cells.cell_path(folder, cell_id), cells.cell_path(out, cell_id))


def _copy_errors(folders: list[Path], out: Path, finished: set[str]) -> None:
    """The newest error file of every cell not in ``finished`` into ``out/errors``; those of finished cells go."""
    newest: dict[str, Path] = {}
    for folder in folders:
        for path in sorted((folder / "errors").glob("*.txt")):
            known = newest.get(path.stem)
            if path.stem not in finished and (known is None or path.stat().st_mtime > known.stat().st_mtime):
                newest[path.stem] = path
    for path in newest.values():
        if path.parent != out / "errors":
            _copy_file(path, out / "errors" / path.name)
    for path in sorted((out / "errors").glob("*.txt")):
        if path.stem in finished:
            path.unlink()


def _merge_logs(folders: list[Path], out: Path) -> list[dict[str, Any]]:
    """Append to ``out/runs.jsonl`` every record of the folders' logs it lacks; returns the whole log."""
    log = read_records(out)
    seen = {_canonical(record) for record in log}
    for folder in folders:
        for record in read_records(folder):
            if _canonical(record) not in seen:
                append_record(out / RUN_LOG, record)
                seen.add(_canonical(record))
                log.append(record)
    return log


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.merge", description=__doc__.split("\n\n")[0])
    parser.add_argument("sources", nargs="+", help="results folders (the --out of benchmarks.run on each machine)")
    parser.add_argument("--out", required=True, help="the merged results folder (a new one, or an earlier merge's)")
    parser.add_argument(
        "--allow-mixed-commits", action="store_true", help="merge cells of different commits (recorded in the merge record)"
    )
    args = parser.parse_args(argv)
    command = "python -m benchmarks.merge " + shlex.join(sys.argv[1:] if argv is None else argv)
    try:
        record = merge(args.sources, args.out, args.allow_mixed_commits, command)
    except MergeError as error:
        print(f"refused: {error}", file=sys.stderr)
        return 2
    hosts = ", ".join(record["hosts"]) or "not recorded"
    print(
        f"{record['copied']} cells copied; {args.out} holds {record['cells']} cells from {len(args.sources)} folders "
        f"(hosts: {hosts}); next: python -m benchmarks.report {args.out}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
