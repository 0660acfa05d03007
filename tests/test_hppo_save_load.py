"""Save/load of HybridPPO models, set_env, and bit-identical reruns (sb3-contrib's test_save_load shapes)."""

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac import PDQN, HybridPPO
from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import LAYOUTS

SMALL = dict(n_steps=32, batch_size=32, n_epochs=2, policy_kwargs=dict(net_arch=[16]))


def same_actions(spec, a, b):
    for x, y in zip(spec.from_env(a), spec.from_env(b), strict=True):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_save_load(tmp_path, layout):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=2, env_kwargs=dict(layout=layout))
    model = HybridPPO("MlpPolicy", env, seed=1, clip_range_params=0.1, **SMALL)
    model.learn(128)
    obs = np.random.default_rng(0).uniform(-1, 1, (10, 2)).astype(np.float32)
    params = model.get_parameters()
    assert set(params) == {"policy", "policy.optimizer"}
    with pytest.raises(ValueError, match="Key invalid_object is an invalid object name"):
        model.set_parameters({"invalid_object": {}}, exact_match=False)
    with pytest.raises(ValueError, match="Names of parameters do not match"):
        model.set_parameters({}, exact_match=True)

    selected, _ = model.predict(obs, deterministic=True)
    model.save(tmp_path / "model.zip")
    loaded = HybridPPO.load(tmp_path / "model.zip", env=env, device="cpu")
    for key, value in loaded.get_parameters()["policy"].items():
        assert th.equal(value, params["policy"][key]), key
    same_actions(model.policy.spec, loaded.predict(obs, deterministic=True)[0], selected)
    assert loaded.num_timesteps == 128 and loaded.clip_range_params == 0.1
    assert loaded.clip_range_params_schedule(1.0) == 0.1
    loaded.learn(64, reset_num_timesteps=False)
    assert loaded.num_timesteps == 192


def test_set_env(tmp_path):
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(), seed=0, **SMALL).learn(32)
    model.set_env(make_vec_env(ParameterizedTargetEnv, n_envs=1, seed=1))
    model.learn(32)
    model.set_env(ParameterizedTargetEnv())  # a raw env is wrapped
    model.learn(32)
    model.save(tmp_path / "model.zip")
    loaded = HybridPPO.load(tmp_path / "model.zip", env=make_vec_env(ParameterizedTargetEnv, n_envs=2))
    loaded.learn(64)  # load with another number of envs rebuilds the rollout buffer
    assert loaded.rollout_buffer.n_envs == 2
    with pytest.raises(ValueError, match="spaces do not match"):
        model.set_env(ParameterizedTargetEnv(n_types=2))


def test_load_other_algorithm_is_rejected(tmp_path):
    PDQN("MlpPolicy", ParameterizedTargetEnv(), seed=0).save(tmp_path / "pdqn.zip")
    with pytest.raises(ValueError, match="needs a HybridActorCriticPolicy"):
        HybridPPO.load(tmp_path / "pdqn.zip")


def run(layout, seed):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=2, env_kwargs=dict(layout=layout))
    model = HybridPPO("MlpPolicy", env, seed=seed, **SMALL)
    model.learn(128)
    env.seed(seed)
    obs, rewards = env.reset(), []
    for _ in range(10):
        actions, _ = model.predict(obs, deterministic=False)
        obs, reward, _, _ = env.step(actions)
        rewards.append(reward)
    return model.get_parameters(), np.array(rewards)


@pytest.mark.parametrize("layout", ["nested", "oneof"])
def test_deterministic_reruns(layout):
    params_1, rewards_1 = run(layout, 3)
    params_2, rewards_2 = run(layout, 3)
    for key in params_1["policy"]:
        assert th.equal(params_1["policy"][key], params_2["policy"][key]), key  # bit-identical
    np.testing.assert_array_equal(rewards_1, rewards_2)
    params_3, _ = run(layout, 4)
    assert not all(th.equal(params_1["policy"][k], params_3["policy"][k]) for k in params_1["policy"])


def test_deterministic_predict_is_the_mode():
    """deterministic=True: the most probable type with its mean parameters, the same on every call."""
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(layout="nested"), seed=0, **SMALL).learn(64)
    obs = np.random.default_rng(1).uniform(-1, 1, (20, 2)).astype(np.float32)
    first, _ = model.predict(obs, deterministic=True)
    same_actions(model.policy.spec, model.predict(obs, deterministic=True)[0], first)
    with th.no_grad():
        dist = model.policy.get_distribution(th.as_tensor(obs))
    k, params = model.policy.spec.from_env(first)
    np.testing.assert_array_equal(k, dist.types.logits.argmax(1).numpy())
    np.testing.assert_allclose(params, np.clip(dist.mean.numpy(), -1, 1), atol=1e-5)
    sampled = {model.predict(obs[0], deterministic=False)[0][0] for _ in range(30)}
    assert len(sampled) > 1  # sampling explores the types (entropy is still high after 64 steps)
