"""Every deterministic case recorded from a real rcssserver 19.0.0 replays within the print precision: the dribbling
cases and the cases at the goals (goal posts, tackles and their frozen cycles, kicks over the goal line)."""

from __future__ import annotations

import json

import pytest

from robocup_dribble import physics, validate
from robocup_dribble.params import make_profile
from tests.conftest import golden_file

CASES = list(validate.read_cases(golden_file("rcss-deterministic.jsonl")))
GOAL_CASES = list(validate.read_cases(golden_file("rcss-goal.jsonl")))


def test_the_recording_has_all_groups():
    groups = {case["group"] for case in CASES}
    assert groups == {"dash", "kick", "ball", "collision", "dribble", "player_type", "dash_negative_power"}
    assert len(CASES) == 67


@pytest.mark.parametrize("case", CASES, ids=[case["id"] for case in CASES])
def test_case_replays_within_tolerance(case):
    result = validate.replay_case(case)
    assert result.passed, result


def test_the_goal_recording_has_all_groups():
    groups = {case["group"] for case in GOAL_CASES}
    assert groups == {"post", "player_post", "tackle", "goal"}
    assert len(GOAL_CASES) == 22


@pytest.mark.parametrize("case", GOAL_CASES, ids=[case["id"] for case in GOAL_CASES])
def test_goal_case_replays_within_tolerance(case):
    result = validate.replay_case(case)
    assert result.passed, result


def _failing(cases, **changes):
    """The ids of the cases that no longer replay when the recorded profile is changed by ``changes``."""
    return {
        case["id"]
        for case in cases
        if not validate.replay_case(case, profile=make_profile(validate.case_profile(case), **changes)).passed
    }


def test_the_post_cases_hit_the_posts():
    post_cases = {case["id"] for case in GOAL_CASES if case["group"] in ("post", "player_post")}
    assert _failing(GOAL_CASES, goal_width=14.03) == post_cases  # the posts 5 mm further out: every one fails
    assert any("post" in state["collision"] for case in GOAL_CASES for state in case["states"])


def test_the_tackle_cases_see_the_frozen_cycles():
    tackle_cases = {case["id"] for case in GOAL_CASES if case["group"] == "tackle"}
    assert _failing(GOAL_CASES, tackle_cycles=9) == tackle_cases
    assert _failing(GOAL_CASES, tackle_cycles=11) == tackle_cases


def test_the_goal_cases_cross_the_goal_line():
    for case in GOAL_CASES:
        if case["group"] == "goal":
            assert abs(case["states"][-1]["ball"]["x"]) > 52.5, case["id"]


def test_cli_passes_on_the_recordings(capsys):
    files = ("rcss-deterministic.jsonl", "rcss-goal.jsonl", "rcss-noise.jsonl")
    assert validate.main([str(golden_file(name)) for name in files]) == 0
    assert "89 passed, 0 failed, 10 skipped" in capsys.readouterr().out


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


def test_parse_command_reads_the_tackle_direction_and_rejects_unknown_commands():
    assert validate.parse_command("(tackle -30)") == (physics.CMD_TACKLE, 0.0, -30.0)
    with pytest.raises(ValueError, match="unsupported command"):
        validate.parse_command("(catch 30)")
