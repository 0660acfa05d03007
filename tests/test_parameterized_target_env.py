import warnings

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.common.spaces import ParameterizedActionSpec

LAYOUTS = ["nested", "flat", "shared", "oneof"]


def run_episodes(env, choose, n_episodes=100):
    returns = []
    for episode in range(n_episodes):
        obs, _ = env.reset(seed=episode)
        done, total = False, 0.0
        while not done:
            obs, reward, terminated, truncated, info = env.step(choose(obs))
            total += reward
            done = terminated or truncated
        assert info["distance"] == pytest.approx(total)
        returns.append(total)
    return np.mean(returns)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_env_checker_and_known_optimum(layout):
    env = ParameterizedTargetEnv(layout)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*symmetric and normalized.*")
        check_env(env, skip_render_check=True)
    spec = ParameterizedActionSpec.from_space(env.action_space)

    def optimal(obs):
        k = env.best_type(obs)
        params = np.zeros(spec.n_params)
        params[spec.type_slice(k)] = env.target(obs, k)
        return spec.to_env_single(k, params)

    assert run_episodes(env, optimal) == pytest.approx(env.max_episode_steps)
    assert run_episodes(env, lambda obs: env.action_space.sample()) < 0.5


def test_termination_and_truncation():
    env = ParameterizedTargetEnv("nested", max_episode_steps=3)
    obs, _ = env.reset(seed=0)
    far = (0, (np.array([2.0], np.float32), np.array([1.0, 10.0], np.float32), np.array([1.0, 1.0], np.float32)))
    # Type 0's target is within 0.7 of the centre, so its upper bound is far from it.
    _, _, terminated, truncated, info = env.step(far)
    assert terminated and not truncated and info["ball_lost"]
    spec = ParameterizedActionSpec.from_space(env.action_space)
    obs, _ = env.reset(seed=0)
    for step in range(3):
        k = env.best_type(obs)
        params = np.zeros(spec.n_params)
        params[spec.type_slice(k)] = env.target(obs, k)
        obs, reward, terminated, truncated, info = env.step(spec.to_env_single(k, params))
        assert reward == pytest.approx(1.0)
        assert not terminated and truncated == (step == 2)


def test_bad_arguments_and_actions():
    with pytest.raises(ValueError, match="Unknown layout 'tuple'"):
        ParameterizedTargetEnv("tuple")
    env = ParameterizedTargetEnv("flat")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="is not an element"):
        env.step((0, np.zeros(1, np.float32)))
