"""The rl-zoo3 hyperparameter files of P-DQN / MP-DQN and their registration (rl-zoo3 itself is optional)."""

from __future__ import annotations

import ast
import importlib.util
import inspect

import pytest

from sb3_aac import MPDQN, PDQN
from tests.test_rl_zoo import ROOT, ZOO_KEYS


@pytest.mark.parametrize("name, algo", [("pdqn", PDQN), ("mpdqn", MPDQN)])
def test_hyperparameters_are_constructor_arguments(name, algo) -> None:
    yaml = pytest.importorskip("yaml", reason="PyYAML is not installed (rl-zoo3 depends on it)")
    config = yaml.safe_load((ROOT / "hyperparams" / f"{name}.yml").read_text())
    assert {"Platform-v0", "RoboCupDribblePaper-v0", "sb3_aac/ParameterizedTarget-v0"} <= set(config)
    ctor = set(inspect.signature(algo.__init__).parameters)
    for env_id, params in config.items():
        unknown = set(params) - ZOO_KEYS - ctor
        assert not unknown, f"{env_id}: {unknown} are neither rl-zoo3 keys nor {algo.__name__} arguments"
        assert params["policy"] in algo.policy_aliases
        if "policy_kwargs" in params:  # rl-zoo3 eval()s this string
            call = ast.parse(params["policy_kwargs"], mode="eval").body
            assert isinstance(call, ast.Call) and call.func.id == "dict"


def test_wrapper_registers_the_algorithms() -> None:
    pytest.importorskip("rl_zoo3", reason="rl-zoo3 is not installed (pip install rl_zoo3); the script needs it")
    spec = importlib.util.spec_from_file_location("rl_zoo3_train", ROOT / "examples" / "rl_zoo3_train.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.register()
    import rl_zoo3.train

    assert rl_zoo3.train.ALGOS["pdqn"] is PDQN and rl_zoo3.train.ALGOS["mpdqn"] is MPDQN
