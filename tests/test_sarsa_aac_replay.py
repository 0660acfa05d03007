"""SarsaAAC's replay of recent transitions (``replay_ratio``, :mod:`sb3_aac.sarsa_aac.replay`)."""

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from gymnasium import spaces
from hypothesis import given, settings
from hypothesis import strategies as st
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.save_util import load_from_zip_file

from sb3_aac import SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.sarsa_aac.replay import RecentTransitions
from tests.helpers import POLICIES

SMALL = {"MlpPolicy": dict(hidden_units=4), "RbfMlpPolicy": dict(hidden_units=4)}


def batch(first: int, n: int) -> tuple[np.ndarray, ...]:
    """``n`` transitions numbered ``first, first + 1, ...`` in every field (obs of length 2, one parameter)."""
    ids = np.arange(first, first + n)
    return (
        np.stack([ids, -ids], 1).astype(float),
        ids % 3,
        ids[:, None] / 10.0,
        ids * 1.0,
        ids / 100.0,
        np.stack([ids + 0.5, -ids], 1),
        (ids + 1) % 3,
    )


@settings(max_examples=50, deadline=None)
@given(size=st.integers(1, 8), sizes=st.lists(st.integers(1, 12), max_size=6))
def test_ring_holds_the_last_transitions(size, sizes):
    """After any batches, the buffer holds exactly the last ``min(count, size)`` transitions, each field intact."""
    buffer = RecentTransitions(size, obs_dim=2, n_params=1)
    added = 0
    for n in sizes:
        buffer.add(*batch(added, n))
        added += n
    assert buffer.count == added and len(buffer) == min(added, size)
    held = sorted(buffer.rewards[: len(buffer)].astype(int))
    assert held == list(range(added - len(buffer), added))
    order = np.argsort(buffer.rewards[: len(buffer)])
    for stored, expected in zip(
        (buffer.obs, buffer.types, buffer.params, buffer.rewards, buffer.discounts, buffer.next_obs, buffer.next_types),
        batch(added - len(buffer), len(buffer)),
        strict=True,
    ):
        np.testing.assert_array_equal(stored[: len(buffer)][order], expected)


def test_sample_draws_only_held_transitions_whole():
    buffer = RecentTransitions(10, obs_dim=2, n_params=1)
    buffer.add(*batch(0, 4))
    obs, types, params, rewards, discounts, next_obs, next_types = buffer.sample(500, np.random.default_rng(0))
    assert len(rewards) == 500 and set(rewards.astype(int)) == {0, 1, 2, 3}  # all four, none of the empty rows
    ids = rewards.astype(int)
    np.testing.assert_array_equal(obs[:, 0], ids)
    np.testing.assert_array_equal(types, ids % 3)
    np.testing.assert_array_equal(next_types, (ids + 1) % 3)
    np.testing.assert_array_equal(params[:, 0], ids / 10.0)
    np.testing.assert_array_equal(discounts, ids / 100.0)
    np.testing.assert_array_equal(next_obs[:, 0], ids + 0.5)


@pytest.mark.parametrize("delta", [0.5, -0.5])
def test_replayed_step_by_hand(delta):
    """One replayed transition on linear heads (RbfPolicy, rates 0.3 / 0.4 / 0.5): V(s) moves by 0.3 delta, Q_k(s) by
    0.4 of the SARSA error with the stored k', type k's parameters by 0.5 (x - mu) only where delta > 0, and no other
    output at s moves. The reward is chosen so that the TD error is ``delta``."""
    model = SarsaAAC(
        "RbfPolicy", ParameterizedTargetEnv(), learning_rate=0.3, q_learning_rate=0.4, param_learning_rate=0.5,
        replay_ratio=1, seed=0,
    )  # fmt: skip
    model.learn(64)
    policy = model.policy
    vi, ps = policy.value_index, policy.param_slice
    obs, next_obs = np.array([[0.3, -0.6]]), np.array([[-0.8, 0.9]])
    k, next_k, discount = np.array([1]), np.array([2]), np.array([0.9])
    params = np.array([[0.0, 0.9, -0.4, 0.0, 0.0]])[:, : policy.n_params]
    current, following = policy.evaluate(np.concatenate([obs, next_obs]))[0]
    reward = np.array([delta - 0.9 * following[vi] + current[vi]])
    model._replay_transitions((obs, k, params, reward, discount, next_obs, next_k), chunk=1)
    after = policy.evaluate(obs)[0][0]

    q_error = reward[0] + 0.9 * following[2] - current[1]
    expected = current.copy()
    expected[vi] += 0.3 * delta
    expected[1] += 0.4 * q_error
    if delta > 0:
        expected[ps] += 0.5 * policy.param_table[1, 1] * (params[0] - current[ps])
    np.testing.assert_allclose(after, expected, rtol=1e-10, atol=1e-12)
    moved = np.abs(after[ps] - current[ps]).max()
    assert moved > 0.1 if delta > 0 else moved < 1e-12


class CountingEnv(gym.Env[np.ndarray, Any]):
    """Observation ``(t / 10, 0)`` at step ``t`` of an episode; reward 1; the episode ends after 3 steps, by
    termination if ``terminate`` else by truncation."""

    observation_space = spaces.Box(-1, 1, (2,))
    action_space = spaces.Tuple((spaces.Discrete(2), spaces.Tuple((spaces.Box(-1, 1, (1,)), spaces.Box(-1, 1, (1,))))))

    def __init__(self, terminate: bool = False):
        self.terminate = terminate
        self.t = 0

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self.t = 0
        return np.array([0.0, 0.0], np.float32), {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        self.t += 1
        end = self.t == 3
        return np.array([self.t / 10, 0.0], np.float32), 1.0, end and self.terminate, end and not self.terminate, {}


@pytest.mark.parametrize("terminate", [False, True])
def test_buffer_holds_the_bootstrap_observation(terminate):
    """The stored s' is the one the targets bootstrap from: after a truncation the terminal observation (not the
    reset one) with discount gamma; after a termination the discount is 0."""
    env = make_vec_env(CountingEnv, n_envs=1, env_kwargs=dict(terminate=terminate))
    model = SarsaAAC("RbfPolicy", env, gamma=0.8, replay_ratio=1, info_keywords=(), seed=0)
    model.learn(9)
    buffer = model._replay
    assert buffer is not None and len(buffer) == 9
    np.testing.assert_allclose(buffer.obs[:9, 0], np.tile([0.0, 0.1, 0.2], 3), atol=1e-7)
    # After a termination s' is never read (discount 0): the lane's new episode's first observation is stored.
    np.testing.assert_allclose(buffer.next_obs[:9, 0], np.tile([0.1, 0.2, 0.0 if terminate else 0.3], 3), atol=1e-7)
    last = 0.0 if terminate else 0.8
    np.testing.assert_array_equal(buffer.discounts[:9], np.tile([0.8, 0.8, last], 3))
    np.testing.assert_array_equal(buffer.rewards[:9], 1.0)


@pytest.mark.parametrize("policy", POLICIES)
def test_every_policy_replays(policy):
    """Each env step replays ``replay_ratio`` transitions per lane, and replay changes what the weights learn."""
    env_kwargs = dict(n_envs=3, seed=0)
    weights = {}
    for ratio in (0, 2):
        model = SarsaAAC(policy, make_vec_env(ParameterizedTargetEnv, **env_kwargs), policy_kwargs=SMALL.get(policy),
                         replay_ratio=ratio, seed=1)  # fmt: skip
        replayed: list[int] = []
        if ratio:
            replay = model._replay_transitions

            def counted(transitions, chunk, replay=replay, replayed=replayed):
                replayed.append(len(transitions[1]))
                replay(transitions, chunk)

            model._replay_transitions = counted
        model.learn(300)
        weights[ratio] = model.policy.state_dict()
        if ratio:
            assert replayed == [6] * 100
            assert len(model._replay) == 300
        else:
            assert model._replay is None
    assert any(not th.equal(weights[0][name], weights[2][name]) for name in weights[0])


@pytest.mark.parametrize("policy", ["TilePolicy", "DeepPolicy"])
def test_the_parameter_critic_learns_from_replay(policy):
    """With ``parameter_update="critic"`` the replayed samples also step the critic of the parameters."""
    critics = {}
    for ratio in (0, 1):
        model = SarsaAAC(policy, ParameterizedTargetEnv(), parameter_update="critic", replay_ratio=ratio, seed=2)
        model.learn(200)
        assert model.parameter_critic is not None
        critics[ratio] = model.parameter_critic.state_dict()
    assert any(not th.equal(critics[0][name], critics[1][name]) for name in critics[0] if "obs" not in name)


def test_the_buffer_is_not_saved(tmp_path):
    """The settings are saved, the buffer is not: a loaded model starts it empty and fills it again."""
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), replay_ratio=3, replay_size=50, seed=0)
    model.learn(100)
    model.save(tmp_path / "model.zip")
    data, _, _ = load_from_zip_file(tmp_path / "model.zip")
    assert data is not None and "_replay" not in data
    loaded = SarsaAAC.load(tmp_path / "model.zip", env=ParameterizedTargetEnv())
    assert (loaded.replay_ratio, loaded.replay_size) == (3, 50)
    assert loaded._replay is not None and len(loaded._replay) == 0
    loaded.learn(20)
    assert len(loaded._replay) == 20


@pytest.mark.parametrize("policy", POLICIES)
def test_default_ratio_is_the_policys(policy):
    """Replay is on by default for the MLP families only; an explicit ratio wins."""
    model = SarsaAAC(policy, ParameterizedTargetEnv(), policy_kwargs=SMALL.get(policy))
    assert model.replay_ratio == (2 if policy in ("MlpPolicy", "RbfMlpPolicy") else 0)
    assert SarsaAAC(policy, ParameterizedTargetEnv(), policy_kwargs=SMALL.get(policy), replay_ratio=1).replay_ratio == 1


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (dict(replay_ratio=-1), "replay_ratio must be a whole number"),
        (dict(replay_ratio=1.5), "replay_ratio must be a whole number"),
        (dict(replay_ratio=True), "replay_ratio must be a whole number"),
        (dict(replay_ratio="2"), "replay_ratio must be a whole number"),
        (dict(replay_size=0), "replay_size must be an integer >= 1"),
        (dict(replay_size=2.5), "replay_size must be an integer >= 1"),
    ],
)
def test_bad_values_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), **kwargs)
