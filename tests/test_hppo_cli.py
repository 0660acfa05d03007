"""HybridPPO in the tools: ``sb3-aac train --algo HybridPPO`` (by class name), ``sb3-aac tune --algo HybridPPO`` (train
with --algo hppo and rl-zoo3's flows are tests/test_cli.py's and tests/test_rl_zoo.py's, for every algorithm)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sb3_aac import HybridPPO
from sb3_aac.cli import main

TOY = "sb3_aac/ParameterizedTarget-v0"


def test_train_algo_by_class_name(tmp_path: Path, capsys) -> None:
    assert main(["train", "--algo", "HybridPPO", "--env", TOY, "--timesteps", "128", "--n-envs", "2", "--eval-episodes", "3",
                 "--out", str(tmp_path), "--set", "n_steps=32", "--set", "batch_size=32", "--set", "net_arch=[8]",
                 "--tensorboard", str(tmp_path / "tb")]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "training HybridPPO MlpPolicy" in out and "greedy evaluation over 3 episodes: return" in out
    assert json.loads((tmp_path / "run.json").read_text())["algo"] == "hppo"
    assert list((tmp_path / "tb").glob("HybridPPO_MlpPolicy_1/events.out.tfevents.*"))
    model = HybridPPO.load(tmp_path / "model.zip")
    assert model.n_steps == 32 and model.policy.net_arch == [8]


def test_tune_algo(tmp_path: Path, capsys) -> None:
    pytest.importorskip("optuna", reason="sb3-aac tune needs Optuna")
    storage = str(tmp_path / "study.log")
    argv = ["tune", "--algo", "HybridPPO", "--policy", "MlpPolicy", "--env", TOY, "--timesteps", "256", "--eval-every",
            "128", "--eval-episodes", "4", "--n-envs", "2", "--trials", "2", "--startup-trials", "2", "--set",
            "n_steps=64", "--set", "batch_size=64", "--storage", storage]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "tuning HybridPPO MlpPolicy" in out and "add to hyperparams/hppo.yml" in out
    assert "sb3-aac train --env sb3_aac/ParameterizedTarget-v0 --algo hppo --policy MlpPolicy" in out


def test_train_at_the_lane_limit_is_refused_before_it_runs_out_of_memory(tmp_path: Path, capsys) -> None:
    """On the dribbling env (one vectorised env for all lanes), the default."""
    from tests.test_cli import run_error

    err = run_error(capsys, ["train", "--algo", "hppo", "--n-envs", "65536", "--out", str(tmp_path / "run")])
    assert "rollout buffer (n_steps=2,048 x 65,536 envs) would take" in err and "choose smaller sizes" in err
    assert not (tmp_path / "run" / "model.zip").exists()
