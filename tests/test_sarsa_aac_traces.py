"""Eligibility traces of SarsaAAC's tile heads: reference lambda-return updates, the lambda=0 identity, episodes, files."""

import numpy as np
import pytest
import torch as th
from hypothesis import given, settings
from hypothesis import strategies as st
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.vec_env import DummyVecEnv

from sb3_aac import SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.sarsa_aac.tile_coding import TileBank, TileTraces
from tests.helpers import OneStepEnv


def chain_kernel(n_outputs: int = 1):
    """One input on [0, 2], one tiling of 2 tiles: observations 0.1, 1.1 and 2.0 activate features 0, 1 and 2."""
    bank = TileBank(np.zeros(1), 2 * np.ones(1), n_outputs, groups=[(0,)], tiles_per_input=2, n_tilings=1)
    kernel = bank.numpy_kernel()
    chain = np.array([[0.1], [1.1], [2.0]])
    np.testing.assert_array_equal(kernel.features(chain), [[0], [1], [2]])
    return kernel, chain


def test_three_step_chain_gets_the_lambda_return_updates():
    """
    Rewards 1, 2, 3 then termination, fixed values V = 0.5, 1.0, 1.5, gamma = 0.9, lambda = 0.5, rate 1 (a step of
    err / 2 with one active feature plus the bias): the TD errors are 1.4, 2.35, 1.5 and each state's feature gets
    half its lambda-return error G^lambda - V, by hand: s0: 3.26125 - 0.5 = 2.76125; s1: 4.025 - 1.0 = 3.025;
    s2: 3 - 1.5 = 1.5. Replacing traces keep the bias (always active) at trace 1: half the summed TD errors.
    """
    kernel, chain = chain_kernel()
    traces = TileTraces(1, 3, np.array([0]), decay=0.9 * 0.5, replacing=True)
    w0, b0 = kernel.w.copy(), kernel.b.copy()
    for obs, delta in zip(chain, [1.4, 2.35, 1.5], strict=True):
        kernel.update_traced(kernel.forward(obs[None])[1], np.array([[delta]]), np.ones(1), np.ones((1, 1)), traces)
    np.testing.assert_allclose(kernel.w[:, 0] - w0[:, 0], [2.76125 / 2, 3.025 / 2, 1.5 / 2], rtol=1e-12)
    np.testing.assert_allclose(kernel.b - b0, [(1.4 + 2.35 + 1.5) / 2], rtol=1e-12)


def test_accumulating_and_replacing_traces_on_a_revisit():
    """s0, s0, s1 with errors 1, 1, 1 and decay 0.45: s0's trace at the third step is 0.45 * (0.45 + 1) accumulating,
    0.45 * 1 replacing; a type's trace on a feature is cleared where another type is chosen (replacing)."""
    kernel, chain = chain_kernel(2)
    expected = {True: 1 + 1 + 0.45, False: 1 + (0.45 + 1) + 0.45 * 1.45}
    for replacing, step_sum in expected.items():
        w0 = kernel.w.copy()
        traces = TileTraces(1, 3, np.array([0]), decay=0.45, replacing=replacing)
        for obs in chain[[0, 0, 1]]:
            kernel.update_traced(kernel.forward(obs[None])[1], np.array([[1.0, 0.0]]), np.ones(2), np.ones((1, 1)), traces)
        np.testing.assert_allclose(kernel.w[0, 0] - w0[0, 0], step_sum / 2, rtol=1e-12)
    traces = TileTraces(1, 3, np.array([0, 1]), decay=0.45, replacing=True)
    cache = kernel.forward(chain[:1])[1]
    kernel.update_traced(cache, np.zeros((1, 2)), np.ones(2), np.array([[1.0, 0.0]]), traces)
    kernel.update_traced(cache, np.zeros((1, 2)), np.ones(2), np.array([[0.0, 1.0]]), traces)
    np.testing.assert_array_equal(traces.trace[0, 0], [0.0, 1.0])
    traces.clear(np.array([0]))
    assert traces.n_live[0] == 0 and not traces.trace.any() and not traces.listed.any()


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(1, 9),
    steps=st.integers(1, 4),
    columns=st.sampled_from([[0], [0, 2], [1, 2], [0, 1, 2]]),
)
def test_lambda_zero_is_the_one_step_update_bit_for_bit(seed, n, steps, columns):
    """Replacing traces with decay 0 (lambda = 0): update_traced changes the weights exactly as update does."""
    rng = np.random.default_rng(seed)
    one_step, traced = (TileBank(-np.ones(3), np.ones(3), 3, tiles_per_input=3, n_tilings=2) for _ in range(2))
    one_step.tile_weight.data.normal_(generator=th.Generator().manual_seed(seed))
    traced.load_state_dict(one_step.state_dict())
    one_step_kernel, traced_kernel = one_step.numpy_kernel(), traced.numpy_kernel()
    traces = TileTraces(n, traced.n_features, np.array(columns), decay=0.0, replacing=True)
    for _ in range(steps):
        obs = rng.uniform(-1.2, 1.2, (n, 3))
        obs[rng.random(n) < 0.5] = obs[0]  # repeated features across lanes
        err, lr = rng.standard_normal((n, 3)), rng.uniform(0.1, 1, 3)
        hit = np.zeros((n, len(columns)))
        hit[:, -1] = 1.0
        err[:, columns[:-1]] *= hit[:, :-1]  # a traced column that is not hit has no error (an unchosen type's Q)
        one_step_kernel.update(one_step_kernel.forward(obs)[1], err, lr)
        traced_kernel.update_traced(traced_kernel.forward(obs)[1], err, lr, hit, traces)
        np.testing.assert_array_equal(traced_kernel.w, one_step_kernel.w)
        np.testing.assert_array_equal(traced_kernel.b, one_step_kernel.b)


def test_traces_end_with_episodes():
    """One-step episodes, lambda = 0.9: a trace surviving an episode's end would drag the other lane's values; the
    values stay those of the one-step case (V = Q = 1 on termination, 2 on a time limit with gamma = 0.5)."""
    env = DummyVecEnv([lambda: OneStepEnv(truncate=False, obs=-0.5), lambda: OneStepEnv(truncate=True, obs=0.5)])
    model = SarsaAAC("TilePolicy", env, gamma=0.5, trace_lambda=0.9, exploration_initial_eps=0.5, seed=0)
    model.learn(4000)
    out, _ = model.policy.evaluate(np.array([[-0.5], [0.5]]))
    np.testing.assert_allclose(out[:, model.policy.value_index], [1.0, 2.0], atol=0.05)
    np.testing.assert_allclose(out[:, model.policy.q_slice], [[1.0, 1.0], [2.0, 2.0]], atol=0.05)


def greedy_return(model):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=1, seed=100)
    return evaluate_policy(model, env, n_eval_episodes=50, deterministic=True)[0]


@pytest.mark.parametrize("replacing", [True, False])
def test_learns_toy_env_with_traces(replacing):
    # The toy env's short run wants bolder steps than the defaults (0.1): 0.3, as in test_sarsa_aac_learning.
    model = SarsaAAC(
        "TilePolicy",
        make_vec_env(ParameterizedTargetEnv, n_envs=4, seed=0),
        learning_rate=0.3,
        q_learning_rate=0.3,
        param_learning_rate=0.3,
        trace_lambda=0.7,
        replacing_traces=replacing,
        seed=0,
    )
    model.learn(20_000)
    assert greedy_return(model) >= 8.5


def test_save_load_with_traces(tmp_path):
    model = SarsaAAC("TilePolicy", make_vec_env(ParameterizedTargetEnv, n_envs=2, seed=0), trace_lambda=0.6, seed=0)
    model.learn(500)
    model.save(tmp_path / "traces.zip")
    loaded = SarsaAAC.load(tmp_path / "traces.zip", env=make_vec_env(ParameterizedTargetEnv, n_envs=2, seed=1))
    assert (loaded.trace_lambda, loaded.replacing_traces) == (0.6, True)
    obs = np.random.default_rng(0).uniform(-1, 1, (50, *model.observation_space.shape))
    np.testing.assert_array_equal(loaded.policy.evaluate(obs)[0], model.policy.evaluate(obs)[0])
    loaded.learn(500)  # fresh traces for the new episodes
    assert loaded._traces is not None and loaded._traces.trace.shape[0] == 2


@pytest.mark.parametrize(
    "policy, kwargs, message",
    [
        ("TilePolicy", dict(trace_lambda=1.5), r"trace_lambda must be in \[0, 1\]"),
        ("TilePolicy", dict(trace_lambda=-0.1), r"trace_lambda must be in \[0, 1\]"),
        ("TilePolicy", dict(trace_lambda="0.5"), r"trace_lambda must be in \[0, 1\]"),
        ("TilePolicy", dict(trace_lambda=0.5, replacing_traces="yes"), "replacing_traces must be True"),
        ("RbfPolicy", dict(trace_lambda=0.5), "needs linear tile heads"),
    ],
)
def test_bad_trace_settings(policy, kwargs, message):
    with pytest.raises(ValueError, match=message):
        SarsaAAC(policy, ParameterizedTargetEnv(), **kwargs)


def test_traces_train_alike_on_the_array_path_and_the_tuple_path():
    """Per-lane traces, cleared where episodes end: the same training whichever way the env is stepped."""
    from tests.test_sarsa_aac_scale_free import ArrayTargetVecEnv, TupleOnly

    weights = []
    for env_class in (ArrayTargetVecEnv, TupleOnly):
        model = SarsaAAC("TilePolicy", env_class(4), trace_lambda=0.8, seed=0, info_keywords=("distance",))
        model.learn(2_000, log_interval=None)
        weights.append(model.policy.approximators.tile_weight.numpy().copy())
    np.testing.assert_array_equal(*weights)
    assert weights[0].any()
