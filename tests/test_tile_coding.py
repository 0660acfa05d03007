"""Tile coding: the grids, the normalised batch update, and an interaction (XOR) that per-input features cannot learn."""

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from gymnasium import spaces
from stable_baselines3.common.env_util import make_vec_env

from sb3_aac import SarsaAAC
from sb3_aac.sarsa_aac.tile_coding import TileBank, default_tile_groups, tile_layout


def test_layout_and_active_features():
    layout = tile_layout([(0,), (0, 1)], tiles_per_input=2, n_tilings=2)
    # Single input: 3 tiles per tiling; pair: 9 per tiling.
    np.testing.assert_array_equal(layout.bases, [0, 3, 6, 15])
    assert layout.n_features == 24
    np.testing.assert_allclose(layout.offsets, [[0, 0], [0.5, 0], [0, 0], [0.5, 0.5]])  # (2j + 1) / 2 mod 1
    bank = TileBank(np.array([0.0, 0.0]), np.array([4.0, 4.0]), 1, groups=[(0,), (0, 1)], tiles_per_input=2, n_tilings=2)
    active = bank.numpy_kernel().features(np.array([[0.0, 0.0], [3.0, 1.0], [4.0, 4.0], [9.0, -9.0]]))
    # x=3 of [0, 4] is at 1.5 tiles; tiling 1 shifts by half a tile: 2. y=1 is at 0.5 (+0.5 -> 1).
    np.testing.assert_array_equal(active[1], [1, 3 + 2, 6 + 1 + 3 * 0, 15 + 2 + 3 * 1])
    np.testing.assert_array_equal(active[2], [2, 3 + 2, 6 + 2 + 3 * 2, 15 + 2 + 3 * 2])  # the high corner
    np.testing.assert_array_equal(active[3], [2, 3 + 2, 6 + 2, 15 + 2])  # outside: the edge tiles
    assert default_tile_groups(3) == [(0,), (1,), (2,), (0, 1), (0, 2), (1, 2)]


@pytest.mark.parametrize("n", [1, 64])
def test_rate_one_lands_identical_samples_on_target(n):
    """One sample, or n copies of it: a rate of 1 lands on the target, not n times past (the copies are taken in turn)."""
    bank = TileBank(-np.ones(3), np.ones(3), 2)
    kernel = bank.numpy_kernel()
    obs = np.tile([[0.3, -0.2, 0.9]], (n, 1))
    out, cache = kernel.forward(obs)
    kernel.update(cache, np.tile([[1.0, -3.0]], (n, 1)), np.ones(2))
    np.testing.assert_allclose(kernel.forward(obs[:1])[0], out[:1] + np.array([[1.0, -3.0]]), atol=1e-12)


def test_bad_arguments():
    for kwargs, message in [
        (dict(groups=[(0, 5)]), r"distinct input indices in \[0, 3\)"),
        (dict(groups="pairs"), "non-empty list of tuples"),
        (dict(tiles_per_input=0), "tiles_per_input must be an int >= 1"),
        (dict(n_tilings=1.5), "n_tilings must be an int >= 1"),
    ]:
        with pytest.raises(ValueError, match=message):
            TileBank(-np.ones(3), np.ones(3), 2, **kwargs)
    with pytest.raises(ValueError, match="finite low < high"):
        TileBank(np.array([-np.inf, 0.0]), np.ones(2), 2)


class XorEnv(gym.Env):
    """One-step episodes: type 1 is right where ``a * b > 0``, type 0 elsewhere (reward 1 if right, else 0)."""

    observation_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
    action_space = spaces.Tuple((spaces.Discrete(2), spaces.Tuple((spaces.Box(-1, 1, (1,)), spaces.Box(-1, 1, (1,))))))

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self._obs = self.np_random.uniform(-1, 1, 2).astype(np.float32)
        return self._obs, {}

    def step(self, action):
        right = int(self._obs[0] * self._obs[1] > 0)
        reward = float(int(action[0]) == right)
        return self.reset()[0], reward, True, False, {}


def xor_accuracy(policy: str) -> float:
    model = SarsaAAC(policy, make_vec_env(XorEnv, n_envs=8, seed=0), seed=0, q_learning_rate=0.5, info_keywords=())
    model.learn(20_000)
    obs = np.random.default_rng(1).uniform(-1, 1, (2000, 2))
    q = model.policy.evaluate(obs)[0][:, model.policy.q_slice]
    return float((q.argmax(1) == (obs[:, 0] * obs[:, 1] > 0)).mean())


def test_interaction_learned_by_tiles_not_by_per_input_rbfs():
    assert xor_accuracy("TilePolicy") >= 0.95
    # Additive features: the best a sum of per-input functions does on XOR is chance level plus edge effects.
    assert xor_accuracy("RbfPolicy") <= 0.7


def test_save_load_keeps_the_grid(tmp_path):
    model = SarsaAAC("TilePolicy", XorEnv(), policy_kwargs=dict(tile_groups=[(0, 1)], tiles_per_input=3), seed=0)
    model.learn(200)
    model.save(tmp_path / "tiles.zip")
    loaded = SarsaAAC.load(tmp_path / "tiles.zip")
    assert loaded.policy.approximators.groups == [(0, 1)] and loaded.policy.approximators.n_features == 16 * 8
    obs = np.random.default_rng(0).uniform(-1, 1, (100, 2))
    np.testing.assert_array_equal(loaded.policy.evaluate(obs)[0], model.policy.evaluate(obs)[0])
    assert loaded.policy.approximators.tile_inputs.dtype == th.int64


def test_compiled_training_pass_equals_the_runtime_forward_pass():
    """Training's numba loops give the very tiles and outputs of runtime.TileForward (numpy), on 5,000 observations."""
    from sb3_aac.runtime.forward import TileForward

    bank = TileBank(np.array([-1.0, 0.0, -5.0]), np.array([1.0, 2.0, 5.0]), 4)
    with th.no_grad():
        bank.tile_weight.normal_()
    kernel = bank.numpy_kernel()
    reference = TileForward(**bank.arrays())
    obs = np.random.default_rng(2).uniform([-1.5, -0.5, -6.0], [1.5, 2.5, 6.0], (5000, 3))
    np.testing.assert_array_equal(kernel.features(obs), reference.features(obs))
    np.testing.assert_array_equal(kernel.forward(obs)[0], reference.outputs(reference.features(obs))[0])
