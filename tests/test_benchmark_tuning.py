"""The benchmark's tuning stage (benchmarks/tuning.py), tuned configs (benchmarks/tuned.py), the equal wall-clock
budget (benchmarks/evaluation.py's TrainingTimeLimit) and the report's sections on them (benchmarks/report_budgets.py)."""

from __future__ import annotations

import glob
import json
import multiprocessing
import os
import pwd
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import optuna
import pytest
import yaml
from optuna.storages import JournalStorage
from optuna.storages.journal import JournalFileBackend
from optuna.trial import TrialState

from benchmarks import run as bench_run
from benchmarks.presets import QUICK, Cell
from benchmarks.report import build_report
from benchmarks.tuned import TUNED_DIR_VAR, resolve_tuned, sample_kwargs, tuned_cell
from benchmarks.tuning import TUNE_EVAL_SEED, TUNE_SEED, open_study, plan_studies, run_trial, run_tuning
from sb3_aac.tune.storage import open_storage
from sb3_aac.tune.study import FINISHED
from tests.test_benchmarks import synthetic_cell

REPO = Path(__file__).resolve().parents[1]
ENV_ID = "RoboCupDribblePaper-v0"
QUIET = optuna.logging.WARNING


@pytest.fixture(autouse=True)
def quiet_optuna():
    level = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(QUIET)
    yield
    optuna.logging.set_verbosity(level)


def free_port() -> int:
    with socket.socket() as probe:  # bound, then released: nobody listens there
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def journal_trials(path: Path, study_name: str) -> list[optuna.trial.FrozenTrial]:
    storage = JournalStorage(JournalFileBackend(str(path)))
    return optuna.load_study(study_name=study_name, storage=storage).get_trials(deepcopy=False)


# ---------------------------------------------------------------------------------------------------------------------
# The stage: plan, resume after a kill, a PostgreSQL study shared by two workers
# ---------------------------------------------------------------------------------------------------------------------


def test_the_plan_gives_every_learner_a_study_of_the_same_size():
    studies = plan_studies("full")
    # SarsaAAC's TilePolicy and DeepPolicy on every env but HFO, HybridPPO wherever it runs and PPO wherever it runs
    # but HFO, MP-DQN on the paper env, Platform, Goal and CatchPoint, P-DQN on Platform, Goal and CatchPoint, TD3 on both
    # dribbling envs
    sarsa, on_policy = ("SarsaAAC-tile", "SarsaAAC-deep"), ("HybridPPO", "PPO")
    assert [s.name for s in studies] == [
        *("paper__SarsaAAC-tile", "paper__SarsaAAC-deep", "paper__MPDQN", "paper__TD3", "paper__HybridPPO", "paper__PPO"),
        *(f"v19__{learner}" for learner in (*sarsa, *on_policy, "TD3")),
        *(f"platform__{learner}" for learner in (*sarsa, "MPDQN", "PDQN", *on_policy)),
        *(f"goal__{learner}" for learner in (*sarsa, "HybridPPO", "MPDQN", "PDQN")),
        *(f"catchpoint__{learner}" for learner in (*sarsa, "MPDQN", "PDQN")),
        *(f"moving__{learner}" for learner in (*sarsa, *on_policy)),
        *(f"sliding__{learner}" for learner in (*sarsa, *on_policy)),
        "hfo__HybridPPO",
    ]
    for env_id in {s.env_id for s in studies}:
        sizes = {(s.trials, s.env_steps, s.seeds, s.evaluations, s.eval_episodes) for s in studies if s.env_id == env_id}
        assert len(sizes) == 1 and next(iter(sizes))[0] >= 20
    # a trial trains on the env's tune_steps
    assert {s.name: s.env_steps for s in plan_studies("full", 3, "paper__*")} == dict.fromkeys(
        ("paper__SarsaAAC-tile", "paper__SarsaAAC-deep", "paper__MPDQN", "paper__TD3", "paper__HybridPPO", "paper__PPO"),
        20_000,
    )
    assert TUNE_SEED > 9 and TUNE_EVAL_SEED not in (10_000, 20_000, 30_000)  # none of the grid's seeds or sets


TUNE_COMMAND = ["-m", "benchmarks.run", "--tune", "--preset", "quick", "--only", "SarsaAAC", "--trials", "3", "--workers", "1"]


def test_the_tuning_stage_resumes_after_a_kill_and_keeps_every_finished_trial(tmp_path):
    """2 learners x 3 trials; the first run is killed with SIGKILL after two finished trials, mid-trial."""
    command = [sys.executable, *TUNE_COMMAND, "--tuned-dir", str(tmp_path)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), str(REPO / "envs")])}
    journals = {
        "paper__SarsaAAC-tile": tmp_path / ENV_ID / "SarsaAAC-tile.journal",
        "paper__SarsaAAC-mlp2": tmp_path / ENV_ID / "SarsaAAC-mlp2.journal",
    }

    def finished() -> dict[tuple[str, int], tuple[float | None, dict]]:
        done = {}
        for name, path in journals.items():
            if path.exists() and path.stat().st_size:
                for t in journal_trials(path, name):
                    if t.state in FINISHED:
                        done[(name, t.number)] = (t.value, t.params)
        return done

    process = subprocess.Popen(command, cwd=REPO, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 300
    try:
        while len(finished()) < 2:
            assert process.poll() is None, process.stderr.read().decode() if process.stderr else ""
            assert time.monotonic() < deadline, "no two trials finished in 300 s"
            time.sleep(0.2)
        assert process.poll() is None  # killed mid-study
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    before = finished()
    assert 2 <= len(before) < 6

    rerun = subprocess.run(command, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    after = finished()
    assert len(after) == 6 and all(after[key] == value for key, value in before.items())  # kept, not rerun
    for name, path in journals.items():
        trials = journal_trials(path, name)
        assert not [t for t in trials if t.state == TrialState.RUNNING]
        assert all(t.user_attrs.get("abandoned") for t in trials if t.state == TrialState.FAIL)  # the killed trial
        tuned = yaml.safe_load(path.with_suffix(".yml").read_text())
        best = max((t for t in trials if t.state == TrialState.COMPLETE), key=lambda t: t.value)
        assert tuned["params"] == best.params and tuned["budget"]["trials"] == 3


def _postgres_binary(name: str) -> str | None:
    candidates = [shutil.which(name), *sorted(glob.glob(f"/usr/lib/postgresql/*/bin/{name}"), reverse=True)]
    return next((c for c in candidates if c), None)


@pytest.fixture(scope="module")
def postgres_url():
    """A real PostgreSQL server on a free port of 127.0.0.1, in a temporary directory, for this module's tests."""
    pg_ctl, initdb = _postgres_binary("pg_ctl"), _postgres_binary("initdb")
    if pg_ctl is None or initdb is None:
        pytest.skip("PostgreSQL's server binaries (initdb, pg_ctl) are not installed: apt-get install -y postgresql")
    pytest.importorskip("psycopg2")
    data = tempfile.mkdtemp(prefix="sb3-aac-postgres-")
    as_postgres: list[str] = []
    if os.geteuid() == 0:  # the server refuses to run as root
        user = pwd.getpwnam("postgres")
        os.chown(data, user.pw_uid, user.pw_gid)
        as_postgres = ["runuser", "-u", "postgres", "--"]
    port = free_port()
    try:
        subprocess.run([*as_postgres, initdb, "-D", data, "-U", "postgres", "--auth=trust"], check=True, capture_output=True)
        options = f"-p {port} -h 127.0.0.1 -k {data} -c fsync=off"
        subprocess.run(
            [*as_postgres, pg_ctl, "-D", data, "-o", options, "-l", f"{data}/log", "-w", "start"],
            check=True,
            capture_output=True,
            timeout=60,
        )
        yield f"postgresql+psycopg2://postgres@127.0.0.1:{port}/postgres"
    finally:
        subprocess.run([*as_postgres, pg_ctl, "-D", data, "-m", "immediate", "-w", "stop"], capture_output=True)
        shutil.rmtree(data, ignore_errors=True)


def _worker(barrier, study: dict, storage: str, trials: int) -> None:
    barrier.wait()  # both workers ask the shared study for trials at the same time
    for _ in range(trials):
        run_trial(study, storage)


def test_a_postgresql_study_is_shared_by_two_workers(postgres_url, tmp_path):
    (study,) = plan_studies("quick", 4, "SarsaAAC-tile")
    open_study(open_storage(postgres_url), study, create=True)  # the tables and the study, once
    context = multiprocessing.get_context("spawn")
    barrier = context.Barrier(2)
    workers = [context.Process(target=_worker, args=(barrier, study.to_dict(), postgres_url, 2)) for _ in range(2)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(240)
        assert worker.exitcode == 0
    trials = optuna.load_study(study_name=study.name, storage=postgres_url).get_trials(states=FINISHED)
    assert len(trials) == 4 and len({t.user_attrs["pid"] for t in trials}) == 2
    assert len({tuple(sorted(t.params.items())) for t in trials}) == 4  # no two workers drew the same settings

    status = run_tuning([study], storage=postgres_url, folder=tmp_path, workers=1, progress=False)  # nothing to run
    assert status == {"done": [study.name], "failed": []}
    journal = tmp_path / ENV_ID / "SarsaAAC-tile.journal"  # the study copied beside its tuned file
    assert sorted(t.value for t in journal_trials(journal, study.name)) == sorted(t.value for t in trials)
    tuned = yaml.safe_load((tmp_path / ENV_ID / "SarsaAAC-tile.yml").read_text())
    assert tuned["params"] == max(trials, key=lambda t: t.value).params


# ---------------------------------------------------------------------------------------------------------------------
# Bad input: clear errors before any work
# ---------------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--trials", "0"], "must be >= 1"),
        (["--only", "no-such-learner"], "matches none of the studies"),
        (["--preset", "no-such-preset"], "invalid choice"),
    ],
)
def test_the_tuning_stage_refuses_bad_arguments(tmp_path, capsys, argv, message):
    with pytest.raises(SystemExit) as info:
        bench_run.main(["--tune", "--preset", "quick", "--tuned-dir", str(tmp_path), *argv])
    assert info.value.code == 2 and message in capsys.readouterr().err
    assert not list(tmp_path.rglob("*.journal"))


@pytest.mark.parametrize(
    ("tuning", "message"),
    [
        ({"learners": [("NoSuchAlgo", "x")]}, "has no search space"),
        ({"learners": [("SarsaAAC", "no-such-config")]}, "has no search space"),
        ({"trials": 0}, "trials must be a whole number >= 1"),
        ({"env_steps": 0}, "env_steps must be a whole number >= 1"),
        ({"seeds": 0}, "seeds must be a whole number >= 1"),
    ],
)
def test_a_bad_tuning_budget_or_learner_is_refused(tuning, message):
    preset = {**QUICK, "tuning": {**QUICK["tuning"], **tuning}}
    with pytest.raises(ValueError, match=message):
        plan_studies(preset)


def _refused(tmp_path, capsys, storage: str) -> str:
    start = time.monotonic()
    code = bench_run.main([*TUNE_COMMAND[2:], "--storage", storage, "--tuned-dir", str(tmp_path / "tuned")])
    assert code == 2 and time.monotonic() - start < 30
    return capsys.readouterr().err


def test_a_corrupt_journal_is_refused_before_any_trial(tmp_path, capsys):
    journal = tmp_path / "study.journal"
    journal.write_text('{"op_code": 0}\nnot a journal record\n')
    assert "cannot read" in _refused(tmp_path, capsys, str(journal))
    assert journal.read_text() == '{"op_code": 0}\nnot a journal record\n'  # untouched


def test_an_unwritable_storage_is_refused(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    assert "cannot create the folder" in _refused(tmp_path, capsys, str(tmp_path / "file" / "study.journal"))


def test_an_unreachable_database_is_refused_at_once(tmp_path, capsys):
    pytest.importorskip("psycopg2")
    err = _refused(tmp_path, capsys, f"postgresql+psycopg2://nobody@127.0.0.1:{free_port()}/studies")
    assert "cannot open the study database" in err


def test_an_unwritable_tuned_folder_is_refused(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    with pytest.raises(SystemExit) as info:
        bench_run.main([*TUNE_COMMAND[2:], "--tuned-dir", str(tmp_path / "file")])
    assert info.value.code == 2 and "--tuned-dir" in capsys.readouterr().err


def test_a_study_is_not_resumed_with_another_definition(tmp_path):
    (study,) = plan_studies("quick", 3, "SarsaAAC-tile")
    storage = open_storage(str(tmp_path / "study.journal"))
    open_study(storage, study, create=True)
    with pytest.raises(ValueError, match="was made with env_steps=5000"):
        open_study(storage, replace(study, env_steps=6000))
    open_study(storage, replace(study, trials=5))  # more trials for the same study: allowed


def test_the_grid_refuses_tuned_cells_without_tuned_settings(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv(TUNED_DIR_VAR, raising=False)
    argv = ["--preset", "full", "--only", "paper__TD3-td3-tuned__s0", "--out", str(tmp_path / "out")]
    with pytest.raises(SystemExit) as info:
        bench_run.main([*argv, "--tuned-dir", str(tmp_path / "empty")])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "no tuned settings" in err and "TD3.yml" in err and not (tmp_path / "out" / "cells").exists()


# ---------------------------------------------------------------------------------------------------------------------
# Tuned configs: rl-zoo3's samplers through the wrappers, replayed from the tuned file
# ---------------------------------------------------------------------------------------------------------------------


def write_tuned_file(folder: Path, env_id: str, learner: str, params: dict) -> None:
    (folder / env_id).mkdir(parents=True, exist_ok=True)
    record = {"study": "s", "budget": {"trials": 20, "env_steps": 1000, "seeds": 1}, "best": {"trial": 3, "value": 0.5}}
    (folder / env_id / f"{learner}.yml").write_text(yaml.safe_dump({**record, "params": params}))


@pytest.mark.parametrize(
    ("algo", "config"),
    [
        ("TD3", "td3"),
        ("PPO", "ppo"),
        ("MPDQN", "mpdqn"),
        ("HybridPPO", "hybridppo"),
        ("SarsaAAC", "tile"),
        ("SarsaAAC", "deep"),
    ],
)
def test_a_tuned_cell_builds_its_learner_with_the_best_trials_settings(tmp_path, monkeypatch, algo, config):
    from benchmarks.execution import algo_config
    from benchmarks.models import build_model
    from benchmarks.tuned import learner_name

    trial = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=3)).ask()
    sampled = sample_kwargs(trial, "Platform-v0", algo, config)
    write_tuned_file(tmp_path, "Platform-v0", learner_name(algo, config), trial.params)
    monkeypatch.setenv(TUNED_DIR_VAR, str(tmp_path))
    (cell,) = resolve_tuned([Cell("Platform-v0", algo, f"{config}-tuned", 0, 1000)])
    assert cell.overrides["tuned_params"] == trial.params
    json.dumps(cell.to_dict())  # a cell file can hold it
    rebuilt = tuned_cell(cell).overrides
    assert rebuilt.keys() == sampled.keys() and repr(rebuilt.get("policy_kwargs")) == repr(sampled.get("policy_kwargs"))
    model, _, _ = build_model(cell)
    assert model.learning_rate == sampled["learning_rate"]
    if algo == "TD3":  # rl-zoo3's net sizes, through the flattening wrapper (3 action scores, 3 parameters)
        assert model.policy.net_arch == sampled["policy_kwargs"]["net_arch"]
        assert model.action_space.shape == (6,)
    recorded = algo_config(cell)
    assert recorded["tuned_params"] == trial.params and recorded["tuning"]["best"]["value"] == 0.5
    json.dumps(recorded)


@pytest.mark.parametrize(
    ("content", "error"),
    [
        (b"params: {gamma: [0.9\n", "ParserError"),
        (b"params: !!python/object/apply:os.system ['true']\n", "ConstructorError"),
        (b"params:\x00 {}\n", "ReaderError"),
    ],
    ids=["syntax-error", "python-tag", "nul-bytes"],
)
def test_a_tuned_file_that_is_not_yaml_is_named_before_any_cell_runs(tmp_path, monkeypatch, content, error):
    from benchmarks.tuned import tuned_path

    path = tuned_path("Platform-v0", "MPDQN", "mpdqn", tmp_path)
    path.parent.mkdir(parents=True)
    path.write_bytes(content)
    monkeypatch.setenv(TUNED_DIR_VAR, str(tmp_path))
    with pytest.raises(ValueError, match=f"{re.escape(str(path))} is not a tuned-settings YAML file \\({error}"):
        resolve_tuned([Cell("Platform-v0", "MPDQN", "mpdqn-tuned", 0, 1000)])


# ---------------------------------------------------------------------------------------------------------------------
# The equal wall-clock budget
# ---------------------------------------------------------------------------------------------------------------------


def test_a_wall_clock_cell_stops_at_its_seconds(tmp_path):
    from benchmarks.execution import run_cell

    cell = Cell("Platform-v0", "SarsaAAC", "tile", 0, 10**8, eval_every=10**6, eval_episodes=5, final_episodes=5, seconds=1)
    assert cell.cell_id.endswith("__1s") and "seconds" not in Cell("Platform-v0", "SarsaAAC", "tile").to_dict()
    result = run_cell(cell.to_dict(), str(tmp_path))
    assert result["stopped_by"] == "time" and 0 < result["env_steps"] < 10**8
    assert 1.0 <= result["curve"][-1]["train_s"] < 10.0


# ---------------------------------------------------------------------------------------------------------------------
# The report: tuned and default rows, the wall-clock view, each env-step budget
# ---------------------------------------------------------------------------------------------------------------------


def as_cell(result: dict, **fields) -> dict:
    cell = replace(Cell.from_dict(result["cell"]), **fields)
    return {**result, "cell_id": cell.cell_id, "cell": cell.to_dict()}


def test_the_report_shows_tuned_rows_and_the_wall_clock_view(tmp_path):
    (tmp_path / "cells").mkdir()
    tuning = {
        "study": "paper__MPDQN",
        "budget": {"trials": 20, "env_steps": 50_000, "seeds": 1, "tuning_seeds": [1000], "eval_seed": 40_000},
        "best": {"trial": 7, "value": 19.5},
    }
    results = [synthetic_cell(ENV_ID, "SarsaAAC", "tile", s, 24.0, "Tiles") for s in range(10)]
    results += [synthetic_cell(ENV_ID, "MPDQN", "mpdqn", s, 12.0, "peer") for s in range(10)]
    tuned = [synthetic_cell(ENV_ID, "MPDQN", "mpdqn", s, 20.0, "peer") for s in range(10)]
    results += [as_cell({**r, "algo_config": {**r["algo_config"], "tuning": tuning}}, config="mpdqn-tuned") for r in tuned]
    clock = [synthetic_cell(ENV_ID, "SarsaAAC", "tile", s, 26.0, "Tiles") for s in range(5)]
    clock += [synthetic_cell(ENV_ID, "MPDQN", "mpdqn", s, 16.0, "peer") for s in range(5)]
    results += [as_cell({**r, "stopped_by": "time"}, seconds=120) for r in clock]
    long = [synthetic_cell(ENV_ID, "SarsaAAC", "tile", s, 27.0, "Tiles") for s in range(5)]
    long += [synthetic_cell(ENV_ID, "MPDQN", "mpdqn", s, 26.0 + 0.01 * s, "peer") for s in range(5)]
    results += [as_cell(r, budget=500_000) for r in long]
    for r in results:
        (tmp_path / "cells" / f"{r['cell_id']}.json").write_text(json.dumps(r))
    text = build_report(tmp_path, figures=False).read_text()

    tuned_section = text.split("## Tuned and default settings")[1].split("\n## ")[0]
    row = next(line for line in tuned_section.splitlines() if line.startswith(f"| {ENV_ID} | MPDQN"))
    assert "**tuned better**" in row and "20 trials x 50,000 env steps x 1 seed(s)" in row and "19.5" in row
    assert "MPDQN, tuned" in text  # its own row in the env's tables

    clock_section = text.split("## Equal wall-clock budget")[1].split("\n## ")[0]
    assert "| TilePolicy | 5 | 120 |" in clock_section and "5/5" in clock_section
    assert "at 120 s: **SarsaAAC better**" in clock_section

    summary = text.split("## Summary")[1].split("\n## ")[0]
    assert f"**{ENV_ID}** (168,000 env steps)" in summary and f"**{ENV_ID}** (500,000 env steps)" in summary
    # the best peer at the short budget is the tuned MP-DQN, and the wall-clock runs are in no env-step verdict
    short = summary.split("(500,000 env steps)")[0]
    assert "best parameterized peer, MPDQN, tuned" in short and "26.0" not in short
