import numpy as np
import pytest
import torch as th
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac import SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import LAYOUTS, POLICIES


@pytest.mark.parametrize("policy", POLICIES)
@pytest.mark.parametrize("layout", LAYOUTS)
def test_predict_single_and_vectorized(policy, layout):
    env = ParameterizedTargetEnv(layout)
    model = SarsaAAC(policy, env, seed=0)
    observations = np.random.default_rng(0).uniform(-1, 1, (6, 2)).astype(np.float32)
    batch, _ = model.predict(observations, deterministic=True)
    assert batch.dtype == object and batch.shape == (6,)
    for obs, batch_action in zip(observations, batch, strict=True):
        single, _ = model.predict(obs, deterministic=True)
        assert isinstance(single, tuple) and env.action_space.contains(single)
        assert env.action_space.contains(batch_action)
        assert repr(single) == repr(batch_action)
    # The greedy action is the argmax of the Q outputs and the clipped parameter outputs, as computed by torch.
    with th.no_grad():
        out = model.policy(th.as_tensor(observations)).numpy()
    k = out[:, model.policy.q_slice].argmax(1)
    assert [a[0] for a in batch] == k.tolist()
    expected = model.policy.spec.to_env(k, np.clip(out[:, model.policy.param_slice], -1, 1))
    assert repr(list(expected)) == repr(list(batch))


def test_predict_in_vec_env():
    env = make_vec_env(ParameterizedTargetEnv, n_envs=3, seed=0)
    model = SarsaAAC("RbfPolicy", env, seed=0)
    obs = env.reset()
    for _ in range(15):
        actions, _ = model.predict(obs)
        obs, _, _, _ = env.step(actions)


def test_policy_predict_matches_model_predict_and_device():
    model = SarsaAAC("RbfMlpPolicy", ParameterizedTargetEnv(), seed=0, device="cpu")
    assert model.device.type == "cpu" and model.policy.device.type == "cpu"
    obs = np.array([0.1, -0.4], np.float32)
    assert repr(model.policy.predict(obs)[0]) == repr(model.predict(obs, deterministic=True)[0])
    with pytest.raises(NotImplementedError, match="use predict"):
        model.policy._predict(th.zeros(1, 2))
