"""Save/load of every algorithm (sb3-contrib's test_save_load shape), parametrised over tests.helpers.ALGOS."""

import inspect
import zipfile

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import ALGO_CLASSES, LAYOUTS, algos


def same_actions(spec, a, b):
    """Two batches (object arrays) of env actions are equal (parameters to float32 rounding)."""
    assert len(a) == len(b)
    for x, y in zip(spec.from_env(a), spec.from_env(b), strict=True):
        np.testing.assert_allclose(x, y, atol=1e-6)


@algos()
@pytest.mark.parametrize("layout", LAYOUTS)
def test_save_load(tmp_path, case, layout):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=2, env_kwargs=dict(layout=layout))
    model = case.make(env, seed=1)
    model.learn(300)
    observations = np.random.default_rng(0).uniform(-1, 1, (10, 2)).astype(np.float32)

    # set_parameters error cases (as in sb3-contrib's test_save_load)
    params = model.get_parameters()
    with pytest.raises(ValueError, match="Key invalid_object is an invalid object name"):
        model.set_parameters({"invalid_object": {}}, exact_match=False)
    with pytest.raises(ValueError, match="Names of parameters do not match"):
        model.set_parameters({}, exact_match=True)
    first_key = next(iter(params["policy"]))
    incomplete = {**params, "policy": {k: v for k, v in params["policy"].items() if k != first_key}}
    with pytest.raises(RuntimeError, match=f'Missing key\\(s\\) in state_dict: "{first_key}"'):
        model.set_parameters(incomplete, exact_match=True)

    # Random parameters replace every tensor (a tile policy's integer grid layout stays; input scales and a deep
    # policy's observation statistics stay > 0).
    random_params = {
        **params,
        "policy": {
            k: (th.rand_like(v) + 0.5 if "obs_" in k else th.rand_like(v) * 2 - 1) if v.is_floating_point() else v
            for k, v in params["policy"].items()
        },
    }
    model.set_parameters(random_params, exact_match=True)
    for key, value in model.get_parameters()["policy"].items():
        assert th.equal(value, random_params["policy"][key]), key

    selected, _ = model.predict(observations, deterministic=True)
    path = tmp_path / "model.zip"
    model.save(path)
    for device in ("auto", "cpu"):
        loaded = case.algo.load(path, env=env, device=device)
        assert loaded.device.type == "cpu"  # no GPU here; "auto" resolves to cpu
        for key, value in loaded.get_parameters()["policy"].items():
            assert th.equal(value, random_params["policy"][key]), key
        same_actions(model.policy.spec, loaded.predict(observations, deterministic=True)[0], selected)
        trained = case.timesteps(300, n_envs=2)
        assert loaded.num_timesteps == trained
        loaded.learn(200, reset_num_timesteps=False)
        assert loaded.num_timesteps == case.timesteps(200, n_envs=2, start=trained)


@algos(ALGO_CLASSES)
def test_load_with_changed_hyperparameters(tmp_path, case):
    """Everything derived is rebuilt in _setup_model, so load(..., kwarg=...) takes effect (cf. SB3 GH#1373)."""
    name, value_in_use = case.rebuilt
    model = case.make(ParameterizedTargetEnv(), seed=0, **{name: 0.05})
    model.learn(100)
    model.save(tmp_path / "model.zip")
    loaded = case.algo.load(tmp_path / "model.zip", env=ParameterizedTargetEnv(), gamma=0.5, **{name: 0.2})
    assert loaded.gamma == 0.5
    loaded.learn(100)
    assert value_in_use(loaded) == pytest.approx(0.2)


@algos(ALGO_CLASSES)
def test_load_into_mismatched_env(tmp_path, case):
    model = case.make(ParameterizedTargetEnv("nested"), seed=0)
    model.save(tmp_path / "model.zip")
    with pytest.raises(ValueError, match="Action spaces do not match"):
        case.algo.load(tmp_path / "model.zip", env=ParameterizedTargetEnv("flat"))
    with pytest.raises(ValueError, match="Action spaces do not match"):
        case.algo.load(tmp_path / "model.zip", env=ParameterizedTargetEnv("nested", n_types=2))
    with pytest.raises(ValueError, match="Action spaces do not match"):
        model.set_env(ParameterizedTargetEnv("oneof"))


@algos(ALGO_CLASSES)
def test_exclude_include(tmp_path, case):
    model = case.make(ParameterizedTargetEnv(), gamma=0.7, seed=0)
    model.learn(50)
    model.save(tmp_path / "model.zip", exclude=["gamma"])
    with zipfile.ZipFile(tmp_path / "model.zip") as archive:
        data = archive.read("data").decode()
    assert '"gamma"' not in data and '"_rng"' not in data
    for name in model._excluded_save_params():  # per-run state (SarsaAAC's _pending, P-DQN's _noise, ...)
        assert f'"{name}"' not in data, name
    loaded = case.algo.load(tmp_path / "model.zip")
    assert loaded.gamma == inspect.signature(case.algo).parameters["gamma"].default  # gamma was excluded


@algos(ALGO_CLASSES)
def test_load_missing_file(tmp_path, case):
    with pytest.raises(FileNotFoundError):
        case.algo.load(tmp_path / "nothing.zip")


@algos(ALGO_CLASSES)
def test_load_other_algorithm_file(tmp_path, case):
    from stable_baselines3 import DQN
    from stable_baselines3.common.envs import IdentityEnv

    DQN("MlpPolicy", IdentityEnv(3), learning_starts=0).save(tmp_path / "dqn.zip")
    message = rf"{case.algo.__name__} needs a \w+Policy .* got <class .*DQNPolicy'> .*another algorithm"
    with pytest.raises(ValueError, match=message):
        case.algo.load(tmp_path / "dqn.zip")
    for other in ALGO_CLASSES:
        if not issubclass(other.algo, case.algo) and not issubclass(case.algo, other.algo):
            other.make(ParameterizedTargetEnv(), seed=0).save(tmp_path / "other.zip")
            with pytest.raises(ValueError, match=rf"{case.algo.__name__} needs a \w+Policy"):
                case.algo.load(tmp_path / "other.zip")


def rewritten(source, target, drop=(), data=lambda fields: fields):
    """Copy the model file ``source`` to ``target`` without the members ``drop`` and with its ``data`` edited."""
    import json

    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w") as zout:
        for item in zin.infolist():
            if item.filename not in drop:
                raw = zin.read(item)
                zout.writestr(item, json.dumps(data(json.loads(raw))) if item.filename == "data" else raw)
    return target


@algos(ALGO_CLASSES)
def test_a_damaged_model_file_is_one_clear_error(tmp_path, case):
    """Truncated, without its optimizer state or policy_class, NaN weights, a learning rate that is no number: each a
    ValueError naming the file or the field and what is wrong, never SB3's KeyError or assertion (or a NaN decision)."""
    model = case.make(ParameterizedTargetEnv(), seed=0)
    model.save(tmp_path / "model.zip")
    raw = (tmp_path / "model.zip").read_bytes()
    (tmp_path / "truncated.zip").write_bytes(raw[: len(raw) // 2])
    with pytest.raises(ValueError, match=r"truncated.zip is not a"):
        case.algo.load(tmp_path / "truncated.zip")
    no_class = rewritten(tmp_path / "model.zip", tmp_path / "no_class.zip", data=lambda d: d.pop("policy_class") and d)
    with pytest.raises(ValueError, match=r"no_class.zip is not a usable saved model: .* lacks the fields \['policy_class'\]"):
        case.algo.load(no_class)
    no_optimizer = rewritten(tmp_path / "model.zip", tmp_path / "no_optimizer.zip", drop=("policy.optimizer.pth",))
    try:
        loaded = case.algo.load(no_optimizer)  # loads where acting needs no optimizer state
    except ValueError as error:
        assert "no_optimizer.zip is not a complete" in str(error)
    else:
        assert loaded.predict(model.observation_space.sample(), deterministic=True)[0] is not None
    with th.no_grad():
        for parameter in model.policy.parameters():
            parameter.fill_(float("nan"))
    model.save(tmp_path / "nan.zip")
    with pytest.raises(ValueError, match=r"nan.zip is not a usable saved model: .* holds NaN or inf values"):
        case.algo.load(tmp_path / "nan.zip")
    with pytest.raises(ValueError, match=r"learning_rate must be .*got '?abc"):
        case.algo.load(tmp_path / "model.zip", custom_objects={"learning_rate": "abc"})


@algos(ALGO_CLASSES)
def test_save_removes_a_killed_saves_temporaries_and_names_a_file_in_the_way(tmp_path, case):
    import subprocess
    import sys

    model = case.make(ParameterizedTargetEnv(), seed=0)
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    leftover = tmp_path / f".model.zip.sb3aac-{int(dead.stdout)}.tmpabc.zip"  # what a save killed with -9 leaves
    leftover.write_bytes(b"half a model")
    model.save(tmp_path / "model.zip")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.zip"]
    (tmp_path / "file").write_text("not a folder")
    with pytest.raises(NotADirectoryError, match="its folder, or one above it, is a file"):
        model.save(tmp_path / "file" / "model.zip")
