"""The rl-zoo3 hyperparameter file and registration of every algorithm (rl-zoo3 itself is optional)."""

from __future__ import annotations

import ast
import importlib.util
import inspect
from pathlib import Path

import pytest

from tests.helpers import ALGO_CLASSES, algos

ROOT = Path(__file__).resolve().parents[1]
ZOO_KEYS = {"n_timesteps", "policy", "n_envs", "normalize", "policy_kwargs", "env_wrapper", "callback", "frame_stack"}
# The envs every hyperparameter file covers, and those some files cover besides (by rl-zoo3 name).
ZOO_ENVS = {"RoboCupDribblePaper-v0"}
MORE_ZOO_ENVS = {
    "sarsa_aac": {"RoboCupDribble-v0"},
    "pdqn": {"Platform-v0", "sb3_aac/ParameterizedTarget-v0"},
    "mpdqn": {"Platform-v0", "sb3_aac/ParameterizedTarget-v0"},
}


@algos(ALGO_CLASSES)
def test_hyperparameters_are_constructor_arguments(case) -> None:
    yaml = pytest.importorskip("yaml", reason="PyYAML is not installed (rl-zoo3 depends on it)")
    config = yaml.safe_load((ROOT / "hyperparams" / f"{case.cli}.yml").read_text())
    assert ZOO_ENVS | MORE_ZOO_ENVS.get(case.cli, set()) <= set(config)
    ctor = set(inspect.signature(case.algo.__init__).parameters)
    for env_id, params in config.items():
        unknown = set(params) - ZOO_KEYS - ctor
        assert not unknown, f"{env_id}: {unknown} are neither rl-zoo3 keys nor {case.algo.__name__} arguments"
        assert params["policy"] in case.algo.policy_aliases
        if "policy_kwargs" in params:  # rl-zoo3 eval()s this string
            call = ast.parse(params["policy_kwargs"], mode="eval").body
            assert isinstance(call, ast.Call) and call.func.id == "dict"


def test_wrapper_registers_every_algorithm() -> None:
    pytest.importorskip("rl_zoo3", reason="rl-zoo3 is not installed (pip install rl_zoo3); the script needs it")
    spec = importlib.util.spec_from_file_location("rl_zoo3_train", ROOT / "examples" / "rl_zoo3_train.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.register()
    import rl_zoo3.train

    for case in ALGO_CLASSES:
        assert rl_zoo3.train.ALGOS[case.cli] is case.algo, case.cli
