"""``sb3-aac train --algo pdqn|mpdqn``'s own options (in-process, tiny budgets); what every algorithm's training does
alike is in test_cli.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from sb3_aac.cli import main
from tests.test_cli import run_error


@pytest.mark.parametrize("algo", ["pdqn", "mpdqn"])
def test_set_reaches_the_algorithm_and_the_policy(tmp_path: Path, algo: str) -> None:
    assert main(["train", "--algo", algo, "--env", "sb3_aac/ParameterizedTarget-v0", "--timesteps", "200", "--n-envs", "2",
                 "--eval-episodes", "0", "--out", str(tmp_path),
                 "--set", "learning_starts=100", "--set", "net_arch=[8]"]) == 0  # fmt: skip
    import sb3_aac

    model = getattr(sb3_aac, {"pdqn": "PDQN", "mpdqn": "MPDQN"}[algo]).load(tmp_path / "model.zip")
    assert model.learning_starts == 100 and model.policy.net_arch == [8]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["train", "--algo", "pdqn", "--policy", "RbfPolicy", "--timesteps", "10"], "has one policy, MlpPolicy"),
        (["train", "--algo", "mpdqn", "--set", "n_rbf=3"], "valid keys: .*actor_learning_rate"),
        (["train", "--algo", "dqn"], "invalid choice"),
    ],
)
def test_errors(capsys, argv: list[str], message: str) -> None:
    import re

    assert re.search(message, run_error(capsys, argv))


@pytest.mark.parametrize("algo", ["PDQN", "MPDQN"])
def test_export_of_a_pdqn_model(tmp_path, capsys, algo: str) -> None:
    """``sb3-aac export`` writes P-DQN / MP-DQN models (format version 4) that decide as predict, exit 0; a model the
    format cannot carry (a GELU network) is one line and exit 2, writing nothing."""
    import numpy as np
    import torch as th

    import sb3_aac
    from robocup_dribble import DribbleVecEnv
    from sb3_aac import RuntimePolicy

    model = getattr(sb3_aac, algo)("MlpPolicy", DribbleVecEnv(2, profile="v19"), seed=0, learning_starts=20)
    model.learn(40)
    model.save(tmp_path / "model.zip")
    assert main(["export", str(tmp_path / "model.zip"), str(tmp_path / "policy.aacp")]) == 0
    assert "wrote" in capsys.readouterr().out
    runtime = RuntimePolicy.load(tmp_path / "policy.aacp")
    assert runtime.header["version"] == 4 and runtime.header["metadata"]["env_id"] == "RoboCupDribble-v0"
    obs = np.random.default_rng(0).uniform(-1, 1, (200, *model.observation_space.shape)).astype(np.float32)
    types = [a[0] for a in model.predict(obs, deterministic=True)[0]]
    np.testing.assert_array_equal(runtime.act_batch(obs)[0], types)

    gelu = getattr(sb3_aac, algo)("MlpPolicy", DribbleVecEnv(2, profile="v19"), policy_kwargs={"activation_fn": th.nn.GELU})
    gelu.save(tmp_path / "gelu.zip")
    with pytest.raises(SystemExit) as info:
        main(["export", str(tmp_path / "gelu.zip"), str(tmp_path / "gelu.aacp"), "--trust"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "cannot export" in err and "GELU" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "gelu.aacp").exists()
