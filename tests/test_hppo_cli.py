"""HybridPPO in the tools: ``sb3-aac train --algo HybridPPO``, ``sb3-aac tune --algo hppo``, rl-zoo3's files and sampler."""

from __future__ import annotations

import ast
import inspect
import json
from pathlib import Path

import pytest

from sb3_aac import HybridPPO
from sb3_aac.cli import main
from tests.test_rl_zoo import ROOT, ZOO_KEYS

TOY = "sb3_aac/ParameterizedTarget-v0"


@pytest.mark.parametrize("algo", ["HybridPPO", "hppo"])
def test_train_algo(tmp_path: Path, capsys, algo: str) -> None:
    assert main(["train", "--algo", algo, "--env", TOY, "--timesteps", "128", "--n-envs", "2", "--eval-episodes", "3",
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


def test_hyperparameters_are_constructor_arguments() -> None:
    yaml = pytest.importorskip("yaml", reason="PyYAML is not installed (rl-zoo3 depends on it)")
    config = yaml.safe_load((ROOT / "hyperparams" / "hppo.yml").read_text())
    assert {"Platform-v0", "RoboCupDribblePaper-v0", "RoboCupDribble-v0", TOY} <= set(config)
    ctor = set(inspect.signature(HybridPPO.__init__).parameters)
    for env_id, params in config.items():
        unknown = set(params) - ZOO_KEYS - ctor
        assert not unknown, f"{env_id}: {unknown} are neither rl-zoo3 keys nor HybridPPO arguments"
        assert params["policy"] in HybridPPO.policy_aliases
        if "policy_kwargs" in params:  # rl-zoo3 eval()s this string
            call = ast.parse(params["policy_kwargs"], mode="eval").body
            assert isinstance(call, ast.Call) and call.func.id == "dict"


def test_rl_zoo3_registers_hppo_and_its_sampler() -> None:
    pytest.importorskip("rl_zoo3", reason="rl-zoo3 is not installed (pip install rl_zoo3)")
    import optuna

    from sb3_aac.common.envs import ParameterizedTargetEnv
    from sb3_aac.tune.zoo import convert_params
    from sb3_aac.zoo import register

    register()
    import rl_zoo3.exp_manager
    import rl_zoo3.train

    assert rl_zoo3.train.ALGOS["hppo"] is HybridPPO
    sample = rl_zoo3.exp_manager.HYPERPARAMS_SAMPLER["hppo"]
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=1))
    for _ in range(3):
        trial = study.ask()
        kwargs = sample(trial, n_actions=0, n_envs=2, additional_args={})
        assert convert_params("hppo", trial.params) == kwargs
        HybridPPO(env=ParameterizedTargetEnv(), seed=0, **{**kwargs, "n_steps": 16, "batch_size": 16}).learn(16)
