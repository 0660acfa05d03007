"""P-DQN and MP-DQN learn the toy env with a known optimum (return 10) in seconds."""

import pytest
from stable_baselines3.common.evaluation import evaluate_policy

from sb3_aac import MPDQN, PDQN
from sb3_aac.common.envs import ParameterizedTargetEnv

# The optimal policy is greedy (the next point does not depend on the action), so gamma = 0.
TOY = dict(
    gamma=0.0,
    learning_starts=200,
    batch_size=64,
    exploration_fraction=0.3,
    param_noise_std=0.05,
    actor_learning_rate=3e-3,
    actor_tau=0.05,
    policy_kwargs=dict(net_arch=[64]),
)


@pytest.mark.slow
@pytest.mark.parametrize("algo, at_least", [(PDQN, 8.0), (MPDQN, 9.0)])
def test_learns_the_known_optimum(algo, at_least):
    env = ParameterizedTargetEnv(layout="nested")
    model = algo("MlpPolicy", env, seed=0, device="cpu", **TOY)
    untrained, _ = evaluate_policy(model, model.get_env(), n_eval_episodes=50)
    model.learn(3000)
    trained, _ = evaluate_policy(model, model.get_env(), n_eval_episodes=50)
    assert untrained < 3.0 and trained >= at_least, (untrained, trained)
