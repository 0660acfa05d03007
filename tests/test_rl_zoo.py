"""The rl-zoo3 hyperparameter file and wrapper script (rl-zoo3 itself is optional)."""

from __future__ import annotations

import ast
import importlib.util
import inspect
from pathlib import Path

import pytest

from sb3_aac import SarsaAAC

ROOT = Path(__file__).resolve().parents[1]
ZOO_KEYS = {"n_timesteps", "policy", "n_envs", "normalize", "policy_kwargs", "env_wrapper", "callback", "frame_stack"}


def test_hyperparameters_are_sarsa_aac_arguments() -> None:
    yaml = pytest.importorskip("yaml", reason="PyYAML is not installed (rl-zoo3 depends on it)")
    config = yaml.safe_load((ROOT / "hyperparams" / "sarsa_aac.yml").read_text())
    assert {"RoboCupDribble-v0", "RoboCupDribblePaper-v0"} <= set(config)
    ctor = set(inspect.signature(SarsaAAC.__init__).parameters)
    for env_id, params in config.items():
        unknown = set(params) - ZOO_KEYS - ctor
        assert not unknown, f"{env_id}: {unknown} are neither rl-zoo3 keys nor SarsaAAC arguments"
        assert params["policy"] in SarsaAAC.policy_aliases
        if "policy_kwargs" in params:  # rl-zoo3 eval()s this string
            call = ast.parse(params["policy_kwargs"], mode="eval").body
            assert isinstance(call, ast.Call) and call.func.id == "dict"


def test_wrapper_registers_the_algorithm() -> None:
    pytest.importorskip("rl_zoo3", reason="rl-zoo3 is not installed (pip install rl_zoo3); the script needs it")
    spec = importlib.util.spec_from_file_location("rl_zoo3_train", ROOT / "examples" / "rl_zoo3_train.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.register()
    import rl_zoo3.train

    assert rl_zoo3.train.ALGOS["sarsa_aac"] is SarsaAAC
