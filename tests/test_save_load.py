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
