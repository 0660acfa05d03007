"""The sb3-aac command line, in-process through sb3_aac.cli.main on tiny budgets."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from sb3_aac.cli import main
from tests.helpers import algos


def run_error(capsys, argv: list[str]) -> str:
    """Run a failing command: exit status 2, no traceback; returns stderr."""
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("run")
    assert main(["train", "--policy", "RbfPolicy", "--timesteps", "600", "--n-envs", "4", "--seed", "1", "--out", str(out),
                 "--eval-episodes", "20",
                 "--set", "n_rbf=5", "--set", "gamma=0.8", "--set", "type_exploration=boltzmann"]) == 0  # fmt: skip
    return out


def test_train_saves_and_evaluates(trained: Path, capsys) -> None:
    from sb3_aac import RuntimePolicy, SarsaAAC

    model = SarsaAAC.load(trained / "model.zip")
    assert model.gamma == 0.8 and model.type_exploration == "boltzmann" and model.policy.n_rbf == 5
    assert RuntimePolicy.load(trained / "policy.aacp").header["metadata"]["env_id"] == "RoboCupDribblePaper-v0"
    run = json.loads((trained / "run.json").read_text())
    assert run["env_id"] == "RoboCupDribblePaper-v0" and run["policy"] == "RbfPolicy" and run["seed"] == 1


def test_train_episodes_tensorboard_other_env(tmp_path: Path, capsys) -> None:
    assert (
        main(["train", "--episodes", "30", "--n-envs", "2", "--eval-episodes", "10", "--tensorboard", str(tmp_path / "tb")])
        == 0
    )
    out = capsys.readouterr().out
    assert "30 episodes" in out and "mean distance" in out and "share >= 20 m" in out and "ball-loss rate" in out
    assert list((tmp_path / "tb").glob("SarsaAAC_DeepPolicy_1/events.out.tfevents.*"))
    assert main(["train", "--env", "sb3_aac/ParameterizedTarget-v0", "--policy", "MlpPolicy", "--timesteps", "200",
                 "--n-envs", "2", "--eval-episodes", "3", "--progress-bar"]) == 0  # fmt: skip
    assert "greedy evaluation over 3 episodes: return" in capsys.readouterr().out


@algos()
def test_train_every_algorithm(tmp_path: Path, capsys, case) -> None:
    assert main(["train", "--algo", case.cli, "--policy", case.policy, "--env", "sb3_aac/ParameterizedTarget-v0",
                 "--timesteps", "300", "--n-envs", "2", "--eval-episodes", "3", "--out", str(tmp_path),
                 "--set", "gamma=0.8", "--tensorboard", str(tmp_path / "tb"), *case.cli_settings()]) == 0  # fmt: skip
    out = capsys.readouterr().out
    name = case.algo.__name__
    assert f"training {name} {case.policy}" in out and "greedy evaluation over 3 episodes: return" in out
    assert (tmp_path / "policy.aacp").exists()
    run = json.loads((tmp_path / "run.json").read_text())
    assert run["algo"] == case.cli and run["policy"] == case.policy
    assert list((tmp_path / "tb").glob(f"{name}_{case.policy}_1/events.out.tfevents.*"))
    model = case.algo.load(tmp_path / "model.zip")
    assert model.gamma == 0.8 and type(model.policy) is case.algo.policy_aliases[case.policy]


@pytest.mark.parametrize("model", ["model.zip", "policy.aacp", "dir"])
def test_evaluate(trained: Path, model: str, capsys) -> None:
    path = trained if model == "dir" else trained / model
    assert main(["evaluate", str(path), "--episodes", "20", "--seed", "3"]) == 0
    out = capsys.readouterr().out
    assert "RoboCupDribblePaper-v0" in out and "mean distance" in out and "ball-loss rate" in out


def test_zip_and_export_evaluate_alike(trained: Path, capsys) -> None:
    main(["evaluate", str(trained / "model.zip"), "--episodes", "30"])
    from_zip = capsys.readouterr().out.splitlines()[1:]
    main(["evaluate", str(trained / "policy.aacp"), "--episodes", "30"])
    assert capsys.readouterr().out.splitlines()[1:] == from_zip


def test_evaluate_dribbler(capsys) -> None:
    assert main(["evaluate", "dribbler", "--episodes", "10", "--profile", "v11"]) == 0
    assert "RoboCupDribblePaper-v0" in capsys.readouterr().out


def test_reliability_writes_png(trained: Path, tmp_path: Path, capsys) -> None:
    png = tmp_path / "figs" / "rel.png"
    assert main(["reliability", str(trained / "model.zip"), "--players", "200", "--out", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    out = capsys.readouterr().out
    assert "200 fresh players" in out and "reached 20 m" in out


def test_render_gif(trained: Path, tmp_path: Path, capsys) -> None:
    pytest.importorskip("pygame")
    import imageio.v2 as imageio

    gif = tmp_path / "episode.gif"
    assert main(["render", str(trained / "policy.aacp"), "--out", str(gif), "--seed", "2"]) == 0
    frames = imageio.mimread(gif)
    steps = int(capsys.readouterr().out.split(": ")[1].split()[0])
    assert len(frames) == steps + 1 and frames[0].ndim == 3


@pytest.mark.parametrize(
    ("argv", "module", "extra"),
    [
        (["reliability", "MODEL", "--players", "20", "--out", "OUT/rel.png"], "matplotlib", "plots"),
        (["render", "MODEL", "--out", "OUT/e.gif"], "imageio", "render"),
        (["render", "MODEL", "--window"], "pygame", "render"),
        (["push", "MODEL", "--repo-id", "me/x", "--episodes", "3"], "huggingface_hub", "hub"),
        (["train", "--timesteps", "100", "--progress-bar", "--out", "OUT/run"], "tqdm", "progress"),
        (["train", "--timesteps", "100", "--progress-bar"], "rich", "progress"),
    ],
)
def test_a_missing_optional_package_is_named_before_any_work(
    trained: Path, tmp_path: Path, monkeypatch, capsys, argv, module, extra
) -> None:
    """Each command checks the optional packages it needs first: one line naming the extra that holds them, exit 2,
    nothing printed or written."""
    monkeypatch.setitem(sys.modules, module, None)  # makes `import module` fail
    argv = [str(trained / "model.zip") if a == "MODEL" else a.replace("OUT", str(tmp_path)) for a in argv]
    err = run_error(capsys, argv)
    assert f"needs {module}" in err and f"pip install 'sb3-aac[{extra}]'" in err and len(err.splitlines()) == 1
    assert capsys.readouterr().out == "" and list(tmp_path.iterdir()) == []


def test_each_extra_holds_what_its_command_imports() -> None:
    tomllib = pytest.importorskip("tomllib")  # Python 3.11+
    extras = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    for extra, modules in {
        "plots": ["matplotlib"], "render": ["pygame", "imageio"], "hub": ["huggingface_hub"], "progress": ["tqdm", "rich"],
        "tune": ["optuna"],
    }.items():  # fmt: skip
        for module in modules:
            assert any(req.startswith(module) for req in extras[extra]), (extra, module)


def test_train_says_when_the_budget_is_rounded_up_and_the_model_not_kept(capsys) -> None:
    argv = ["train", "--env", "sb3_aac/ParameterizedTarget-v0", "--algo", "hppo", "--timesteps", "100", "--n-envs", "2",
            "--set", "n_steps=16", "--set", "batch_size=16", "--eval-episodes", "2"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "whole rollouts of n_steps x n_envs = 32 steps, so it trains 128 steps for the budget of 100" in out
    assert "trained 128 steps" in out and "no --out: the model is evaluated and then not kept" in out


def test_train_names_its_evaluation_seed_and_evaluate_repeats_it(tmp_path: Path, capsys) -> None:
    argv = ["train", "--policy", "RbfPolicy", "--timesteps", "300", "--n-envs", "2", "--seed", "3", "--set", "n_rbf=4",
            "--out", str(tmp_path), "--eval-episodes", "20"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "note:" not in out  # a step budget SarsaAAC keeps, and --out given
    assert "seed 10003 (never a training seed; sb3-aac evaluate MODEL --seed 10003 repeats it)" in out
    assert main(["evaluate", str(tmp_path / "model.zip"), "--episodes", "20", "--seed", "10003"]) == 0
    figures = [line for line in out.splitlines() if "distance" in line or "rate" in line]
    evaluated = capsys.readouterr().out
    assert figures and all(line in evaluated for line in figures)


def test_export(trained: Path, tmp_path: Path, capsys) -> None:
    from sb3_aac import RuntimePolicy, SarsaAAC

    out = tmp_path / "sub" / "d.aacp"
    assert main(["export", str(trained / "model.zip"), str(out)]) == 0
    runtime, model = RuntimePolicy.load(out), SarsaAAC.load(trained / "model.zip")
    obs = np.zeros(10, np.float32)
    assert runtime.act(obs)[0] == model.predict(obs, deterministic=True)[0][0]
    assert "RuntimePolicy" in capsys.readouterr().out


def test_help(capsys) -> None:
    for argv in (["--help"], ["train", "--help"], ["export", "--help"]):
        with pytest.raises(SystemExit) as info:
            main(argv)
        assert info.value.code == 0
    out = capsys.readouterr().out
    assert "examples:" in out and "--set KEY=VALUE" in out and "docs/export-format.md" in out


def test_module_entry_point() -> None:
    root = Path(__file__).resolve().parents[1]
    env = {"PYTHONPATH": f"{root}:{root / 'envs'}", "PATH": "/usr/bin:/bin"}
    result = subprocess.run([sys.executable, "-m", "sb3_aac.cli", "export", "nothing.zip", "x.aacp"], capture_output=True,
                            text=True, env=env, cwd=root, check=False)  # fmt: skip
    assert result.returncode == 2 and "does not exist" in result.stderr and "Traceback" not in result.stderr


@pytest.mark.parametrize(
    "argv, message",
    [
        (["train", "--timesteps", "0"], "must be in 1 .."),
        (["train", "--episodes", "-3"], "must be in 1 .."),
        (["train", "--timesteps", "10", "--episodes", "10"], "not allowed with"),
        (["train", "--env", "Nope-v0"], "unknown env id 'Nope-v0'"),
        (["train", "--set", "nonsense=1"], "valid keys: .*gamma"),
        (["train", "--set", "seed=1"], "--seed"),
        (["train", "--set", "gamma"], "expected key=value"),
        (["train", "--timesteps", "10", "--set", "gamma=7"], "gamma must be in"),
        (["train", "--policy", "CnnPolicy"], "invalid choice"),
        (["train", "--env", "CartPole-v1", "--timesteps", "10"], "not a parameterized action space"),
        (["train", "--gym-package", "no_such_module_xyz"], "cannot be imported"),
        (["train", "--gym-package", "."], "cannot be imported"),
        (["evaluate", "missing.zip"], "does not exist"),
        (["evaluate", "dribbler", "--episodes", "0"], "must be in 1 .."),
        (["reliability", "dribbler", "--out", "figure.jpg"], "must end with .png"),
        (["render", "dribbler", "--out", "clip.avi"], "must end with .gif or .mp4"),
        (["export", "missing.zip", "out.aacp"], "does not exist"),
        ([], "required: COMMAND"),
    ],
)
def test_errors(capsys, argv: list[str], message: str) -> None:
    import re

    assert re.search(message, run_error(capsys, argv))


def test_train_and_evaluate_on_the_perception_model(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    assert main(["train", "--env", "RoboCupDribble-v0", "--timesteps", "300", "--n-envs", "2", "--perception", "match",
                 "--eval-episodes", "10", "--out", str(out)]) == 0  # fmt: skip
    assert json.loads((out / "run.json").read_text())["perception"] == "match"
    assert main(["evaluate", "dribbler", "--episodes", "10", "--perception", "match"]) == 0
    assert "(perception match)" in capsys.readouterr().out
    assert "is an option of the dribbling envs" in run_error(
        capsys, ["train", "--env", "sb3_aac/ParameterizedTarget-v0", "--policy", "MlpPolicy", "--timesteps", "10",
                 "--perception", "match"],
    )  # fmt: skip


def test_errors_on_files(trained: Path, tmp_path: Path, capsys) -> None:
    (tmp_path / "notes.txt").write_text("hello")
    assert "must be a .zip or .aacp" in run_error(capsys, ["evaluate", str(tmp_path / "notes.txt")])
    (tmp_path / "broken.zip").write_bytes(b"PK\x03\x04 not really")
    assert "broken.zip is not a usable saved model: it is not a zip archive" in run_error(
        capsys, ["evaluate", str(tmp_path / "broken.zip")]
    )
    damaged = bytearray((trained / "policy.aacp").read_bytes())
    damaged[100] ^= 1
    (tmp_path / "damaged.aacp").write_bytes(bytes(damaged))
    assert "checksum" in run_error(capsys, ["evaluate", str(tmp_path / "damaged.aacp")])
    assert "must end with .aacp" in run_error(capsys, ["export", str(trained / "model.zip"), str(tmp_path / "p.json")])
    assert "does not fit --profile v19" in run_error(capsys, ["evaluate", str(trained / "model.zip"), "--profile", "v19"])
    assert "existing file" in run_error(capsys, ["train", "--timesteps", "10", "--out", str(tmp_path / "notes.txt")])


def test_bench_quick(capsys) -> None:
    # The runtime benchmark in its quick mode (the env benchmark alone takes as long as this whole file).
    assert main(["bench", "--only", "runtime"]) == 0


@pytest.mark.parametrize(
    "argv",
    [
        ["train", "--timesteps", "100000", "--out", "/proc"],
        ["train", "--timesteps", "100000", "--out", "/sys/kernel"],
        ["train", "--timesteps", "100000", "--tensorboard", "/proc/tb"],
        ["train", "--timesteps", "100000", "--out", ""],
        ["reliability", "dribbler", "--players", "100000", "--out", "/proc/x.png"],
        ["render", "dribbler", "--out", "/proc/x.gif"],
        ["export", "MODEL", "/proc/x.aacp"],
    ],
)
def test_unwritable_outputs_fail_before_any_work(trained: Path, capsys, argv: list[str]) -> None:
    argv = [str(trained / "model.zip") if a == "MODEL" else a for a in argv]
    start = time.perf_counter()
    err = run_error(capsys, argv)
    assert "cannot write" in err or "current directory" in err
    assert len(err.strip().splitlines()) == 1
    assert time.perf_counter() - start < 5  # refused before training / evaluating 100,000 players
    assert "training" not in capsys.readouterr().out


def test_damaged_models_are_one_line(trained: Path, tmp_path: Path, capsys) -> None:
    import io
    import zipfile

    import torch as th

    members = {n: zipfile.ZipFile(trained / "model.zip").read(n) for n in zipfile.ZipFile(trained / "model.zip").namelist()}
    data = json.loads(members["data"])
    nan_weights = io.BytesIO()
    th.save(
        {k: v * float("nan") for k, v in th.load(io.BytesIO(members["policy.pth"]), weights_only=True).items()}, nan_weights
    )
    cases = {
        "garbage_pth": ({"policy.pth": b"\x00garbage" * 50}, "'policy.pth' is not a torch tensor file"),
        "data_list": ({"data": b"[1, 2, 3]"}, "'data' member is a JSON list"),
        "missing_keys": ({"data": json.dumps({k: data[k] for k in list(data)[:3]}).encode()}, "lacks the fields"),
        "wrong_space": (
            {"data": json.dumps({**data, "action_space": data["observation_space"]}).encode()},
            "SarsaAAC.load failed",
        ),
        "nan_weights": ({"policy.pth": nan_weights.getvalue()}, "NaN or inf"),
    }
    for name, (changed, message) in cases.items():
        path = tmp_path / f"{name}.zip"
        with zipfile.ZipFile(path, "w") as archive:
            for member, content in {**members, **changed}.items():
                archive.writestr(member, content)
        err = run_error(capsys, ["evaluate", str(path), "--episodes", "2"])
        assert len(err.strip().splitlines()) == 1 and str(path) in err and message in err, err
    (tmp_path / "empty.zip").write_bytes(b"")
    assert "it is empty" in run_error(capsys, ["evaluate", str(tmp_path / "empty.zip")])
    if Path("/dev/zero").exists():
        (tmp_path / "zero.zip").symlink_to("/dev/zero")
        assert "not a regular file" in run_error(capsys, ["export", str(tmp_path / "zero.zip"), str(tmp_path / "x.aacp")])


def test_train_out_overwrite_replaces_the_runs_files_and_keeps_other_files(trained: Path, tmp_path: Path, capsys) -> None:
    import shutil

    out = tmp_path / "run"
    shutil.copytree(trained, out)
    (out / "reliability.png").write_bytes(b"png")
    assert main(["train", "--policy", "RbfPolicy", "--timesteps", "200", "--n-envs", "2", "--seed", "7", "--out", str(out),
                 "--eval-episodes", "0", "--set", "n_rbf=3", "--overwrite"]) == 0  # fmt: skip
    assert json.loads((out / "run.json").read_text())["seed"] == 7
    assert (out / "reliability.png").read_bytes() == b"png"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"] and not list(out.glob(".*"))


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["train", "--n-envs", "100000000000"], "--n-envs: must be in 1 .. 65,536"),
        (["train", "--seed", str(2**70)], "--seed: must be in 0 .. 4294967295"),
        (["train", "--timesteps", "1" + "0" * 13], "--timesteps: must be in 1 .. 1e+11"),
        (["train", "--episodes", "0"], "--episodes: must be in 1 .. 10,000,000"),
        (["evaluate", "dribbler", "--episodes", str(10**20)], "--episodes: must be in 1 .. 10,000,000"),
        (["evaluate", "dribbler", "--seed", "-1"], "--seed: must be in 0 .. 4294967295"),
        (["render", "dribbler", "--fps", "1e-300"], "--fps: must be in 0.1 .. 1000 frames per second"),
        (["tune", "--n-envs", "1e11"], "--n-envs: expected a whole number, got '1e11'"),
    ],
)
def test_sizes_and_numbers_beyond_their_limits_are_one_line(capsys, argv, message) -> None:
    assert message in run_error(capsys, argv)


@pytest.mark.parametrize("keep", [True, False])
def test_ctrl_c_during_train_saves_the_model_so_far_or_says_so(tmp_path: Path, capsys, monkeypatch, keep) -> None:
    from sb3_aac import SarsaAAC
    from sb3_aac.cli import train

    def interrupted_learn(model, args, total_timesteps):
        model.learn(200)
        raise KeyboardInterrupt

    monkeypatch.setattr(train, "learn", interrupted_learn)
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as info:
        main(["train", "--timesteps", "1000", "--n-envs", "2", "--eval-episodes", "0", *(["--out", str(out)] if keep else [])])
    assert info.value.code == 130
    printed = capsys.readouterr().out
    if keep:
        assert "interrupted after 200 steps: saving the model trained so far" in printed and "saved" in printed
        assert SarsaAAC.load(out / "model.zip").num_timesteps == 200
        assert json.loads((out / "run.json").read_text())["interrupted"] is True
    else:
        assert "interrupted after 200 steps: nothing was kept (give --out DIR to keep a run)" in printed


def test_out_keeps_the_users_files_unless_overwrite(tmp_path: Path, capsys) -> None:
    out = tmp_path / "run"
    out.mkdir()
    (out / "model.zip").write_text("the user's own model")
    argv = ["train", "--timesteps", "100", "--n-envs", "2", "--eval-episodes", "0", "--out", str(out)]
    assert "already holds model.zip: pass --overwrite" in run_error(capsys, argv)
    assert (out / "model.zip").read_text() == "the user's own model"
    assert main([*argv, "--overwrite"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["model.zip", "policy.aacp", "run.json"]
