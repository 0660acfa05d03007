"""P-DQN / MP-DQN's own save/load (the replay buffer, the number of passes) and bit-identical reruns; the contract
every algorithm shares is in test_save_load.py."""

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac import MPDQN, PDQN, SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.pdqn.buffers import ParameterizedReplayBuffer
from tests.helpers import LAYOUTS, PDQN_SMALL


@pytest.mark.parametrize("algo", [PDQN, MPDQN])
@pytest.mark.parametrize("layout", LAYOUTS)
def test_save_load_replay_buffer(tmp_path, algo, layout):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=2, env_kwargs=dict(layout=layout))
    model = algo("MlpPolicy", env, seed=1, **PDQN_SMALL)
    model.learn(300)
    assert set(model.get_parameters()) == {"policy", "policy.q_optimizer", "policy.actor_optimizer"}
    model.save(tmp_path / "model.zip")
    model.save_replay_buffer(tmp_path / "buffer.pkl")
    loaded = algo.load(tmp_path / "model.zip", env=env)
    assert loaded.num_timesteps == 300 and loaded.replay_buffer.size() == 0

    loaded.load_replay_buffer(tmp_path / "buffer.pkl")
    assert loaded.replay_buffer.size() == model.replay_buffer.size() == 150
    for name in ("observations", "next_observations", "action_types", "params", "rewards", "dones", "timeouts"):
        np.testing.assert_array_equal(getattr(loaded.replay_buffer, name), getattr(model.replay_buffer, name))
    loaded.learn(100, reset_num_timesteps=False)
    assert loaded.num_timesteps == 400 and loaded.replay_buffer.size() == 200


def test_replay_buffer_from_other_spaces_is_rejected(tmp_path):
    model = PDQN("MlpPolicy", ParameterizedTargetEnv(layout="nested"), seed=0, **PDQN_SMALL)
    model.learn(60)
    model.save_replay_buffer(tmp_path / "buffer.pkl")
    other = PDQN("MlpPolicy", ParameterizedTargetEnv(layout="nested", n_types=2), seed=0, **PDQN_SMALL)
    kept = other.replay_buffer
    with pytest.raises(ValueError, match="replay buffer holds transitions of observation space"):
        other.load_replay_buffer(tmp_path / "buffer.pkl")
    assert other.replay_buffer is kept  # nothing half-loaded
    two_envs = PDQN("MlpPolicy", make_vec_env(ParameterizedTargetEnv, n_envs=2), seed=0, **PDQN_SMALL)
    with pytest.raises(ValueError, match="filled by 1 environments, but the model has 2"):
        two_envs.load_replay_buffer(tmp_path / "buffer.pkl")
    from stable_baselines3.common.save_util import save_to_pkl

    save_to_pkl(tmp_path / "other.pkl", {"not": "a buffer"})
    with pytest.raises(ValueError, match="not a ParameterizedReplayBuffer"):
        model.load_replay_buffer(tmp_path / "other.pkl")


def test_load_other_algorithm_is_rejected(tmp_path):
    SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), seed=0).save(tmp_path / "sarsa.zip")
    with pytest.raises(ValueError, match="needs a PDQNPolicy"):
        PDQN.load(tmp_path / "sarsa.zip")
    MPDQN("MlpPolicy", ParameterizedTargetEnv(), seed=0).save(tmp_path / "mpdqn.zip")
    with pytest.raises(ValueError, match=r"multi-pass Q network: load it with MPDQN\.load"):
        PDQN.load(tmp_path / "mpdqn.zip")
    PDQN("MlpPolicy", ParameterizedTargetEnv(), seed=0).save(tmp_path / "pdqn.zip")
    with pytest.raises(ValueError, match=r"single-pass Q network: load it with PDQN\.load"):
        MPDQN.load(tmp_path / "pdqn.zip")
    assert MPDQN.load(tmp_path / "mpdqn.zip").policy.multi_pass


def run(algo, layout, seed, n_envs=2):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=n_envs, env_kwargs=dict(layout=layout))
    model = algo("MlpPolicy", env, seed=seed, exploration_initial_eps=0.5, **PDQN_SMALL)
    model.learn(300)
    env.seed(seed)
    obs, rewards = env.reset(), []
    for _ in range(10):
        actions, _ = model.predict(obs, deterministic=False)
        obs, reward, _, _ = env.step(actions)
        rewards.append(reward)
    return model.get_parameters(), np.array(rewards), model.replay_buffer.params[: model.replay_buffer.size()].copy()


@pytest.mark.parametrize("algo", [PDQN, MPDQN])
@pytest.mark.parametrize("layout", ["nested", "oneof"])
def test_deterministic_reruns(algo, layout):
    params_1, rewards_1, buffer_1 = run(algo, layout, 3)
    params_2, rewards_2, buffer_2 = run(algo, layout, 3)
    for key in params_1["policy"]:
        assert th.equal(params_1["policy"][key], params_2["policy"][key]), key  # bit-identical
    np.testing.assert_array_equal(rewards_1, rewards_2)
    np.testing.assert_array_equal(buffer_1, buffer_2)
    params_3, _, _ = run(algo, layout, 4)
    assert not all(th.equal(params_1["policy"][k], params_3["policy"][k]) for k in params_1["policy"])


class TestReplayBuffer:
    @staticmethod
    def buffer(**kwargs):
        env = ParameterizedTargetEnv(layout="shared")
        return ParameterizedReplayBuffer(8, env.observation_space, env.action_space, device="cpu", **kwargs)

    def test_stores_type_and_full_scaled_params_per_env(self):
        buffer = self.buffer(n_envs=2)
        assert buffer.buffer_size == 4 and buffer.params.shape == (4, 2, 6)  # shared: each type owns a copy of Box(2)
        obs = np.array([[0.1, 0.2], [0.3, 0.4]], np.float32)
        params = np.linspace(-1, 1, 12).reshape(2, 6)
        buffer.add(
            obs, -obs, np.array([0, 2]), params, np.array([1.0, 2.0]), np.array([False, True]), np.array([False, False])
        )
        np.testing.assert_array_equal(buffer.action_types[0], [0, 2])
        np.testing.assert_allclose(buffer.params[0], params, rtol=1e-6)
        np.testing.assert_array_equal(buffer.next_observations[0], -obs)
        batch = buffer.sample(200, np.random.default_rng(0))
        assert batch.params.shape == (200, 6) and batch.action_types.dtype == th.int64
        assert set(batch.rewards.tolist()) == {1.0, 2.0}
        assert th.all(batch.dones == (batch.rewards == 2.0).float())

    @pytest.mark.parametrize("handle", [True, False])
    def test_timeouts(self, handle):
        buffer = self.buffer(handle_timeout_termination=handle)
        for truncated in (True, False):
            buffer.add(
                np.zeros(2),
                np.ones(2),
                np.array([1]),
                np.zeros((1, 6)),
                np.array([float(truncated)]),
                np.array([True]),
                np.array([truncated]),
            )
        batch = buffer.sample(100, np.random.default_rng(0))
        timed_out = batch.rewards == 1.0
        assert th.all(batch.dones[~timed_out] == 1)
        assert th.all(batch.dones[timed_out] == (0.0 if handle else 1.0))

    def test_memory_efficient_matches_regular(self):
        regular = self.buffer(handle_timeout_termination=False)
        compact = self.buffer(handle_timeout_termination=False, optimize_memory_usage=True)
        assert compact.next_observations is None
        rng = np.random.default_rng(1)
        obs = rng.uniform(-1, 1, (1, 2)).astype(np.float32)
        for step in range(13):  # wraps around the 8 rows
            next_obs = rng.uniform(-1, 1, (1, 2)).astype(np.float32)
            args = (
                obs,
                next_obs,
                np.array([step % 3]),
                rng.uniform(-1, 1, (1, 6)),
                np.array([float(step)]),
                np.array([False]),
                np.array([False]),
            )
            regular.add(*args)
            compact.add(*args)
            obs = next_obs
        batch = compact.sample(500, np.random.default_rng(2))
        sampled_steps = set(batch.rewards.long().tolist())
        assert sampled_steps == set(range(6, 13))  # the oldest row (step 5) lost its observation
        for i in range(500):
            row = int(batch.rewards[i]) % 8
            np.testing.assert_array_equal(batch.next_observations[i], regular.next_observations[row, 0])
            np.testing.assert_array_equal(batch.observations[i], regular.observations[row, 0])

    def test_bad_arguments(self):
        with pytest.raises(ValueError, match="cannot be combined"):
            self.buffer(optimize_memory_usage=True)
        with pytest.raises(ValueError, match="buffer_size and n_envs must be whole numbers >= 1"):
            self.buffer(n_envs=0)
        env = ParameterizedTargetEnv()
        with pytest.raises(ValueError, match="stores Box observations"):
            ParameterizedReplayBuffer(8, env.action_space, env.action_space)
