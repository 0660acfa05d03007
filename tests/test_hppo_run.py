"""HybridPPO's own runs: the PPO options, shared actor layers, VecNormalize, truncation bootstraps and the array path
(every layout, SubprocVecEnv and DribbleVecEnv are tests/test_run.py's, for every algorithm)."""

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import VecNormalize

from sb3_aac import HybridPPO
from sb3_aac.common.array_env import array_path
from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.test_pdqn_array_path import ArrayTargetVecEnv, make

SMALL = dict(n_steps=32, batch_size=32, n_epochs=2, policy_kwargs=dict(net_arch=[16]))


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(clip_range_params=0.1, clip_range_vf=0.5, ent_coef=0.01, param_ent_coef=0.001),
        dict(learning_rate=lambda progress: 1e-3 * progress, clip_range=lambda progress: 0.2 * progress),
        dict(normalize_advantage=False, gae_lambda=1.0, target_kl=0.01),
        dict(policy_kwargs=dict(net_arch=dict(shared=[16], type=[8], params=[8], vf=[16]), log_std_init=-1.0)),
        dict(policy_kwargs=dict(net_arch=[], ortho_init=False, activation_fn=th.nn.ReLU)),
    ],
)
def test_run_variants(kwargs):
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(), seed=0, **{**SMALL, **kwargs})
    model.learn(64)
    assert model._n_updates > 0


def test_shared_first_layers_serve_both_actors():
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(), policy_kwargs=dict(net_arch=dict(shared=[8], type=[], params=[])))
    policy = model.policy
    assert policy.type_head.in_features == policy.mean_head.in_features == 8
    assert policy.value_net[0].in_features == 2  # the critic has its own layers


def test_vec_normalize():
    env = VecNormalize(make_vec_env(ParameterizedTargetEnv, n_envs=3, env_kwargs=dict(layout="flat")), norm_reward=False)
    model = HybridPPO("MlpPolicy", env, seed=0, **SMALL)
    model.learn(96)
    assert model.num_timesteps == 96 and model._episode_num > 0
    actions, _ = model.predict(env.reset(), deterministic=False)
    assert actions.shape == (3,) and all(env.action_space.contains(a) for a in actions)


def test_truncations_bootstrap_from_the_value_of_the_terminal_observation():
    """A time-limit truncation adds gamma * V(terminal observation) to the last reward; a termination does not."""
    rewards = {}
    for name, env_kwargs in (("truncated", dict(max_episode_steps=2, loss_threshold=0.0)), ("terminated", {})):
        env = make_vec_env(ParameterizedTargetEnv, n_envs=1, seed=0, env_kwargs=env_kwargs)
        model = HybridPPO("MlpPolicy", env, seed=0, **SMALL)
        model._setup_learn(32, None)
        model.collect_rollouts(model.env, model._init_callback(None), model.rollout_buffer, 32)
        rewards[name] = model.rollout_buffer.rewards[:, 0]
    # rewards of ParameterizedTargetEnv are in [0, 1]; a bootstrapped one is shifted by gamma * V (V != 0)
    assert np.all((rewards["terminated"] >= 0) & (rewards["terminated"] <= 1))
    assert np.any((rewards["truncated"][1::2] < 0) | (rewards["truncated"][1::2] > 1))


def test_array_path_matches_sb3_path():
    runs = []
    for with_arrays in (False, True):
        env = make(with_arrays, seed=3)
        assert (array_path(env) is not None) == with_arrays
        model = HybridPPO("MlpPolicy", env, seed=3, **SMALL)
        before = ArrayTargetVecEnv.arrays_stepped
        model.learn(96 * 3)
        assert (ArrayTargetVecEnv.arrays_stepped - before == 96) == with_arrays
        runs.append(model)
    sb3, arrays = runs
    for key, value in sb3.get_parameters()["policy"].items():
        assert th.equal(value, arrays.get_parameters()["policy"][key]), key
    assert [e["r"] for e in sb3.ep_info_buffer] == pytest.approx([e["r"] for e in arrays.ep_info_buffer])
    assert sb3._episode_num == arrays._episode_num > 0
