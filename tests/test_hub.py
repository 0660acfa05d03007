"""Sharing a model on the Hugging Face Hub (sb3_aac.hub, sb3-aac push), offline: a stand-in for the Hub API records
what would be uploaded."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from huggingface_hub import ModelCard
from torch.nn import GELU

from robocup_dribble import DribbleVecEnv
from sb3_aac import MPDQN, RuntimePolicy, SarsaAAC
from sb3_aac.cli import main, push
from tests.test_cli import run_error


class StandInHub:
    """Records create_repo and upload_folder as huggingface_hub.HfApi would receive them, and keeps the files."""

    def __init__(self) -> None:
        self.repos: list[dict] = []
        self.uploaded: dict[str, bytes] = {}

    def create_repo(self, repo_id: str, repo_type: str, private: bool, exist_ok: bool) -> str:
        self.repos.append(dict(repo_id=repo_id, repo_type=repo_type, private=private, exist_ok=exist_ok))
        return f"https://huggingface.co/{repo_id}"

    def upload_folder(self, repo_id: str, repo_type: str, folder_path: str, allow_patterns: list[str], commit_message: str):
        assert repo_type == "model" and commit_message
        self.uploaded = {name: (Path(folder_path) / name).read_bytes() for name in allow_patterns}


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("models")
    paths = {}
    for name, model in {
        "tile": SarsaAAC("TilePolicy", DribbleVecEnv(2, profile="v11"), seed=0),
        "mpdqn": MPDQN("MlpPolicy", DribbleVecEnv(2, profile="v19"), seed=0, learning_starts=20),
        "mpdqn-gelu": MPDQN(  # a network the format cannot carry
            "MlpPolicy", DribbleVecEnv(2, profile="v19"), seed=0, learning_starts=20, policy_kwargs={"activation_fn": GELU}
        ),
    }.items():
        model.learn(300)
        paths[name] = folder / f"{name}.zip"
        model.save(paths[name])
    return paths


@pytest.fixture
def hub(monkeypatch) -> StandInHub:
    stand_in = StandInHub()
    monkeypatch.setattr(push, "hub_api", lambda: stand_in)
    return stand_in


def test_push_uploads_the_model_its_policy_and_a_card(models, hub, tmp_path, capsys) -> None:
    assert main(["push", str(models["tile"]), "--repo-id", "me/dribble-tile", "--episodes", "20", "--private"]) == 0
    assert hub.repos == [dict(repo_id="me/dribble-tile", repo_type="model", private=True, exist_ok=True)]
    assert set(hub.uploaded) == {"model.zip", "policy.aacp", "results.json", "README.md"}
    assert "uploaded to https://huggingface.co/me/dribble-tile" in capsys.readouterr().out
    card = ModelCard(hub.uploaded["README.md"].decode())
    results = json.loads(hub.uploaded["results.json"])
    assert card.data.library_name == "sb3-aac"
    assert {"reinforcement-learning", "stable-baselines3", "RoboCupDribblePaper-v0", "SarsaAAC"} <= set(card.data.tags)
    metrics = {r.metric_type: r.metric_value for r in card.data.eval_results}
    assert results["env_id"] == "RoboCupDribblePaper-v0" and results["episodes"] == 20
    assert metrics["mean_distance"] == round(results["mean_distance"], 4) and 0 <= metrics["ball_loss_rate"] <= 1
    assert 'SarsaAAC.load(hf_hub_download("me/dribble-tile", "model.zip"))' in card.text
    assert "RuntimePolicy.load" in card.text and "TODO" not in card.text
    # what was uploaded is the model: it loads, and its exported policy decides as it does
    (tmp_path / "model.zip").write_bytes(hub.uploaded["model.zip"])
    (tmp_path / "policy.aacp").write_bytes(hub.uploaded["policy.aacp"])
    model, runtime = SarsaAAC.load(tmp_path / "model.zip"), RuntimePolicy.load(tmp_path / "policy.aacp")
    obs = np.stack([model.observation_space.sample() for _ in range(50)])
    types = np.array([a[0] for a in model.predict(obs, deterministic=True)[0]])
    np.testing.assert_array_equal(types, runtime.act_batch(obs)[0])


def test_push_of_a_model_export_cannot_carry_leaves_the_policy_out(models, hub) -> None:
    assert main(["push", str(models["mpdqn-gelu"]), "--repo-id", "me/mpdqn", "--episodes", "5", "--trust"]) == 0
    assert set(hub.uploaded) == {"model.zip", "results.json", "README.md"}
    card = ModelCard(hub.uploaded["README.md"].decode())
    assert "MPDQN.load" in card.text and "RuntimePolicy" not in card.text
    assert json.loads(hub.uploaded["results.json"])["env_id"] == "RoboCupDribble-v0"
    assert main(["push", str(models["mpdqn"]), "--repo-id", "me/mpdqn", "--episodes", "5"]) == 0
    assert set(hub.uploaded) == {"model.zip", "policy.aacp", "results.json", "README.md"}


def test_dry_run_writes_the_folder_and_uploads_nothing(models, hub, tmp_path, capsys) -> None:
    folder = tmp_path / "hub"
    argv = ["push", str(models["tile"]), "--repo-id", "me/x", "--episodes", "5", "--folder", str(folder), "--dry-run"]
    assert main(argv) == 0
    assert sorted(p.name for p in folder.iterdir()) == ["README.md", "model.zip", "policy.aacp", "results.json"]
    assert hub.repos == [] and hub.uploaded == {}
    assert "already holds" in run_error(capsys, argv)


def test_a_dry_run_needs_no_hub_client_and_its_card_runs_as_written(models, tmp_path, monkeypatch, capsys) -> None:
    """Without huggingface_hub, --dry-run writes the whole folder; the card's install command names the wheel sb3-aac
    really comes from, and its snippets, with hf_hub_download reading that folder, make the env and decide."""
    import types

    folder = tmp_path / "hub"
    monkeypatch.setitem(sys.modules, "huggingface_hub", None)  # makes `import huggingface_hub` fail
    argv = ["push", str(models["tile"]), "--repo-id", "me/x", "--episodes", "3", "--folder", str(folder), "--dry-run"]
    assert main(argv) == 0
    assert sorted(p.name for p in folder.iterdir()) == ["README.md", "model.zip", "policy.aacp", "results.json"]
    card = (folder / "README.md").read_text()
    assert "pip install sb3-aac" not in card and 'pip install "./dist/sb3_aac-' in card
    stand_in = types.ModuleType("huggingface_hub")
    stand_in.hf_hub_download = lambda repo_id, name: str(folder / name)  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "huggingface_hub", stand_in)
    snippets = re.findall(r"```python\n(.*?)```", card, re.DOTALL)
    assert len(snippets) == 2
    for snippet in snippets:
        names: dict = {}
        exec(snippet, names)
        assert "obs" in names and ("action" in names or "action_type" in names)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--repo-id", "no-slash"], "--repo-id must be USER/NAME"),
        (["--repo-id", "a/b", "--dry-run"], "--dry-run writes the files into --folder"),
    ],
)
def test_push_bad_input_is_one_line(models, hub, capsys, argv, message) -> None:
    assert message in run_error(capsys, ["push", str(models["tile"]), *argv])
    assert hub.repos == []


def test_an_upload_failure_is_one_line(models, monkeypatch, capsys) -> None:
    class Offline(StandInHub):
        def create_repo(self, *args, **kwargs):
            raise ConnectionError("no network")

    monkeypatch.setattr(push, "hub_api", Offline)
    assert "cannot upload to me/x: ConnectionError: no network" in run_error(
        capsys, ["push", str(models["tile"]), "--repo-id", "me/x", "--episodes", "3"]
    )


def test_an_endpoint_that_never_answers_times_out(models, monkeypatch, capsys) -> None:
    import socket

    from huggingface_hub import constants

    with socket.socket() as server:  # accepts connections (the kernel's backlog) and never answers
        server.bind(("127.0.0.1", 0))
        server.listen(4)
        monkeypatch.setattr(constants, "ENDPOINT", f"http://127.0.0.1:{server.getsockname()[1]}")
        monkeypatch.setattr(push, "HUB_TIMEOUT_S", 0.5)
        monkeypatch.setenv("HF_TOKEN", "hf_stand_in")
        err = run_error(capsys, ["push", str(models["tile"]), "--repo-id", "me/x", "--episodes", "3"])
    assert "cannot upload to me/x" in err and "Timeout" in err
