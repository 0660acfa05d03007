"""Step sizes that mean the same whatever the reward's units and the number of lanes; validation; divergence."""

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.monitor import Monitor
from stable_baselines3.common.vec_env import DummyVecEnv

from sb3_aac import SarsaAAC
from sb3_aac.common.array_env import ArrayStep
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.common.spaces import ParameterizedActionSpec
from tests.helpers import POLICIES, OneStepEnv, PoisonWeights

OBS = np.random.default_rng(5).uniform(-1, 1, (2000, 2))


def scaled_reward_env(scale: float, n_envs: int = 4):
    scaled = dict(wrapper_class=gym.wrappers.TransformReward, wrapper_kwargs=dict(func=lambda r: r * scale))
    return make_vec_env(ParameterizedTargetEnv, n_envs=n_envs, seed=0, **scaled)


def greedy(model):
    out, _ = model.policy.evaluate(OBS)
    return out[:, model.policy.q_slice].argmax(1), out[:, model.policy.param_slice]


@pytest.mark.parametrize("policy", POLICIES)
def test_reward_units_do_not_change_greedy_behaviour(policy):
    models = {}
    for scale in (0.02, 50.0):
        models[scale] = SarsaAAC(policy, scaled_reward_env(scale), seed=0, learning_rate=0.3, q_learning_rate=0.3)
        models[scale].learn(4_000)
    (types_small, params_small), (types_large, params_large) = greedy(models[0.02]), greedy(models[50.0])
    assert (types_small == types_large).mean() >= 0.99
    np.testing.assert_allclose(params_small, params_large, atol=1e-6)
    assert models[50.0].return_scale == pytest.approx(2500 * models[0.02].return_scale, rel=1e-6)  # float32 rewards


class ArrayTargetVecEnv(DummyVecEnv):
    """A fake array env: the toy env's lanes, also offering ``step_arrays`` (built on the tuple step)."""

    def __init__(self, n_envs: int, seed: int = 0):
        super().__init__([lambda: Monitor(ParameterizedTargetEnv(check_action=False))] * n_envs)
        self.seed(seed)
        self.spec = ParameterizedActionSpec.from_space(self.action_space)
        self.array_steps = 0

    def step_arrays(self, action_types, params):
        self.array_steps += 1
        assert np.isfinite(params).all()
        obs, rewards, dones, infos = self.step(self.spec.to_env(action_types, self.spec.scale(params)))
        truncated = np.array([info.get("TimeLimit.truncated", False) for info in infos])
        ended = [i for i in range(len(infos)) if dones[i]]
        terminal = obs.copy()
        for i in ended:
            terminal[i] = infos[i]["terminal_observation"]
        return ArrayStep(
            obs,
            rewards,
            dones & ~truncated,
            truncated,
            terminal,
            np.array([infos[i]["episode"]["r"] if dones[i] else 0.0 for i in range(len(infos))]),
            np.array([infos[i]["episode"]["l"] if dones[i] else 0 for i in range(len(infos))]),
            {"distance": np.array([info.get("distance", 0.0) for info in infos])},
        )


class TupleOnly(ArrayTargetVecEnv):
    step_arrays = None  # hides the array path


def test_array_path_trains_like_the_tuple_path():
    params = {}
    for env_class in (ArrayTargetVecEnv, TupleOnly):
        env = env_class(4)
        model = SarsaAAC("RbfPolicy", env, seed=0, info_keywords=("distance",))
        model.learn(2_000, log_interval=None)
        params[env_class] = model.policy.approximators.weight.numpy().copy()
        if env_class is ArrayTargetVecEnv:
            assert env.array_steps == 500
            assert len(model._ep_keyword_buffers["distance"]) > 0
    np.testing.assert_array_equal(params[ArrayTargetVecEnv], params[TupleOnly])


@pytest.mark.parametrize("policy", POLICIES)
def test_many_lanes_do_not_diverge(policy):
    """512 lanes learning in lock-step (summed steps diverged at 256 before the batch normalisation)."""
    model = SarsaAAC(policy, ArrayTargetVecEnv(512), seed=0, learning_rate=1.0, q_learning_rate=1.0, param_learning_rate=1.0)
    model.learn(512 * 100, log_interval=None)
    out, _ = model.policy.evaluate(OBS)
    assert np.isfinite(out).all()
    assert np.abs(out[:, model.policy.value_index]).max() < 50  # the optimal return is 10


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(learning_rate=-1.0), r"learning_rate must be in \[0, 1\]"),
        (dict(q_learning_rate=1.5), r"q_learning_rate must be in \[0, 1\]"),
        (dict(param_learning_rate=lambda p: 2 * p - 0.5), r"param_learning_rate must be in \[0, 1\].*from 1.5 to -0.5"),
        (dict(learning_rate=float("nan")), r"learning_rate must be in \[0, 1\]"),
        (dict(gamma="0.9"), "gamma must be in"),
        (dict(param_noise_final=float("inf")), "param_noise_final must be a finite number >= 0"),
        (dict(info_keywords="distance"), r"info_keywords must be a tuple .* \('distance',\)"),
    ],
)
def test_bad_hyperparameters(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), **kwargs)


def test_predict_rejects_non_finite_observations():
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), seed=0)
    for obs in (np.array([np.nan, 0.0]), np.array([[0.0, 0.0], [np.inf, 0.0]])):
        for deterministic in (True, False):
            with pytest.raises(ValueError, match="NaN or inf"):
                model.predict(obs, deterministic=deterministic)


@pytest.mark.parametrize("policy", POLICIES)
def test_divergence_restores_finite_weights(tmp_path, policy):
    model = SarsaAAC(policy, OneStepEnv(truncate=False), seed=0)
    with pytest.raises(FloatingPointError, match=r"diverged: the weights of .* restored to those of timestep 768"):
        model.learn(5_000, log_interval=None, callback=PoisonWeights(1_000))
    weights = model.get_parameters()["policy"]
    assert all(np.isfinite(w.numpy()).all() for w in weights.values())
    model.save(tmp_path / "model.zip")
    loaded = SarsaAAC.load(tmp_path / "model.zip")
    action, _ = loaded.predict(np.zeros(1, np.float32), deterministic=True)
    assert np.isfinite(action[1]).all()


def test_return_scale_survives_save_load(tmp_path):
    model = SarsaAAC("MlpPolicy", scaled_reward_env(50.0, n_envs=2), seed=0)
    model.learn(500)
    model.save(tmp_path / "model.zip")
    loaded = SarsaAAC.load(tmp_path / "model.zip", env=scaled_reward_env(50.0, n_envs=2))
    assert loaded.return_scale == model.return_scale > 0
    before = loaded.policy.approximators.weight2.clone()
    loaded.learn(2, reset_num_timesteps=False)  # one step: a small change, not a rescale by return_scale
    assert (loaded.policy.approximators.weight2 - before).abs().max() < 0.5 * before.abs().max()
