"""HybridPPO learns the toy env with a known optimum (return 10); PPO through FlattenParameterizedAction, with the same
settings and budget, does not."""

import pytest
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

from sb3_aac import FlattenParameterizedAction, HybridPPO
from sb3_aac.common.envs import ParameterizedTargetEnv

# The optimal policy is greedy (the next point does not depend on the action), so gamma = 0; hyperparams/hppo.yml's
# entry for sb3_aac/ParameterizedTarget-v0.
TOY = dict(n_steps=64, batch_size=64, gamma=0.0, learning_rate=1e-3, policy_kwargs=dict(log_std_init=-1.0))
BUDGET = 10_000  # measured (seed 0): HybridPPO 9.9, PPO through the flatten wrapper 7.5


@pytest.mark.slow
def test_learns_the_known_optimum_where_flattened_ppo_does_not():
    env = make_vec_env(ParameterizedTargetEnv, n_envs=4, seed=0)
    model = HybridPPO("MlpPolicy", env, seed=0, device="cpu", **TOY).learn(BUDGET)
    hybrid, _ = evaluate_policy(model, make_vec_env(ParameterizedTargetEnv, seed=100), n_eval_episodes=50)
    flat_env = make_vec_env(ParameterizedTargetEnv, n_envs=4, seed=0, wrapper_class=FlattenParameterizedAction)
    flat = PPO("MlpPolicy", flat_env, seed=0, device="cpu", **TOY).learn(BUDGET)
    flat_eval = make_vec_env(ParameterizedTargetEnv, seed=100, wrapper_class=FlattenParameterizedAction)
    flattened, _ = evaluate_policy(flat, flat_eval, n_eval_episodes=50)
    assert hybrid >= 9.0 > flattened, (hybrid, flattened)
