"""Every deterministic case recorded from a real rcssserver 19.0.0 replays within the print precision."""

from __future__ import annotations

import json

import pytest

from robocup_dribble import validate
from tests.conftest import golden_file

CASES = list(validate.read_cases(golden_file("rcss-deterministic.jsonl")))


def test_the_recording_has_all_groups():
    groups = {case["group"] for case in CASES}
    assert groups == {"dash", "kick", "ball", "collision", "dribble", "player_type", "dash_negative_power"}
    assert len(CASES) == 67


@pytest.mark.parametrize("case", CASES, ids=[case["id"] for case in CASES])
def test_case_replays_within_tolerance(case):
    result = validate.replay_case(case)
    assert result.passed, result


def test_cli_passes_on_the_recordings(capsys):
    assert validate.main([str(golden_file("rcss-deterministic.jsonl")), str(golden_file("rcss-noise.jsonl"))]) == 0
    assert "67 passed, 0 failed, 10 skipped" in capsys.readouterr().out


def test_cli_fails_on_an_altered_recording(tmp_path, capsys):
    case = json.loads(json.dumps(CASES[0]))
    case["states"][0]["player"]["x"] += 1e-3  # far beyond 6-digit rounding
    path = tmp_path / "altered.jsonl"
    path.write_text(json.dumps(case) + "\n")
    assert validate.main([str(path)]) == 1
    out = capsys.readouterr().out
    assert "FAIL" in out and "player.x at cycle 1" in out


def test_cli_rejects_missing_and_malformed_files(tmp_path, capsys):
    assert validate.main([str(tmp_path / "nope.jsonl")]) == 2
    bad = tmp_path / "bad.jsonl"
    bad.write_text("{not json\n")
    assert validate.main([str(bad)]) == 2
    assert "bad.jsonl:1: not a JSON record" in capsys.readouterr().err


def test_parse_command_rejects_unknown_commands():
    with pytest.raises(ValueError, match="unsupported command"):
        validate.parse_command("(tackle 100)")
