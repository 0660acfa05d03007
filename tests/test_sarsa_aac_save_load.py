import io
import zipfile

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import DummyVecEnv

from sb3_aac import SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.sarsa_aac.policies import MlpPolicy, RbfMlpPolicy, RbfPolicy
from tests.helpers import POLICIES


def same_actions(a, b):
    """Two batches (object arrays) of env actions are equal."""
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert x[0] == y[0]
        for p, q in zip(x[1], y[1], strict=True):
            np.testing.assert_allclose(p, q, atol=1e-6)


@pytest.mark.parametrize("policy", POLICIES)
def test_save_load(tmp_path, policy):
    env = DummyVecEnv([ParameterizedTargetEnv])
    model = SarsaAAC(
        policy, env, policy_kwargs=dict(hidden_units=4) if policy in ("MlpPolicy", "RbfMlpPolicy") else None, seed=1
    )
    model.learn(300)
    observations = np.random.default_rng(0).uniform(-1, 1, (10, 2)).astype(np.float32)

    # set_parameters error cases (as in sb3-contrib's test_save_load)
    params = model.get_parameters()
    with pytest.raises(ValueError, match="Key invalid_object is an invalid object name"):
        model.set_parameters({"invalid_object": {}}, exact_match=False)
    with pytest.raises(ValueError, match="Names of parameters do not match"):
        model.set_parameters({}, exact_match=True)
    first_key = next(iter(params["policy"]))
    incomplete = {"policy": {k: v for k, v in params["policy"].items() if k != first_key}}
    with pytest.raises(RuntimeError, match=f'Missing key\\(s\\) in state_dict: "{first_key}"'):
        model.set_parameters(incomplete, exact_match=True)

    # Random parameters really change every tensor and every prediction (the numpy views follow).
    before, _ = model.predict(observations, deterministic=True)
    # (a tile policy's integer grid layout stays; input scales and a deep policy's observation statistics stay > 0)
    random_params = {
        "policy": {
            k: (th.rand_like(v) + 0.5 if "obs_" in k else th.rand_like(v) * 2 - 1) if v.is_floating_point() else v
            for k, v in params["policy"].items()
        }
    }
    model.set_parameters(random_params, exact_match=True)
    for key, value in model.get_parameters()["policy"].items():
        assert th.equal(value, random_params["policy"][key]), key
    out_random, _ = model.policy.evaluate(observations.astype(np.float64))
    with th.no_grad():
        np.testing.assert_allclose(out_random, model.policy(th.as_tensor(observations)).numpy(), atol=1e-12)

    selected, _ = model.predict(observations, deterministic=True)
    path = tmp_path / "model.zip"
    model.save(path)
    for device in ("auto", "cpu"):
        loaded = SarsaAAC.load(path, env=env, device=device)
        assert loaded.device.type == "cpu"  # no GPU here; "auto" resolves to cpu
        for key, value in loaded.get_parameters()["policy"].items():
            assert th.equal(value, random_params["policy"][key]), key
        same_actions(loaded.predict(observations, deterministic=True)[0], selected)
        assert loaded.num_timesteps == 300
        loaded.learn(200, reset_num_timesteps=False)
        assert loaded.num_timesteps == 500
    assert before is not None


@pytest.mark.parametrize("policy_class", [MlpPolicy, RbfMlpPolicy, RbfPolicy])
def test_save_load_policy(tmp_path, policy_class):
    model = SarsaAAC(policy_class, ParameterizedTargetEnv(), policy_kwargs=dict(rbf_width=0.7), seed=2)
    model.learn(200)
    observations = np.random.default_rng(1).uniform(-1, 1, (5, 2)).astype(np.float32)
    actions, _ = model.policy.predict(observations)
    model.policy.save(tmp_path / "policy.pkl")
    loaded = policy_class.load(tmp_path / "policy.pkl")
    assert loaded.rbf_width == 0.7 and loaded.n_rbf == model.policy.n_rbf
    same_actions(loaded.predict(observations)[0], actions)


def test_load_with_changed_hyperparameters(tmp_path):
    """Everything derived is rebuilt in _setup_model, so load(..., kwarg=...) takes effect (cf. SB3 GH#1373)."""
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), exploration_final_eps=0.05, seed=0)
    model.learn(100)
    model.save(tmp_path / "model.zip")
    loaded = SarsaAAC.load(tmp_path / "model.zip", env=ParameterizedTargetEnv(), gamma=0.5, exploration_final_eps=0.2)
    assert loaded.gamma == 0.5
    assert loaded.exploration_schedule(0.0) == pytest.approx(0.2)
    loaded.learn(100)
    assert loaded.exploration_rate == pytest.approx(0.2)


def test_load_into_mismatched_env(tmp_path):
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv("nested"), seed=0)
    model.save(tmp_path / "model.zip")
    with pytest.raises(ValueError, match="Action spaces do not match"):
        SarsaAAC.load(tmp_path / "model.zip", env=ParameterizedTargetEnv("flat"))
    with pytest.raises(ValueError, match="Action spaces do not match"):
        SarsaAAC.load(tmp_path / "model.zip", env=ParameterizedTargetEnv("nested", n_types=2))
    with pytest.raises(ValueError, match="Action spaces do not match"):
        model.set_env(ParameterizedTargetEnv("oneof"))


def test_set_env(tmp_path):
    model = SarsaAAC("RbfPolicy", make_vec_env(ParameterizedTargetEnv, n_envs=2, seed=0), seed=0)
    model.learn(100)
    model.set_env(make_vec_env(ParameterizedTargetEnv, n_envs=2, seed=1))
    model.learn(100, reset_num_timesteps=False)
    assert model.num_timesteps == 200
    model.save(tmp_path / "model.zip")
    # A different number of envs goes through load, which re-chooses the pending action for the new envs.
    loaded = SarsaAAC.load(tmp_path / "model.zip", env=make_vec_env(ParameterizedTargetEnv, n_envs=3, seed=2))
    loaded.learn(100, reset_num_timesteps=False)
    assert loaded.num_timesteps == 200 + 102  # 3 envs step together: 34 steps
    assert len(loaded._pending[1]) == 3


def test_exclude_include(tmp_path):
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), gamma=0.7, seed=0)
    model.learn(50)
    model.save(tmp_path / "model.zip", exclude=["gamma"])
    with zipfile.ZipFile(tmp_path / "model.zip") as archive:
        data = archive.read("data").decode()
    assert '"gamma"' not in data and '"_pending"' not in data and '"_rng"' not in data
    loaded = SarsaAAC.load(tmp_path / "model.zip")
    assert loaded.gamma == 0.9  # the constructor default, since gamma was excluded


@pytest.mark.parametrize("corruption", ["truncated", "not_a_zip", "empty_zip"])
def test_load_corrupted_file(tmp_path, corruption):
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), seed=0)
    buffer = io.BytesIO()
    model.save(buffer)
    content = buffer.getvalue()
    path = tmp_path / "model.zip"
    if corruption == "truncated":
        path.write_bytes(content[: len(content) // 2])
    elif corruption == "not_a_zip":
        path.write_bytes(b"this is not a model")
    else:
        with zipfile.ZipFile(path, "w"):
            pass
    with pytest.raises(ValueError, match=r"is not a complete SarsaAAC model|wasn.t a zip-file|is not a usable saved model"):
        SarsaAAC.load(path)


def test_load_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError):
        SarsaAAC.load(tmp_path / "nothing.zip")


def test_load_other_algorithm_file(tmp_path):
    from stable_baselines3 import DQN
    from stable_baselines3.common.envs import IdentityEnv

    DQN("MlpPolicy", IdentityEnv(3), learning_starts=0).save(tmp_path / "dqn.zip")
    with pytest.raises(ValueError, match=r"SarsaAAC needs a SarsaAACPolicy .* got <class .*DQNPolicy'> .*another algorithm"):
        SarsaAAC.load(tmp_path / "dqn.zip")
