"""HybridPPO's own save/load checks, set_env, bit-identical reruns and the deterministic mode (sb3-contrib's
test_save_load shapes; the round trip in every layout is tests/test_save_load.py's, for every algorithm)."""

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac import HybridPPO
from sb3_aac.common.envs import ParameterizedTargetEnv

SMALL = dict(n_steps=32, batch_size=32, n_epochs=2, policy_kwargs=dict(net_arch=[16]))


def same_actions(spec, a, b):
    for x, y in zip(spec.from_env(a), spec.from_env(b), strict=True):
        np.testing.assert_array_equal(x, y)


def test_save_load_keeps_the_clip_ranges(tmp_path):
    """The clip ranges are saved and their schedules rebuilt (every layout's round trip is tests/test_save_load.py's)."""
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(), seed=1, clip_range_params=0.1, clip_range_vf=0.3, **SMALL)
    assert set(model.get_parameters()) == {"policy", "policy.optimizer"}
    model.save(tmp_path / "model.zip")
    loaded = HybridPPO.load(tmp_path / "model.zip")
    assert (loaded.clip_range, loaded.clip_range_params, loaded.clip_range_vf) == (0.2, 0.1, 0.3)
    assert loaded.clip_range_params_schedule(1.0) == 0.1 and loaded.clip_range_vf_schedule(1.0) == 0.3


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
    np.testing.assert_array_equal(k, dist.type_logits.argmax(1).numpy())
    np.testing.assert_allclose(params, np.clip(dist.mean.numpy(), -1, 1), atol=1e-5)
    sampled = {model.predict(obs[0], deterministic=False)[0][0] for _ in range(30)}
    assert len(sampled) > 1  # sampling explores the types (entropy is still high after 64 steps)
