"""``sb3-aac pitch``: its argument errors, and (when an rcssserver binary is found) a short real run with its CSV."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import pytest

from robocup_dribble.rcss import find_server
from sb3_aac.cli import main
from tests.test_cli import run_error


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["pitch", "dribbler", "--profile", "v11", "--server", "x"], "v11 cannot be played on a real server"),
        (["pitch", "dribbler", "--server", "/no/such/rcssserver"], "is not an executable file"),
        (["pitch", "dribbler", "--server", "x", "--out", "results.json"], "must end with .csv"),
        (["pitch", "dribbler", "--episodes", "0"], "must be in 1 .. 10,000,000"),
        (["pitch", "dribbler", "--server", "x", "--world-seed", "4294967295"], "--world-seed: world_seed must be an integer"),
        (
            ["pitch", "dribbler", "--server", "x", "--timeout", "1e12"],
            "--timeout: timeout must be a number of seconds in (0, 3600]",
        ),
    ],
)
def test_pitch_errors(capsys, argv: list[str], message: str) -> None:
    assert message in run_error(capsys, argv)


def test_a_binary_that_is_no_server_is_one_line(capsys) -> None:
    true = shutil.which("true")
    assert true is not None
    err = run_error(capsys, ["pitch", "dribbler", "--server", true, "--episodes", "2", "--timeout", "3"])
    assert "rcssserver exited (exit status 0)" in err or "private network namespace" in err


def test_no_server_found_says_how_to_get_one(capsys, monkeypatch) -> None:
    monkeypatch.delenv("RCSSSERVER", raising=False)
    monkeypatch.setenv("PATH", "/nonexistent")
    assert "no rcssserver found: give --server PATH or set RCSSSERVER" in run_error(capsys, ["pitch", "dribbler"])


@pytest.mark.skipif(
    find_server() is None, reason="no rcssserver binary: set RCSSSERVER or put rcssserver on PATH (docs/pitch.md)"
)
def test_pitch_prints_both_sides_and_writes_the_episodes(tmp_path: Path, capsys) -> None:
    out = tmp_path / "pitch.csv"
    assert main(["pitch", "dribbler", "--episodes", "12", "--world-seed", "4", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "real server" in printed and "env" in printed and "Welch t =" in printed
    with open(out, newline="") as file:
        rows = list(csv.DictReader(file))
    assert len(rows) == 12 and {int(row["type_id"]) for row in rows} <= set(range(18))
    assert all(float(row["real_distance"]) > 5 for row in rows)
