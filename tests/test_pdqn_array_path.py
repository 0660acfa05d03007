"""P-DQN steps envs offering the array path with arrays, and learns exactly what it learns through SB3's env.step."""

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import DummyVecEnv

from sb3_aac import MPDQN, PDQN
from sb3_aac.common.array_env import ArrayStep, array_path
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.common.spaces import ParameterizedActionSpec


class ArrayTargetVecEnv(DummyVecEnv):
    """``DummyVecEnv`` of Monitor-wrapped target envs that also offers ``step_arrays`` (built on ``step``)."""

    arrays_stepped = 0

    def step_arrays(self, action_types, params):
        spec = ParameterizedActionSpec.from_space(self.action_space)
        obs, rewards, dones, infos = self.step(spec.to_env(action_types, spec.scale(params)))
        type(self).arrays_stepped += 1
        truncated = np.array([bool(d and i.get("TimeLimit.truncated", False)) for d, i in zip(dones, infos, strict=True)])
        terminal = obs.copy()
        returns, lengths = np.zeros(self.num_envs), np.zeros(self.num_envs, dtype=np.int64)
        info = {key: np.zeros(self.num_envs) for key in ("distance", "ball_lost")}
        for i in np.flatnonzero(dones):
            terminal[i] = infos[i]["terminal_observation"]
            returns[i], lengths[i] = infos[i]["episode"]["r"], infos[i]["episode"]["l"]
            for key in info:
                info[key][i] = infos[i][key]
        return ArrayStep(obs, rewards, dones & ~truncated, truncated, terminal, returns, lengths, info)


def make(with_arrays: bool, seed: int):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=3, seed=seed, env_kwargs=dict(layout="flat", max_episode_steps=6))
    if with_arrays:
        env = ArrayTargetVecEnv([lambda fn=fn: fn for fn in env.envs])
        env.seed(seed)
    return env


@pytest.mark.parametrize("algo", [PDQN, MPDQN])
def test_array_path_matches_sb3_path(algo):
    runs = []
    for with_arrays in (False, True):
        env = make(with_arrays, seed=5)
        assert (array_path(env) is not None) == with_arrays
        model = algo("MlpPolicy", env, seed=5, learning_starts=60, batch_size=16, policy_kwargs=dict(net_arch=[16]))
        before = ArrayTargetVecEnv.arrays_stepped
        model.learn(600)
        assert (ArrayTargetVecEnv.arrays_stepped - before == 200) == with_arrays
        runs.append(model)
    sb3, arrays = runs
    for name in ("observations", "next_observations", "action_types", "params", "rewards", "dones", "timeouts"):
        np.testing.assert_array_equal(getattr(sb3.replay_buffer, name), getattr(arrays.replay_buffer, name), err_msg=name)
    assert sb3.replay_buffer.timeouts.any() and sb3.replay_buffer.dones.any()
    for key, value in sb3.get_parameters()["policy"].items():
        assert th.equal(value, arrays.get_parameters()["policy"][key]), key
    assert [e["r"] for e in sb3.ep_info_buffer] == pytest.approx([e["r"] for e in arrays.ep_info_buffer])
    assert list(sb3._ep_keyword_buffers["distance"]) == pytest.approx(list(arrays._ep_keyword_buffers["distance"]))
