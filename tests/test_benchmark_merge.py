"""A sweep on several machines: ``--shard I/N`` splits a grid (every cell in exactly one shard), and
``python -m benchmarks.merge`` puts the shards' results folders together into the folder one machine would have
written, with one provenance log; conflicting cells and mixed commits are refused. Synthetic cell files: nothing
trains here."""

from __future__ import annotations

import json
import os
import platform

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks import merge as bench_merge
from benchmarks import provenance
from benchmarks import run as bench_run
from benchmarks.cost import longest_first
from benchmarks.presets import build_cells
from benchmarks.report import build_report
from benchmarks.shards import Shard
from tests.test_benchmarks import synthetic_cell

# ---------------------------------------------------------------------------------------------------------------------
# Shards
# ---------------------------------------------------------------------------------------------------------------------

jobs = st.lists(st.tuples(st.text(min_size=1, max_size=4), st.floats(0, 1e4)), unique_by=lambda job: job[0], max_size=40)


@settings(max_examples=200, deadline=None)
@given(jobs, st.integers(1, 12), st.randoms(use_true_random=False))
def test_the_longest_first_split_places_every_item_once_whatever_their_order(items, bins, rng):
    split = longest_first(items, lambda job: job[1], lambda job: job[0], bins)
    assert len(split) == bins
    assert sorted(job for part in split for job in part) == sorted(items)  # every item exactly once
    shuffled = list(items)
    rng.shuffle(shuffled)
    assert longest_first(shuffled, lambda job: job[1], lambda job: job[0], bins) == split
    loads = [sum(seconds for _, seconds in part) for part in split]
    if items:
        assert max(loads) <= sum(loads) / bins + max(seconds for _, seconds in items) + 1e-6
    sizes = [len(part) for part in split]
    assert not (0 in sizes and max(sizes) >= 2)  # no shard idles while another has a second cell


FULL = build_cells("full")


@settings(max_examples=30, deadline=None)
@given(st.integers(1, len(FULL)), st.randoms(use_true_random=False))
def test_the_shards_of_a_preset_partition_its_cells(count, rng):
    shuffled = list(FULL)
    rng.shuffle(shuffled)
    shards = [Shard(i, count).cells(FULL) for i in range(1, count + 1)]
    ids = [cell.cell_id for shard in shards for cell in shard]
    assert sorted(ids) == sorted(cell.cell_id for cell in FULL)  # each cell in exactly one shard
    assert all(shards)
    assert Shard(1, count).cells(shuffled) == [c for c in shuffled if c in shards[0]]  # the order of the grid is no input


def test_the_cli_lists_a_shards_cells_and_refuses_bad_shards(tmp_path, capsys):
    listed = []
    for index in (1, 2, 3):
        assert bench_run.main(["--preset", "quick", "--out", str(tmp_path), "--list", "--shard", f"{index}/3"]) == 0
        listed.append([line.split()[1] for line in capsys.readouterr().out.splitlines()])
    assert sorted(cell_id for shard in listed for cell_id in shard) == sorted(cell.cell_id for cell in build_cells("quick"))
    assert all(listed)
    for argv, message in [
        (["--shard", "4/3"], "1 <= I <= N"),
        (["--shard", "0/3"], "1 <= I <= N"),
        (["--shard", "two"], "expected I/N"),
        (["--shard", "1/99", "--list"], "too few for 99 shards"),
        (["--shard", "1/2", "--estimate"], "--shard splits the grid run only"),
        (["--shard", "1/2", "--reliability"], "--shard splits the grid run only"),
        (["--cores", "4"], "--cores belongs to --estimate"),
        (["--estimate", "--cores", "2,0"], "must be >= 1"),
    ]:
        with pytest.raises(SystemExit) as info:
            bench_run.main(["--preset", "quick", "--out", str(tmp_path / "out"), *argv])
        assert info.value.code == 2 and message in capsys.readouterr().err, argv
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------------------------------------------------------------
# Merging results folders
# ---------------------------------------------------------------------------------------------------------------------

PLATFORM = "Platform-v0"


def sweep_cells(commit: str = "c0ffee") -> list[dict]:
    """A small sweep's cell files: enough seeds on Platform for the report's verdicts."""
    cells = [synthetic_cell(PLATFORM, "SarsaAAC", "tile", s, 0.95, "Tiles") for s in range(10)]
    cells += [synthetic_cell(PLATFORM, "MPDQN", "mpdqn", s, 0.9, "peer") for s in range(10)]
    for cell in cells:
        cell["provenance"] = {"invocation": "i", "git_commit": commit, "changed_files": [], "allow_dirty": False}
    return cells


def write_folder(folder, cells, host: str, extra_files: bool = True) -> None:
    """A results folder as a runner on ``host`` leaves it: cell files, models and TensorBoard folders, its log."""
    for cell in cells:
        (folder / "cells").mkdir(parents=True, exist_ok=True)
        (folder / "cells" / f"{cell['cell_id']}.json").write_text(json.dumps(cell))
        if extra_files:
            (folder / "models").mkdir(exist_ok=True)
            (folder / "models" / f"{cell['cell_id']}.zip").write_bytes(cell["cell_id"].encode())
            (folder / "tb" / cell["cell_id"]).mkdir(parents=True)
            (folder / "tb" / cell["cell_id"] / "events").write_text(host)
    log = folder / provenance.RUN_LOG
    base = {"invocation": host, "command": "python -m benchmarks.run --preset full", "workers": 2, "host": host}
    for event in (
        {"event": "start", **base},
        {"event": "end", **base, "status": "finished", "wall_s": 60.0, "done": 10, "skipped": 0},
    ):
        with open(log, "a") as f:
            f.write(json.dumps(event) + "\n")


def report_lines(folder) -> list[str]:
    """The report's lines, less those that differ between any two folders (when and where it was generated, the
    merge record)."""
    text = build_report(folder, figures=False).read_text()
    return [line for line in text.splitlines() if not line.startswith(("Generated", "Merged"))]


@pytest.fixture
def shards(tmp_path):
    """Two machines' folders, each with half the sweep, and the folder one machine running both would have."""
    cells = sweep_cells()
    a, b, single = tmp_path / "a", tmp_path / "b", tmp_path / "single"
    write_folder(a, cells[::2], "host-a")
    write_folder(b, cells[1::2], "host-b")
    write_folder(single, cells[::2], "host-a", extra_files=False)
    write_folder(single, cells[1::2], "host-b", extra_files=False)
    return a, b, single, cells


def test_merged_shards_give_the_report_of_one_folder_and_one_provenance_log(shards, tmp_path, capsys):
    a, b, single, cells = shards
    out = tmp_path / "merged"
    assert bench_merge.main([str(a), str(b), "--out", str(out)]) == 0
    assert "20 cells copied" in capsys.readouterr().out
    assert report_lines(out) == report_lines(single)
    for cell in cells:  # every cell's files came along
        assert (out / "models" / f"{cell['cell_id']}.zip").read_bytes() == cell["cell_id"].encode()
        assert (out / "tb" / cell["cell_id"] / "events").read_text() == ("host-a" if cell in cells[::2] else "host-b")
    hosts = {entry["host"] for entry in provenance.invocations(out)}
    assert hosts == {"host-a", "host-b"}
    (record,) = provenance.merges(out)
    assert record["hosts"] == ["host-a", "host-b"] and record["commits"] == {"c0ffee": 20}
    assert record["cells"] == record["copied"] == 20 and record["allow_mixed_commits"] is False
    assert record["sources"] == [str(a), str(b)] and record["machines"] == [cells[0]["machine"]]
    text = build_report(out, figures=False).read_text()
    assert "by `python -m benchmarks.merge` from 2 results folders: 20 cells (hosts: host-a, host-b)" in text
    assert "on host-a" in text and "2 hosts ran in parallel, the busiest for 1.0 min" in text


def test_merging_again_copies_only_what_is_new(shards, tmp_path):
    a, b, _, _ = shards
    out = tmp_path / "merged"
    bench_merge.merge([a], out)
    before = {p.name: p.stat().st_mtime_ns for p in (out / "cells").iterdir()}
    record = bench_merge.merge([a, b], out)  # machine b finished later
    assert record["copied"] == 10 and record["cells"] == 20
    assert {p.name: p.stat().st_mtime_ns for p in (out / "cells").iterdir() if p.name in before} == before
    again = bench_merge.merge([a, b], out)
    assert again["copied"] == 0 and again["cells"] == 20
    assert len(provenance.invocations(out)) == 2 and len(provenance.merges(out)) == 3  # no invocation twice


def test_a_cell_finished_twice_differently_is_refused_and_the_same_result_twice_is_kept_once(shards, tmp_path, capsys):
    a, b, _, cells = shards
    twin = cells[0]
    (b / "cells" / f"{twin['cell_id']}.json").write_text(json.dumps(twin))  # the very same result: a copy
    out = tmp_path / "merged"
    assert bench_merge.merge([a, b], out)["cells"] == 20
    other = {**twin, "started": "2026-01-02T00:00:00", "wall_s": 23.0}
    (b / "cells" / f"{twin['cell_id']}.json").write_text(json.dumps(other))
    fresh = tmp_path / "fresh"
    assert bench_merge.main([str(a), str(b), "--out", str(fresh)]) == 2
    err = capsys.readouterr().err
    assert "refused: 1 cells finished in more than one folder with different results" in err
    assert twin["cell_id"] in err and str(a) in err and str(b) in err and "2026-01-02T00:00:00" in err
    assert "remove its files" in err
    assert not fresh.exists()  # nothing written
    with pytest.raises(bench_merge.MergeError, match="different results"):
        bench_merge.merge([b], out)  # the merged folder's own cells count too


def test_cells_of_different_commits_are_refused_unless_allowed(tmp_path, capsys):
    a, b, out = tmp_path / "a", tmp_path / "b", tmp_path / "merged"
    write_folder(a, sweep_cells("aaa")[:3], "host-a", extra_files=False)
    write_folder(b, sweep_cells("bbb+dirty")[3:5], "host-b", extra_files=False)
    assert bench_merge.main([str(a), str(b), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "2 commits: aaa (3 cells), bbb+dirty (2 cells)" in err and "--allow-mixed-commits" in err
    assert not out.exists()
    assert bench_merge.main([str(a), str(b), "--out", str(out), "--allow-mixed-commits"]) == 0
    (record,) = provenance.merges(out)
    assert record["commits"] == {"aaa": 3, "bbb+dirty": 2} and record["allow_mixed_commits"] is True


def test_different_machines_and_versions_are_merged_with_a_warning(tmp_path, capsys):
    a, b = tmp_path / "a", tmp_path / "b"
    cells = sweep_cells()[:2]
    cells[0]["versions"] = {"python": "3.11", "git_commit": "c0ffee"}
    cells[1] = {**cells[1], "machine": {**cells[1]["machine"], "cpu": "other CPU"}, "versions": {"python": "3.12"}}
    write_folder(a, cells[:1], "host-a", extra_files=False)
    write_folder(b, cells[1:], "host-b", extra_files=False)
    record = bench_merge.merge([a, b], tmp_path / "merged")
    err = capsys.readouterr().err
    assert "2 sets of package versions" in err and "2 kinds of machine" in err
    assert record["versions"] == [{"python": "3.11"}, {"python": "3.12"}] and len(record["machines"]) == 2


def test_an_unfinished_cells_newest_error_comes_along_and_a_finished_cells_does_not(shards, tmp_path):
    a, b, _, cells = shards
    done = cells[0]["cell_id"]  # finished in a, failed earlier in b
    for folder, name, text, age in [(b, done, "old failure", 0), (a, "x__y", "older", 100), (b, "x__y", "newest", 0)]:
        (folder / "errors").mkdir(exist_ok=True)
        path = folder / "errors" / f"{name}.txt"
        path.write_text(text)
        os.utime(path, (path.stat().st_mtime - age,) * 2)
    out = tmp_path / "merged"
    bench_merge.merge([a, b], out)
    assert sorted(p.name for p in (out / "errors").iterdir()) == ["x__y.txt"]
    assert (out / "errors" / "x__y.txt").read_text() == "newest"


def test_the_merge_refuses_folders_it_cannot_merge(shards, tmp_path, capsys):
    a, b, _, _ = shards
    (tmp_path / "plain").mkdir()
    for argv, message in [
        ([str(tmp_path / "plain"), str(a)], "'plain' is not a results folder"),
        ([str(a), str(a)], "is given twice"),
        ([str(a), str(b), "--out", str(b)], "is also a source"),
    ]:
        argv = argv if "--out" in argv else [*argv, "--out", str(tmp_path / "merged")]
        assert bench_merge.main(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith("refused:") and message in err.replace(str(tmp_path) + "/", ""), argv
    assert not (tmp_path / "merged").exists()


def test_an_invocation_record_names_its_host(tmp_path):
    with provenance.logged_invocation(tmp_path, command="c", workers=1):
        pass
    (entry,) = provenance.invocations(tmp_path)
    assert entry["host"] == platform.node() and entry["status"] == "finished"


def test_a_shards_invocation_is_logged_with_its_shard_and_host(tmp_path):
    argv = ["--preset", "quick", "--only", "reference", "--shard", "1/1", "--workers", "1", "--allow-dirty"]
    assert bench_run.main([*argv, "--out", str(tmp_path)]) == 0
    (entry,) = provenance.invocations(tmp_path)
    assert entry["shard"] == "1/1" and entry["host"] == platform.node() and entry["done"] == 1
