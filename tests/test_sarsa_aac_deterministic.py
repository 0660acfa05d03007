import numpy as np
import pytest
import torch as th
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac import SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import LAYOUTS, POLICIES

SEED = 0


def train_and_roll_out(policy, layout, seed, type_exploration="epsilon_greedy"):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=2, env_kwargs=dict(layout=layout))
    model = SarsaAAC(policy, env, type_exploration=type_exploration, exploration_initial_eps=0.5, seed=seed)
    model.learn(256)
    env.seed(seed)
    obs = env.reset()
    rewards, types = [], []
    for _ in range(20):
        actions, _ = model.predict(obs, deterministic=False)  # draws from the model's generator too
        obs, reward, _, _ = env.step(actions)
        rewards.append(reward)
        types.append([a[0] for a in actions])
    return model.get_parameters()["policy"], np.array(rewards), np.array(types)


@pytest.mark.parametrize("policy", POLICIES)
@pytest.mark.parametrize("layout", ["nested", "oneof"])
def test_deterministic_training(policy, layout):
    params_1, rewards_1, types_1 = train_and_roll_out(policy, layout, SEED)
    params_2, rewards_2, types_2 = train_and_roll_out(policy, layout, SEED)
    for key in params_1:
        assert th.equal(params_1[key], params_2[key]), key  # bit-identical
    np.testing.assert_array_equal(rewards_1, rewards_2)
    np.testing.assert_array_equal(types_1, types_2)


def test_boltzmann_deterministic_and_seed_matters():
    params_1, rewards_1, _ = train_and_roll_out("RbfPolicy", "flat", SEED, "boltzmann")
    params_2, rewards_2, _ = train_and_roll_out("RbfPolicy", "flat", SEED, "boltzmann")
    params_3, rewards_3, _ = train_and_roll_out("RbfPolicy", "flat", SEED + 1, "boltzmann")
    assert all(th.equal(params_1[key], params_2[key]) for key in params_1)
    np.testing.assert_array_equal(rewards_1, rewards_2)
    assert not th.equal(params_1["approximators.weight"], params_3["approximators.weight"])
    assert not np.array_equal(rewards_1, rewards_3)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_set_random_seed_restarts_stream(layout):
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(layout), exploration_initial_eps=1.0, seed=3)
    obs = np.zeros(2, np.float32)
    model.set_random_seed(7)
    first = [model.predict(obs)[0][0] for _ in range(30)]
    model.set_random_seed(7)
    second = [model.predict(obs)[0][0] for _ in range(30)]
    assert first == second and len(set(first)) > 1
