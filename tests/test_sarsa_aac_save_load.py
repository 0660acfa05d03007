"""SarsaAAC's own save/load behaviour; the contract every algorithm shares is in test_save_load.py."""

import io
import zipfile

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.env_util import make_vec_env

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
def test_numpy_views_follow_set_parameters(policy):
    """After set_parameters (which copies into the tensors) the numpy kernel computes with the new weights."""
    model = SarsaAAC(
        policy,
        ParameterizedTargetEnv(),
        policy_kwargs=dict(hidden_units=4) if policy in ("MlpPolicy", "RbfMlpPolicy") else None,
        seed=1,
    )
    model.learn(300)
    observations = np.random.default_rng(0).uniform(-1, 1, (10, 2)).astype(np.float32)
    params = model.get_parameters()
    before, _ = model.predict(observations, deterministic=True)
    # (a tile policy's integer grid layout stays; input scales and a deep policy's observation statistics stay > 0)
    random_params = {
        "policy": {
            k: (th.rand_like(v) + 0.5 if "obs_" in k else th.rand_like(v) * 2 - 1) if v.is_floating_point() else v
            for k, v in params["policy"].items()
        }
    }
    model.set_parameters(random_params, exact_match=True)
    out_random, _ = model.policy.evaluate(observations.astype(np.float64))
    with th.no_grad():
        np.testing.assert_allclose(out_random, model.policy(th.as_tensor(observations)).numpy(), atol=1e-12)
    assert repr(model.predict(observations, deterministic=True)[0]) != repr(before)


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
