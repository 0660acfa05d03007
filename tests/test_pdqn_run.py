"""P-DQN / MP-DQN with the SB3 off-policy options; what every algorithm runs alike is in test_run.py."""

import numpy as np
import pytest
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac import MPDQN, PDQN
from sb3_aac.common.envs import ParameterizedTargetEnv

ALGOS = [PDQN, MPDQN]
SMALL = dict(learning_starts=50, batch_size=16, policy_kwargs=dict(net_arch=[16]))


@pytest.mark.parametrize("algo", ALGOS)
@pytest.mark.parametrize(
    "kwargs",
    [
        dict(train_freq=(1, "episode"), gradient_steps=-1),
        dict(train_freq=4, gradient_steps=2, target_update_interval=3),
        dict(optimize_memory_usage=True, replay_buffer_kwargs=dict(handle_timeout_termination=False)),
        dict(param_noise="gaussian", loss="huber"),
        dict(param_noise=None, policy_kwargs=dict(net_arch=[8, 8], actor_net_arch=[4], param_bounding="tanh")),
        dict(policy_kwargs=dict(initial_params=[1.0, 0.5, 5.0, 0.0, 0.0])),
        dict(learning_rate=lambda progress: 1e-3 * progress, actor_learning_rate=lambda progress: 1e-4 * progress),
    ],
)
def test_run_variants(algo, kwargs):
    model = algo("MlpPolicy", ParameterizedTargetEnv(), seed=0, **{**SMALL, **kwargs})
    model.learn(150)
    assert model._n_updates > 0


@pytest.mark.parametrize("algo", ALGOS)
def test_replay_buffer_rows_hold_every_env(algo):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=3, env_kwargs=dict(layout="flat"))
    model = algo("MlpPolicy", env, seed=0, **SMALL)
    model.learn(300)
    assert model.replay_buffer.size() == 100  # rows of 3 transitions


def test_episodic_train_freq_needs_one_env():
    env = make_vec_env(ParameterizedTargetEnv, n_envs=2)
    model = PDQN("MlpPolicy", env, train_freq=(1, "episode"), **SMALL)
    with pytest.raises(ValueError, match="train_freq in episodes needs one env"):
        model.learn(10)


def test_initial_params_set_the_actor_start():
    """The actor starts at initial_params (its last layer is nearly zero), as in the reference code."""
    env = ParameterizedTargetEnv(layout="nested")
    model = MPDQN("MlpPolicy", env, policy_kwargs=dict(initial_params=[1.5, 0.25, 7.5, 0.5, -0.5]), seed=0)
    action, _ = model.predict(np.zeros(2, np.float32), deterministic=True)
    np.testing.assert_allclose(np.concatenate(action[1]), [1.5, 0.25, 7.5, 0.5, -0.5], atol=1e-3)
