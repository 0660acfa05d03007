"""The cost estimate of a preset (benchmarks/cost.py, ``python -m benchmarks.run --estimate``): a cell's and a trial's
seconds against hand-computed figures, and the printed table's stages and totals."""

from __future__ import annotations

import pytest

from benchmarks import cost, presets
from benchmarks import run as bench_run
from benchmarks.presets import Cell, build_cells
from benchmarks.tuning import plan_studies


@pytest.fixture
def round_tables(monkeypatch):
    """Rates and costs with round numbers, so the figures below can be computed by hand."""
    monkeypatch.setitem(presets.STEPS_PER_SECOND, "PPO", 1000)
    monkeypatch.setitem(presets.STEPS_PER_SECOND, "SarsaAAC-deep", 500)
    monkeypatch.setitem(presets.ENV_STEP_SECONDS, "Moving-v0", 1e-3)
    monkeypatch.setitem(cost.EPISODE_STEPS, "Moving-v0", 100)
    monkeypatch.setitem(cost.EVAL_EPISODE_SECONDS, "Moving-v0", 0.01)


def test_a_cells_seconds_are_training_evaluations_and_setup(round_tables):
    # 1 / (1/1000 + 1e-3) = 500 steps/s on Moving
    assert presets.training_rate("Moving-v0", "PPO", "ppo") == pytest.approx(500.0)
    cell = Cell("Moving-v0", "PPO", "ppo", 0, 100_000, eval_every=500, eval_episodes=100, final_episodes=1000)
    # 200 s of training; 100k / 100 = 1,000 episodes: 2 + 2 curve points of 100 episodes and 1,000 final ones at 0.01 s
    assert cost.cell_seconds(cell) == pytest.approx(200 + 14 + cost.CELL_SETUP_SECONDS)
    # a config's own rate wins over its algorithm's; a wall-clock cell trains its seconds and steps at its rate
    clock = Cell("Moving-v0", "SarsaAAC", "deep", 0, 0, eval_every=500, eval_episodes=10, final_episodes=100, seconds=120)
    assert presets.training_rate("Moving-v0", "SarsaAAC", "deep") == pytest.approx(1 / (1 / 500 + 1e-3))
    steps = 120 / (1 / 500 + 1e-3)  # 40,000 steps: 400 episodes, 2.8 curve points of 10 and 100 final episodes
    assert cost.cell_seconds(clock) == pytest.approx(120 + (2 + steps / 100 / 500) * 10 * 0.01 + 1.0 + 2.0)


def test_a_trial_trains_each_tuning_seed_and_evaluates_it(round_tables):
    preset = {
        "envs": {"Moving-v0": {"budget": 10_000, "runs": [("PPO", "ppo", tuple(range(10)))]}},
        "eval_every": 500,
        "eval_episodes": 100,
        "final_episodes": 1000,
        "tuning": {"learners": None, "trials": 4, "seeds": 2, "env_steps": None, "evaluations": 3, "eval_episodes": 50},
    }
    (study,) = plan_studies(preset)
    # per seed: 10k steps at 500/s and (3 pruning + 1 final) x 50 episodes at 0.01 s; then the setup
    assert cost.trial_seconds(study) == pytest.approx(2 * (20 + 2) + cost.CELL_SETUP_SECONDS)
    table = cost.estimate(preset)
    assert table["tuning\tMoving-v0"] == {"runs": 4, "hours": pytest.approx(4 * cost.trial_seconds(study) / 3600)}
    cells = build_cells(preset)
    assert table["grid\tMoving-v0"]["runs"] == len(cells) == 10


def test_the_estimate_of_full_prints_every_stage_and_their_sum(capsys):
    assert bench_run.main(["--preset", "full", "--estimate"]) == 0
    lines = capsys.readouterr().out.splitlines()
    stages = {line.split()[0]: float(line.split()[-1]) for line in lines if "(all)" in line}
    assert set(stages) == set(cost.STAGES)
    total = float(next(line for line in lines if line.startswith("total")).split()[-1])
    assert total == pytest.approx(sum(stages.values()), abs=0.02)
    runs = {line.split()[0]: int(line.split()[-2]) for line in lines if "(all)" in line}
    cells = build_cells("full")
    assert runs["grid"] + runs["long"] + runs["wall-clock"] == len(cells)
    assert runs["wall-clock"] == sum(1 for c in cells if c.seconds)
    assert runs["tuning"] == sum(s.trials for s in plan_studies("full"))


def test_the_estimate_follows_only_and_refuses_a_pattern_that_matches_nothing(capsys):
    assert bench_run.main(["--preset", "full", "--estimate", "--only", "goal__SarsaAAC-tile"]) == 0
    out = capsys.readouterr().out
    assert "Goal-v0" in out and "Moving-v0" not in out and "tuning" in out  # the study goal__SarsaAAC-tile too
    with pytest.raises(SystemExit) as info:
        bench_run.main(["--preset", "full", "--estimate", "--only", "no-such-cell"])
    assert info.value.code == 2 and "matches none of the cells" in capsys.readouterr().err


def test_the_wall_time_on_n_cores_is_the_busiest_core_of_the_longest_first_pool():
    # longest first on 2 cores: 3 | 3, then 2 to each, then the last 2 to the first: 7 s (a perfect split has 6)
    assert cost.busiest_hours([3, 3, 2, 2, 2], 2) * 3600 == pytest.approx(7)
    assert cost.busiest_hours([3, 3, 2, 2, 2], 1) * 3600 == pytest.approx(12)
    assert cost.busiest_hours([3, 3, 2, 2, 2], 100) * 3600 == pytest.approx(3)
    assert cost.busiest_hours([], 4) == 0
    with pytest.raises(ValueError, match="bins must be >= 1"):
        cost.busiest_hours([1.0], 0)


def test_the_estimate_prints_the_wall_time_on_each_count_of_cores(capsys):
    assert bench_run.main(["--preset", "full", "--estimate", "--cores", "1,8,64"]) == 0
    lines = capsys.readouterr().out.splitlines()
    core_hours = float(next(line for line in lines if line.startswith("total")).split()[-1])
    table = lines[lines.index(next(line for line in lines if line.lstrip().startswith("cores"))) + 1 :]
    minutes = {int(line.split()[0]): float(line.split()[-1]) for line in table}
    assert set(minutes) == {1, 8, 64}
    assert minutes[1] == pytest.approx(60 * core_hours, abs=0.6)  # one core runs everything one after the other
    # the pool's bound: sum / N + the longest (minutes printed to 0.1, so each side may be 0.05 off)
    assert minutes[1] / 8 - 0.05 <= minutes[8] < minutes[1] / 8 + minutes[64]
    longest = max(cost.cell_seconds(c) for c in build_cells("full")) / 60
    longest_trial = max(cost.trial_seconds(s) for s in plan_studies("full")) / 60
    assert minutes[64] >= longest + longest_trial - 0.05  # no core count beats the longest cell and trial (printed to 0.1)
