"""Every algorithm runs, predicts and fails clearly alike (sb3-contrib's test_run shape), over tests.helpers.ALGOS."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import ALGO_CLASSES, ALGOS, LAYOUTS, OneStepEnv, algos


@algos()
@pytest.mark.parametrize("layout", LAYOUTS)
def test_run_every_layout(case, layout):
    env = ParameterizedTargetEnv(layout=layout)
    check_env(env, skip_render_check=True)
    model = case.make(env, seed=0)
    model.learn(total_timesteps=300)
    assert model.num_timesteps == case.timesteps(300) and model._n_updates > 0
    obs, _ = env.reset(seed=1)
    for deterministic in (True, False):
        action, state = model.predict(obs, deterministic=deterministic)
        assert state is None
        assert isinstance(action, tuple) and env.action_space.contains(action)
        env.step(action)
    mean_reward, _ = evaluate_policy(model, model.get_env(), n_eval_episodes=2)
    assert np.isfinite(mean_reward)


@algos(ALGO_CLASSES)
@pytest.mark.parametrize("vec_env_class", [DummyVecEnv, SubprocVecEnv])
def test_multi_env_and_window(case, vec_env_class):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=3, seed=0, env_kwargs=dict(layout="flat"), vec_env_cls=vec_env_class)
    model = case.make(env, seed=0, stats_window_size=7)
    model.learn(300)
    assert model.num_timesteps == case.timesteps(300, n_envs=3)
    assert model.ep_info_buffer.maxlen == 7 and model._ep_keyword_buffers["distance"].maxlen == 7
    assert model.episode_num > 0 and len(model._ep_keyword_buffers["distance"]) == min(7, model.episode_num)
    for deterministic in (True, False):
        actions, _ = model.predict(env.reset(), deterministic=deterministic)
        assert actions.dtype == object and actions.shape == (3,)
        assert all(env.action_space.contains(a) for a in actions)
    env.close()


@algos()
def test_dribble_vec_env(case):
    from robocup_dribble import DribbleVecEnv

    env = DribbleVecEnv(4, profile="v11")
    model = case.make(env, seed=0)
    model.learn(200)
    assert model.num_timesteps == case.timesteps(200, n_envs=4) and model._n_updates > 0
    actions, _ = model.predict(env.reset(), deterministic=True)
    assert all(env.action_space.contains(a) for a in actions)


@algos(ALGO_CLASSES)
def test_predict_bad_observations(case):
    model = case.make(ParameterizedTargetEnv(), seed=0)
    with pytest.raises(ValueError, match=r"Unexpected observation shape \(3,\)"):
        model.predict(np.zeros(3))
    with pytest.raises(ValueError, match=r"Unexpected observation shape \(4, 3\)"):
        model.predict(np.zeros((4, 3)))
    for deterministic in (True, False):
        with pytest.raises(ValueError, match="The observation holds NaN or inf values"):
            model.predict(np.array([0.0, np.nan], np.float32), deterministic=deterministic)


class BoxActionEnv(gym.Env):
    observation_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
    action_space = spaces.Box(-1.0, 1.0, (3,), np.float32)


class DiscreteObsEnv(gym.Env):
    observation_space = spaces.Discrete(4)
    action_space = ParameterizedTargetEnv().action_space


@algos(ALGO_CLASSES)
@pytest.mark.parametrize(
    "env, message",
    [
        (BoxActionEnv(), r"Unsupported parameterized action space Box\(-1.0, 1.0, \(3,\), float32\)"),
        (DiscreteObsEnv(), r"Unsupported observation space Discrete\(4\): [\w'-]+ policies take a Box observation"),
    ],
)
def test_unsupported_envs(case, env, message):
    with pytest.raises(ValueError, match=message):
        case.make(env)


@algos(ALGO_CLASSES)
@pytest.mark.parametrize("info_keywords", ["distance", ("distance", 3)])
def test_bad_info_keywords(case, info_keywords):
    with pytest.raises(ValueError, match="info_keywords must be a tuple of info keys"):
        case.make(ParameterizedTargetEnv(), info_keywords=info_keywords)


@algos(ALGO_CLASSES)
def test_non_finite_reward_raises(case):
    model = case.make(OneStepEnv(truncate=False, reward=np.nan), seed=0)
    with pytest.raises(ValueError, match=r"non-finite \(NaN or inf\) rewards of lanes \[0\] at timestep 1;"):
        model.learn(300)


def test_every_algorithm_is_in_the_registry():
    """Each algorithm sb3_aac exports runs the feature tests: it has a case in tests.helpers.ALGOS."""
    import sb3_aac
    from stable_baselines3.common.base_class import BaseAlgorithm

    exported = {getattr(sb3_aac, name) for name in sb3_aac.__all__}
    algorithms = {obj for obj in exported if isinstance(obj, type) and issubclass(obj, BaseAlgorithm)}
    assert algorithms == {case.algo for case in ALGOS}
