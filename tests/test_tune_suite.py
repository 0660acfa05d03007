"""The multi-task study (:mod:`sb3_aac.tune.suite`) and the benchmark's suite of tasks (``benchmarks/suite.py``)."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import pytest

optuna = pytest.importorskip("optuna", reason="the tuning studies need Optuna (pip install 'sb3-aac[tune]')")

from optuna.trial import FixedTrial, TrialState  # noqa: E402
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402

from sb3_aac.common.envs import ParameterizedTargetEnv  # noqa: E402
from sb3_aac.tune.search_spaces import search_space  # noqa: E402
from sb3_aac.tune.storage import open_storage  # noqa: E402
from sb3_aac.tune.study import load_study, run_trials  # noqa: E402
from sb3_aac.tune.suite import SuiteSettings, SuiteTask, suite_objective  # noqa: E402

# Inside the TilePolicy space: SarsaAAC's defaults (rates 0.1) with small tiles, so that a task trains in a blink.
PARAMS = {
    "learning_rate": 0.1,
    "q_learning_rate": 0.1,
    "param_learning_rate": 0.1,
    "gamma": 0.9,
    "exploration_fraction": 0.5,
    "exploration_initial_eps": 0.3,
    "exploration_final_eps": 0.05,
    "param_noise_initial": 0.3,
    "param_noise_final": 0.05,
    "tiles_per_input": 4,
    "n_tilings": 4,
}


class RecordingTrial(FixedTrial):
    """A trial with fixed parameters that records what the objective reports and asks, in order."""

    def __init__(self, events: list[tuple[Any, ...]], prune_at: int | None = None):
        super().__init__(PARAMS)
        self.events, self.prune_at, self.last_step = events, prune_at, -1

    def report(self, value: float, step: int) -> None:
        self.events.append(("report", step, value))
        self.last_step = step

    def should_prune(self) -> bool:
        self.events.append(("should_prune", self.last_step))
        return self.last_step == self.prune_at


def toy_task(name: str, score: float, floor: float, reference: float, events: list[tuple[Any, ...]]) -> SuiteTask:
    """A task on the toy env (200 steps) whose score is the constant ``score``; records its training and scoring."""

    def make_env(n_envs: int, seed: int):
        events.append(("train", name))
        return make_vec_env(ParameterizedTargetEnv, n_envs=n_envs, seed=seed)

    def score_model(model: Any) -> float:
        events.append(("score", name))
        return score

    return SuiteTask(name, make_env, 2, 200, score_model, floor, reference)


def three_tasks(events: list[tuple[Any, ...]]) -> tuple[SuiteTask, ...]:
    # normalised: (7 - 2) / (12 - 2) = 0.5; (-1 - 0) / (1 - 0) -> 0 (clipped); (30 - 10) / (20 - 10) -> 1 (clipped)
    return (
        toy_task("a", 7.0, 2.0, 12.0, events),
        toy_task("b", -1.0, 0.0, 1.0, events),
        toy_task("c", 30.0, 10.0, 20.0, events),
    )


def test_normalisation_maps_floor_to_0_and_reference_to_1_clipped() -> None:
    task = toy_task("t", 0.0, 2.0, 12.0, [])
    assert [task.normalised(s) for s in (2.0, 12.0, 7.0, 4.5, 0.0, 15.0)] == [0.0, 1.0, 0.5, 0.25, 0.0, 1.0]
    assert toy_task("n", 0.0, -1.3, 1.7, []).normalised(0.2) == pytest.approx(0.5)


@pytest.mark.parametrize(("floor", "reference"), [(1.0, 1.0), (2.0, 1.0), (0.0, float("nan")), (float("-inf"), 1.0)])
def test_a_reference_not_above_the_floor_is_refused(floor: float, reference: float) -> None:
    with pytest.raises(ValueError, match="reference must be finite and above the floor"):
        toy_task("t", 0.0, floor, reference, [])


def test_suite_settings_validate() -> None:
    with pytest.raises(ValueError, match="distinct task names"):
        SuiteSettings("s", (toy_task("a", 0, 0, 1, []), toy_task("a", 0, 0, 1, [])), "TilePolicy")
    with pytest.raises(ValueError, match="at least one task"):
        SuiteSettings("s", (), "TilePolicy")
    with pytest.raises(ValueError, match="tunable policies"):
        SuiteSettings("s", (toy_task("a", 0, 0, 1, []),), "TabularPolicy")


def test_objective_is_the_mean_normalised_score_reported_after_each_task() -> None:
    events: list[tuple[Any, ...]] = []
    trial = RecordingTrial(events)
    value = suite_objective(SuiteSettings("s", three_tasks(events), "TilePolicy"))(trial, threading.Event())
    assert value == pytest.approx((0.5 + 0.0 + 1.0) / 3)
    assert events == [
        ("train", "a"),
        ("score", "a"),
        ("report", 0, 0.5),
        ("should_prune", 0),
        ("train", "b"),
        ("score", "b"),
        ("report", 1, 0.25),
        ("should_prune", 1),
        ("train", "c"),
        ("score", "c"),
        ("report", 2, pytest.approx(0.5)),
        ("should_prune", 2),
    ]
    assert trial.user_attrs == {"scores": {"a": 7.0, "b": -1.0, "c": 30.0}, "normalised": {"a": 0.5, "b": 0.0, "c": 1.0}}


def test_a_pruned_trial_trains_no_further_task() -> None:
    events: list[tuple[Any, ...]] = []
    with pytest.raises(optuna.TrialPruned, match="after task 'b'"):
        suite_objective(SuiteSettings("s", three_tasks(events), "TilePolicy"))(RecordingTrial(events, 1), threading.Event())
    assert ("train", "c") not in events and events[-1] == ("should_prune", 1)


def test_a_study_of_a_suite_keeps_each_tasks_scores_and_prunes_a_diverged_trial(tmp_path: Path) -> None:
    events: list[tuple[Any, ...]] = []
    fixed = {name: value for name, value in PARAMS.items() if name not in ("tiles_per_input", "n_tilings")}
    fixed["policy_kwargs"] = {"n_tilings": 4}
    settings = SuiteSettings("s", three_tasks(events), "TilePolicy", fixed=fixed, startup_trials=1)
    storage = open_storage(str(tmp_path / "suite.journal"))
    study = load_study(storage, "suite", settings)
    outcome = run_trials(study, suite_objective(settings), 2)
    assert [t.state for t in study.trials] == [TrialState.COMPLETE] * 2
    assert {t.params["tiles_per_input"] for t in study.trials} <= set(range(4, 17))
    assert set(study.trials[0].params) == {"tiles_per_input"}  # the fixed ones are not searched
    assert study.trials[0].user_attrs["normalised"] == {"a": 0.5, "b": 0.0, "c": 1.0}
    assert not outcome.interrupted

    def diverges(trial: optuna.Trial, stop: threading.Event) -> float:
        raise FloatingPointError("non-finite weights in V")

    run_trials(study, diverges, 3)
    assert study.trials[-1].state == TrialState.PRUNED and study.trials[-1].user_attrs["diverged"] == "non-finite weights in V"
    with pytest.raises(ValueError, match="was made with"):  # another suite definition is refused on resume
        load_study(storage, "suite", SuiteSettings("s", three_tasks(events)[:2], "TilePolicy", fixed=fixed))


def test_search_space_sample_stays_the_tile_space() -> None:
    assert set(PARAMS) == set(search_space("sarsa_aac", "TilePolicy").sample(FixedTrial(PARAMS)))


def test_bad_suite_name_is_a_clear_error(capsys) -> None:
    from benchmarks.suite import main, suite

    with pytest.raises(ValueError, match=r"unknown suite 'nope'; the suites are \['defaults', 'smoke'\]"):
        suite("nope")
    with pytest.raises(SystemExit) as info:
        main(["tune", "--suite", "nope", "--trials", "1"])
    assert info.value.code == 2
    assert "unknown suite 'nope'; the suites are ['defaults', 'smoke']" in capsys.readouterr().err


def evaluation(settings: str, scores: dict[str, list[float]]) -> dict[str, Any]:
    tasks = {name: {"scores": s, "seeds": [0, 1, 2], "floor": 0.0, "reference": 10.0} for name, s in scores.items()}
    return {"settings": settings, "kwargs": {}, "episodes": 1000, "episode_set": 20000, "tasks": tasks}


def test_compare_wins_only_without_a_significantly_worse_task() -> None:
    from benchmarks.suite import compare_text
    from sb3_aac.common.statistics import welch_test

    defaults = evaluation("defaults", {"x": [5.0, 5.2, 4.8], "y": [8.0, 8.1, 7.9]})
    better = evaluation("tuned", {"x": [7.0, 7.2, 6.8], "y": [8.0, 8.2, 7.8]})
    text = compare_text(defaults, better)
    t, p = welch_test([7.0, 7.2, 6.8], [5.0, 5.2, 4.8])
    assert f"{t:7.2f} {p:7.3g}" in text.splitlines()[4]
    assert "mean normalised score over the compared tasks: A 0.6500, B 0.7500" in text and text.endswith(
        "verdict: B wins across the suite"
    )

    trade = evaluation("tuned", {"x": [9.0, 9.2, 8.8], "y": [7.0, 7.1, 6.9]})  # higher mean, but y is worse
    text = compare_text(defaults, trade)
    assert "A 0.6500, B 0.8000" in text and text.endswith("does not win across the suite (significantly worse on y)")


def test_smoke_suite_runs_from_the_command_line(tmp_path: Path, capsys) -> None:
    from benchmarks.suite import main

    main(["tune", "--suite", "smoke", "--trials", "2", "--storage", str(tmp_path / "s.journal")])
    out = capsys.readouterr().out
    assert "suite 'smoke': toy 2000 steps x 4 lanes" in out and "trial 1:" in out and "evaluate it: --set" in out
    study = optuna.load_study(study_name="suite-smoke-sarsa_aac-TilePolicy", storage=open_storage(str(tmp_path / "s.journal")))
    assert [t.state for t in study.trials] == [TrialState.COMPLETE] * 2
    assert set(study.trials[0].user_attrs["normalised"]) == {"toy"}


def test_an_evaluation_is_its_run_files_and_they_must_agree(tmp_path: Path) -> None:
    import json

    from benchmarks.suite import load_evaluation

    header = {"suite": "smoke", "settings": "defaults", "kwargs": {}, "episodes": 1000, "episode_set": 20000}
    for seed, score in ((1, 2.0), (0, 1.0)):
        run = {"task": "toy", "seed": seed, "score": score, "floor": 0.0, "reference": 4.0}
        (tmp_path / f"toy-s{seed}.json").write_text(json.dumps({**header, **run, "train_seconds": 1.0}))
    loaded = load_evaluation(str(tmp_path))
    assert loaded["settings"] == "defaults"
    assert loaded["tasks"] == {"toy": {"scores": [1.0, 2.0], "seeds": [0, 1], "floor": 0.0, "reference": 4.0}}
    (tmp_path / "toy-s2.json").write_text(json.dumps({**header, **run, "seed": 2, "settings": "--set"}))
    with pytest.raises(SystemExit, match="is another evaluation"):
        load_evaluation(str(tmp_path))


def test_the_defaults_are_a_point_of_the_search_space() -> None:
    from benchmarks.suite import default_params

    assert default_params("TilePolicy") == {**PARAMS, "tiles_per_input": 8, "n_tilings": 8}
    space = search_space("sarsa_aac", "RbfPolicy")
    assert default_params("RbfPolicy") == space.sample(FixedTrial(default_params("RbfPolicy")))  # inside the ranges


def test_evaluate_writes_a_file_per_task_keeps_it_on_rerun_and_compares(tmp_path: Path, capsys) -> None:
    from benchmarks.suite import main

    main(["evaluate", "--suite", "smoke", "--seeds", "2", "--out", str(tmp_path / "a")])
    written = (tmp_path / "a" / "toy-s1.json").stat().st_mtime_ns
    main(["evaluate", "--suite", "smoke", "--seeds", "1", "--first-seed", "1", "--out", str(tmp_path / "a")])  # kept
    assert (tmp_path / "a" / "toy-s1.json").stat().st_mtime_ns == written
    main(["evaluate", "--suite", "smoke", "--seeds", "2", "--set", "gamma=0.5", "--out", str(tmp_path / "b")])
    capsys.readouterr()
    main(["compare", str(tmp_path / "a"), str(tmp_path / "b")])
    out = capsys.readouterr().out
    assert "B: --set {'gamma': '0.5'}" in out and "\ntoy " in out and "verdict: B" in out
    with pytest.raises(SystemExit, match="holds another evaluation"):
        main(["evaluate", "--suite", "smoke", "--seeds", "1", "--set", "gamma=0.6", "--out", str(tmp_path / "a")])
    with pytest.raises(SystemExit, match=r"unknown tasks \['paper'\]"):
        main(["evaluate", "--suite", "smoke", "--tasks", "paper", "--out", str(tmp_path / "c")])


def test_compare_leaves_out_a_task_with_fewer_than_2_runs_on_a_side() -> None:
    from benchmarks.suite import compare_text

    defaults = evaluation("defaults", {"x": [5.0, 5.2, 4.8], "y": [8.0, 8.1, 7.9]})
    partial = evaluation("tuned", {"x": [7.0, 7.2, 6.8], "y": [9.0]})
    text = compare_text(defaults, partial)
    assert "not compared (fewer than 2 runs on a side): y (3 | 1 runs)" in text and "\ny " not in text
    assert "A 0.5000, B 0.7000" in text
