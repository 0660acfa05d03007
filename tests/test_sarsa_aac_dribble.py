"""SarsaAAC on the RoboCup dribbling env: the env's spaces, VecEnv and info keys work with the algorithm."""

import numpy as np
import pytest

from sb3_aac import SarsaAAC

robocup_dribble = pytest.importorskip("robocup_dribble")


@pytest.mark.parametrize("policy", ["RbfPolicy", "MlpPolicy"])
def test_dribble_smoke(tmp_path, policy):
    env = robocup_dribble.DribbleVecEnv(4, profile="v11")
    model = SarsaAAC(policy, env, seed=0)
    assert model.policy.n_types == 4 and model.policy.n_params == 7  # the paper's 4 approximators + 7 + 1 critic
    model.learn(2000)
    distances = model._ep_keyword_buffers["distance"]
    assert len(distances) > 0 and len(model._ep_keyword_buffers["ball_lost"]) == len(distances)
    obs = env.reset()
    actions, _ = model.predict(obs, deterministic=True)
    assert all(env.action_space.contains(action) for action in actions)
    model.save(tmp_path / "dribble.zip")
    loaded = SarsaAAC.load(tmp_path / "dribble.zip", env=env)
    np.testing.assert_array_equal([a[0] for a in loaded.predict(obs, deterministic=True)[0]], [a[0] for a in actions])


def test_dribble_single_env_by_id():
    model = SarsaAAC("RbfPolicy", "RoboCupDribblePaper-v0", seed=0)
    model.learn(200)
    obs, _ = model.get_env().envs[0].reset(seed=0)
    action, _ = model.predict(obs, deterministic=True)
    assert model.action_space.contains(action)
