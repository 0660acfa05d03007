"""``sb3-aac tune`` and :mod:`sb3_aac.tune`: resumable studies, storages, pruning, Ctrl-C, the report, rl-zoo3's sampler."""

from __future__ import annotations

import ast
import importlib.util
import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

optuna = pytest.importorskip("optuna", reason="sb3-aac tune needs Optuna (pip install 'sb3-aac[tune]')")

from optuna.trial import TrialState  # noqa: E402
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402

from sb3_aac import SarsaAAC  # noqa: E402
from sb3_aac.cli import build_parser, main  # noqa: E402
from sb3_aac.common.algorithms import hyperparameters  # noqa: E402
from sb3_aac.common.envs import ParameterizedTargetEnv  # noqa: E402
from sb3_aac.tune import (  # noqa: E402
    ALGORITHMS,
    SEARCH_SPACES,
    SearchSpace,
    TuneSettings,
    finished_trials,
    greedy_score,
    load_study,
    open_storage,
    run_study,
    search_space,
    train_command,
    zoo_entry,
)

ROOT = Path(__file__).resolve().parents[1]
TOY = "sb3_aac/ParameterizedTarget-v0"
STUDY = f"sarsa_aac-RbfPolicy-{TOY}"
# A tiny study on the toy env: about a second per trial.
TINY = ["tune", "--env", TOY, "--timesteps", "600", "--eval-every", "200", "--eval-episodes", "8", "--n-envs", "4"]


def toy_envs(n_envs: int, seed: int):
    return make_vec_env(ParameterizedTargetEnv, n_envs=n_envs, seed=seed)


def stored_trials(storage: str, study_name: str = STUDY) -> list:
    return optuna.load_study(study_name=study_name, storage=open_storage(storage)).trials


def cli_env() -> dict[str, str]:
    """The environment of a ``python -m sb3_aac.cli`` subprocess that imports this checkout."""
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "envs"), os.environ.get("PYTHONPATH", "")])}


def run_error(capsys, argv: list[str]) -> str:
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err.strip().splitlines()[-1]  # one line (after any warning of a third-party env)


@pytest.mark.parametrize("storage", ["sqlite:///{dir}/study.db", "{dir}/runs/study.log"], ids=["sqlite", "journal"])
def test_study_resumes_from_its_storage(tmp_path: Path, capsys, storage: str) -> None:
    storage = storage.format(dir=tmp_path)
    assert main([*TINY, "--trials", "2", "--storage", storage]) == 0
    first = stored_trials(storage)
    assert [t.state for t in first] == [TrialState.COMPLETE] * 2  # no pruning before the 5 startup trials
    assert "(0 finished trials so far)" in capsys.readouterr().out

    assert main([*TINY, "--trials", "3", "--storage", storage]) == 0
    out = capsys.readouterr().out
    assert "(2 finished trials so far)" in out and "trial 2:" in out and "trial 1:" not in out
    trials = stored_trials(storage)
    assert len(trials) == 3 and all(t.state == TrialState.COMPLETE for t in trials)
    for before, after in zip(first, trials, strict=False):
        assert (before.params, before.value, before.intermediate_values) == (
            after.params,
            after.value,
            after.intermediate_values,
        )
    assert trials[2].params != trials[0].params  # a resumed sampler does not replay the first trials
    assert len(trials[0].intermediate_values) == 3  # 600 steps, an evaluation every 200

    assert main([*TINY, "--trials", "3", "--storage", storage]) == 0  # nothing left to do
    assert len(stored_trials(storage)) == 3


def test_best_settings_are_a_train_line_and_a_zoo_entry(tmp_path: Path, capsys) -> None:
    yaml = pytest.importorskip("yaml")
    storage = f"sqlite:///{tmp_path}/study.db"
    assert main([*TINY, "--trials", "2", "--storage", storage, "--set", "info_keywords=()", "--set", "n_rbf=7"]) == 0
    out = capsys.readouterr().out
    best = max(stored_trials(storage), key=lambda trial: trial.value)
    assert f"trial {best.number}, return {best.value:.4g}" in out
    assert "n_rbf" not in best.params  # fixed by --set, not searched

    lines = out.splitlines()
    command = shlex.split(lines[lines.index("train with it:") + 1])
    assert command[:2] == ["sb3-aac", "train"]
    args = build_parser().parse_args(command[1:])
    assert (args.env, args.policy, args.timesteps, args.n_envs) == (TOY, "RbfPolicy", 600, 4)
    kwargs = hyperparameters(args.set)
    assert kwargs["policy_kwargs"]["n_rbf"] == 7 and kwargs["info_keywords"] == ()
    for name, value in best.params.items():
        got = kwargs["policy_kwargs"][name] if name in kwargs["policy_kwargs"] else kwargs[name]
        assert got == pytest.approx(value, rel=1e-3)

    entry = yaml.safe_load("\n".join(lines[lines.index("or add to hyperparams/sarsa_aac.yml:") + 1 :]))[TOY]
    assert (entry["policy"], entry["n_envs"], entry["n_timesteps"], entry["info_keywords"]) == ("RbfPolicy", 4, 600, [])
    assert entry["learning_rate"] == pytest.approx(best.params["learning_rate"], rel=1e-3)
    assert "n_rbf=7" in entry["policy_kwargs"] and ast.parse(entry["policy_kwargs"], mode="eval")


def test_report_writes_small_floats_as_yaml_floats() -> None:
    yaml = pytest.importorskip("yaml")
    settings = TuneSettings(env_id=TOY, policy="RbfPolicy")
    kwargs = {
        "exploration_final_eps": 1.23456e-5,
        "gamma": 1.0,
        "type_exploration": "boltzmann",
        "policy_kwargs": {"n_rbf": 9},
    }
    entry = yaml.safe_load(zoo_entry(settings, kwargs))[TOY]
    assert entry["exploration_final_eps"] == 1.235e-5 and entry["gamma"] == 1.0 and entry["type_exploration"] == "boltzmann"
    assert "--set exploration_final_eps=1.235e-05 --set gamma=1.0" in train_command(settings, kwargs)


def test_resume_with_other_settings_is_refused(tmp_path: Path, capsys) -> None:
    storage = f"sqlite:///{tmp_path}/study.db"
    assert main([*TINY, "--trials", "1", "--storage", storage]) == 0
    err = run_error(capsys, [*TINY[:-4], "--n-envs", "2", "--eval-episodes", "8", "--trials", "2", "--storage", storage])
    assert "was made with n_envs=4" in err and "another study name" in err
    assert len(stored_trials(storage)) == 1


@pytest.mark.parametrize(
    ("storage", "content", "message"),
    [
        ("sqlite:///{dir}/bad.db", b"this is not a database" * 10, "file is not a database"),
        ("{dir}/bad.log", b"not json\n", "line 1 is not a JSON record"),
        ("{dir}/bad.log", b'{"op_code": 0}\n[1, 2]\n', "line 2 is not an Optuna journal record"),
        ("sqlite:///{dir}/file/study.db", None, "cannot create the folder"),
        ("{dir}/file/study.log", None, "cannot create the folder"),
        ("{dir}", None, "is a directory"),
        ("sqlite:///", None, "is an in-memory database, which keeps nothing"),
        ("sqlite:///:memory:", None, "is an in-memory database, which keeps nothing"),
        ("{dir}/fifo", None, "is not a regular file (a FIFO"),
        ("sqlite:///{dir}/fifo", None, "is not a regular file (a FIFO"),
        ("{dir}/zero.log", None, "is not a regular file (a FIFO"),
        ("postgresql://nobody@127.0.0.1:1/db", None, "SQLAlchemy's driver for postgresql://, is not installed"),
    ],
    ids=[
        *("corrupt-sqlite", "corrupt-journal", "foreign-journal", "unwritable-sqlite", "unwritable-journal", "directory"),
        *("in-memory", "in-memory-named", "fifo-journal", "fifo-sqlite", "journal-linked-to-dev-zero", "postgresql-driver"),
    ],
)
def test_bad_storage_is_one_line_and_left_alone(
    tmp_path: Path, capsys, storage: str, content: bytes | None, message: str
) -> None:
    (tmp_path / "file").write_text("a regular file, so no folder can be made under it")
    os.mkfifo(tmp_path / "fifo")  # opening it to read would wait for a writer forever
    (tmp_path / "zero.log").symlink_to("/dev/zero")  # read without end
    if "postgresql" in storage and importlib.util.find_spec("psycopg") is not None:
        pytest.skip("psycopg, SQLAlchemy's default PostgreSQL driver, is installed here")
    for name in ("bad.db", "bad.log"):
        if content is not None:
            (tmp_path / name).write_bytes(content)
    err = run_error(capsys, [*TINY, "--trials", "1", "--storage", storage.format(dir=tmp_path)])
    assert err.startswith("sb3-aac tune: error: ") and message in err
    if content is not None:
        assert all((tmp_path / name).read_bytes() == content for name in ("bad.db", "bad.log"))


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--trials", "0"], "--trials: must be positive"),
        (["--timesteps", "-5"], "--timesteps: must be in 1 .."),
        (["--eval-episodes", "0"], "--eval-episodes: must be in 1 .."),
        (["--policy", "TabularPolicy"], "invalid choice: 'TabularPolicy'"),
        (["--set", "gamma=3"], "gamma must be in [0, 1], got 3"),
        (["--set", "colour=1"], "unknown --set key 'colour'"),
        (["--objective", "goals"], "objective 'goals' is not a key of the info"),
        (["--env", "NoSuchEnv-v0"], "unknown env id 'NoSuchEnv-v0'"),
    ],
)
def test_bad_arguments_exit_2(tmp_path: Path, capsys, argv: list[str], message: str) -> None:
    with pytest.raises(SystemExit) as info:
        main([*TINY, "--trials", "1", "--storage", f"sqlite:///{tmp_path}/study.db", *argv])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_settings_and_spaces_validate() -> None:
    policies = "'MlpPolicy', 'RbfMlpPolicy', 'RbfPolicy', 'TilePolicy', 'DeepPolicy'"
    with pytest.raises(ValueError, match=f"tunable policies: \\[{policies}\\]"):
        TuneSettings(env_id=TOY, policy="TabularPolicy")
    algorithms = "'hppo', 'mpdqn', 'pdqn', 'sarsa_aac'"
    with pytest.raises(ValueError, match=f"unknown algorithm 'dqn'; tunable algorithms: \\[{algorithms}\\]"):
        search_space("dqn", "MlpPolicy")
    with pytest.raises(ValueError, match="eval_episodes must be >= 1, got 0"):
        TuneSettings(env_id=TOY, policy="RbfPolicy", eval_episodes=0)
    gamma = optuna.distributions.FloatDistribution(0.5, 0.9)
    with pytest.raises(ValueError, match="a name must mean one thing"):
        SearchSpace({"gamma": gamma}, {"gamma": gamma})


@pytest.mark.parametrize("algo", ["pdqn", "mpdqn"])
def test_the_pdqn_spaces_build_models(algo: str) -> None:
    """Random points of P-DQN's and MP-DQN's spaces are valid constructor arguments, and a one-trial study runs."""
    settings = TuneSettings(
        env_id=TOY,
        policy="MlpPolicy",
        algo=algo,
        timesteps=100,
        eval_every=50,
        eval_episodes=2,
        n_envs=2,
        fixed={"learning_starts": 60, "info_keywords": ()},
    )
    study = load_study(optuna.storages.InMemoryStorage(), algo, settings)
    outcome = run_study(study, settings, toy_envs, n_trials=1)
    assert finished_trials(outcome.study) == 1
    model = ALGORITHMS[algo]("MlpPolicy", toy_envs(2, 0), **settings.kwargs(outcome.study.best_params))
    assert model.learning_starts == 60 and model.batch_size == outcome.study.best_params["batch_size"]


@pytest.mark.parametrize("policy", ["MlpPolicy", "RbfMlpPolicy", "RbfPolicy"])
def test_every_space_builds_a_model(policy: str) -> None:
    """Random points of each space are valid SarsaAAC arguments; fixed names are not sampled and win."""
    settings = TuneSettings(env_id=TOY, policy=policy, fixed={"gamma": 0.5, "policy_kwargs": {"rbf_width": 1.5}})
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0))
    for _ in range(3):
        trial = study.ask()
        params = SEARCH_SPACES[("sarsa_aac", policy)].sample(trial, settings.fixed_names())
        assert "gamma" not in params and "rbf_width" not in params
        model = SarsaAAC(policy, toy_envs(2, 0), seed=0, **settings.kwargs(params))
        assert model.gamma == 0.5 and model.policy.rbf_width == 1.5
        model.learn(20)


def test_deep_space_builds_a_model() -> None:
    settings = TuneSettings(env_id=TOY, policy="DeepPolicy", fixed={"gamma": 0.5})
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0))
    for _ in range(3):
        params = SEARCH_SPACES[("sarsa_aac", "DeepPolicy")].sample(study.ask(), settings.fixed_names())
        assert "gamma" not in params and 0 <= params["trace_lambda"] <= 0.95
        model = SarsaAAC("DeepPolicy", toy_envs(2, 0), seed=0, **settings.kwargs(params))
        assert model.gamma == 0.5 and model.policy.kappa == params["kappa"]
        model.learn(20)


def test_tile_space_builds_a_model() -> None:
    settings = TuneSettings(env_id=TOY, policy="TilePolicy", fixed={"gamma": 0.5})
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0))
    for _ in range(3):
        params = SEARCH_SPACES[("sarsa_aac", "TilePolicy")].sample(study.ask(), settings.fixed_names())
        model = SarsaAAC("TilePolicy", toy_envs(2, 0), seed=0, **settings.kwargs(params))
        assert model.gamma == 0.5
        assert (model.policy.tiles_per_input, model.policy.n_tilings) == (params["tiles_per_input"], params["n_tilings"])
        model.learn(20)


def test_greedy_score_plays_the_same_episodes() -> None:
    model = SarsaAAC("RbfPolicy", toy_envs(2, 0), seed=0, policy_kwargs={"n_rbf": 5}).learn(400)
    env = toy_envs(3, 123)
    first = greedy_score(model, env, 7, seed=5)
    assert greedy_score(model, env, 7, seed=5) == first
    assert greedy_score(model, env, 7, seed=6) != first
    # the toy env's info["distance"] is the return so far, so the two objectives agree
    assert greedy_score(model, env, 7, seed=5, objective="distance") == pytest.approx(first)


def test_median_pruner_stops_a_trial_that_falls_behind(tmp_path: Path) -> None:
    settings = TuneSettings(
        env_id=TOY,
        policy="RbfPolicy",
        timesteps=2000,
        eval_every=400,
        eval_episodes=20,
        n_envs=4,
        startup_trials=1,
        warmup_evaluations=1,
    )
    study = load_study(open_storage(f"sqlite:///{tmp_path}/study.db"), "prune", settings)
    learns = {"learning_rate": 0.5, "q_learning_rate": 0.5, "param_learning_rate": 0.5, "n_rbf": 10}
    # the smallest rates of the space: after 2,000 steps the greedy policy is still about the initial one
    barely = {"learning_rate": 0.01, "q_learning_rate": 0.01, "param_learning_rate": 0.01, "n_rbf": 50}
    study.enqueue_trial(learns)
    study.enqueue_trial(barely)
    run_study(study, settings, toy_envs, n_trials=2)
    good, bad = study.trials
    assert good.state == TrialState.COMPLETE and len(good.intermediate_values) == 5
    assert bad.state == TrialState.PRUNED and bad.params["learning_rate"] == 0.01
    last = max(bad.intermediate_values)
    assert 1 <= last < 4  # stopped early: evaluation 0 is warm-up, 4 would be the end of training
    assert bad.intermediate_values[last] < good.intermediate_values[last]


def test_several_seeds_per_trial_score_their_mean(tmp_path: Path) -> None:
    settings = TuneSettings(
        env_id=TOY, policy="RbfPolicy", timesteps=400, eval_every=200, eval_episodes=5, n_envs=2, seeds_per_trial=2
    )
    study = load_study(open_storage(f"sqlite:///{tmp_path}/study.db"), "seeds", settings)
    run_study(study, settings, toy_envs, n_trials=1)
    (trial,) = study.trials
    assert len(trial.user_attrs["scores"]) == 2 and trial.value == pytest.approx(np.mean(trial.user_attrs["scores"]))
    assert sorted(trial.intermediate_values) == [0, 1, 2, 3]  # the second seed's evaluations continue the count


def test_ctrl_c_ends_the_running_trial_and_keeps_the_finished_ones(tmp_path: Path) -> None:
    storage = f"sqlite:///{tmp_path}/study.db"
    argv = [*TINY, "--timesteps", "40000", "--eval-every", "20000", "--trials", "5", "--storage", storage]
    process = subprocess.Popen(
        [sys.executable, "-W", "ignore", "-m", "sb3_aac.cli", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=cli_env(),
    )
    try:
        lines = []
        while not any(line.startswith("trial 0:") for line in lines):  # trial 0 finished, trial 1 is training
            line = process.stdout.readline()
            assert line, f"the study ended early: {lines} {process.stderr.read()}"
            lines.append(line)
        time.sleep(0.2)
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 130 and "Traceback" not in err and "sb3-aac tune: interrupted" in err
    assert "trial 1: interrupted" in out and "run the same command to resume" in out and "best of 1 completed trials" in out
    trials = stored_trials(storage)
    assert [t.state for t in trials] == [TrialState.COMPLETE, TrialState.FAIL]
    assert trials[1].user_attrs["interrupted"] is True and len(trials[1].intermediate_values) < 2


def test_two_processes_share_one_journal_study(tmp_path: Path) -> None:
    storage = str(tmp_path / "shared.log")
    argv = [sys.executable, "-W", "ignore", "-m", "sb3_aac.cli", *TINY, "--trials", "4", "--storage", storage]
    processes = [subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=cli_env()) for _ in range(2)]
    for process in processes:
        _, err = process.communicate(timeout=120)
        assert process.returncode == 0, err
    trials = stored_trials(storage)
    assert 4 <= len(trials) <= 5  # each process stops once the study holds 4; both may be mid-trial then
    assert [t.number for t in trials] == list(range(len(trials))) and all(t.state == TrialState.COMPLETE for t in trials)
