"""``python -m benchmarks.compare A B``: the same cells of two results folders, group by group, on the seeds both
hold. Synthetic cell files: nothing trains here."""

from __future__ import annotations

import json

import numpy as np
import pytest

from benchmarks import compare as bench_compare
from benchmarks.cells import cell_path
from benchmarks.significance import welch_test
from tests.test_benchmarks import synthetic_cell

ENV_ID = "RoboCupDribblePaper-v0"


def write(folder, seed, final, overrides=None, config="deep", wall_clock=None):
    """A cell's file; ``wall_clock=(seconds, horizon)`` makes it a wall-clock cell (its id names the seconds)."""
    result = synthetic_cell(ENV_ID, "SarsaAAC", config, seed, final, "Deep")
    result["cell"]["overrides"] = overrides or {}
    if wall_clock:
        result["cell"]["seconds"], result["cell"]["budget"] = wall_clock
        result["cell_id"] = result["cell_id"].rsplit("__", 1)[0] + f"__{wall_clock[0]}s"
    path = cell_path(folder, result["cell_id"])
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result))
    return result["final"]["distance_mean"]


def table_rows(lines):
    return [line.split(" | ") for line in lines if line.startswith(f"| {ENV_ID}")]


def test_the_groups_both_folders_hold_are_compared_on_their_shared_seeds(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    scores_a = [write(a, seed, 20.0 + 0.1 * seed) for seed in range(6)]  # seed 5 only in A
    scores_b = [write(b, seed, 25.0 - 0.2 * seed, {"replay_ratio": 3}) for seed in range(5)]
    write(a, 0, 20.0, config="tile")  # a group B lacks: left out
    lines = bench_compare.compare_folders(a, b, min_seeds=5)
    ((_, learner, budget, seeds, settings_a, settings_b, mean_a, mean_b, diff, p, verdict),) = table_rows(lines)
    assert (learner, budget, seeds, settings_a, settings_b) == (
        "DeepPolicy (recommended)",
        "168k",
        "5",
        "defaults",
        "replay_ratio=3",
    )
    assert float(mean_a.split()[0]) == pytest.approx(np.mean(scores_a[:5]), abs=5e-4)
    assert float(mean_b.split()[0]) == pytest.approx(np.mean(scores_b), abs=5e-4)
    assert float(diff) == pytest.approx(np.mean(scores_b) - np.mean(scores_a[:5]), abs=5e-4)
    assert float(p) == pytest.approx(welch_test(scores_b, scores_a[:5])[1], rel=1e-2)
    assert verdict.rstrip(" |") == "B better"


def test_fewer_seeds_than_asked_give_no_verdict_and_a_swap_of_folders_swaps_it(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    for seed in range(5):
        write(a, seed, 25.0 + 0.1 * seed)
        write(b, seed, 20.0 + 0.1 * seed, {"gamma": 0.5})
    assert table_rows(bench_compare.compare_folders(a, b))[0][-1].rstrip(" |") == "too few seeds"  # 10 by default
    assert table_rows(bench_compare.compare_folders(a, b, min_seeds=5))[0][-1].rstrip(" |") == "A better"
    assert table_rows(bench_compare.compare_folders(b, a, min_seeds=5))[0][-1].rstrip(" |") == "B better"


def test_wall_clock_groups_pair_by_their_seconds_whatever_their_horizons(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    for seed in range(5):
        write(a, seed, 30.0 + 0.1 * seed, wall_clock=(120, 1_668_322))
        write(b, seed, 28.0 + 0.1 * seed, wall_clock=(120, 396_000))  # a slower learner's horizon
        write(b, seed, 28.0 + 0.1 * seed, wall_clock=(60, 396_000))  # other seconds: left out
    ((_, _, budget, seeds, *_, verdict),) = table_rows(bench_compare.compare_folders(a, b, min_seeds=5))
    assert (budget, seeds, verdict.rstrip(" |")) == ("120 s", "5", "A better")


@pytest.mark.parametrize(
    ("argv", "message"),
    [(["{a}", "{tmp}/missing"], "is not a results folder"), (["{a}", "{a}", "--min-seeds", "1"], "at least 2")],
)
def test_the_command_refuses_what_it_cannot_compare(tmp_path, capsys, argv, message):
    a = tmp_path / "a"
    write(a, 0, 20.0)
    with pytest.raises(SystemExit) as info:
        bench_compare.main([arg.format(a=a, tmp=tmp_path) for arg in argv])
    assert info.value.code == 2 and message in capsys.readouterr().err


def test_the_command_prints_the_table(tmp_path, capsys):
    a, b = tmp_path / "a", tmp_path / "b"
    for seed in range(3):
        write(a, seed, 20.0)
        write(b, seed, 21.0)
    assert bench_compare.main([str(a), str(b), "--min-seeds", "3"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"A: {a}; B: {b}") and len(table_rows(out.splitlines())) == 1
