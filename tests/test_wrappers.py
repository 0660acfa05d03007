import re
import textwrap
import warnings

import gymnasium as gym
import numpy as np
import pytest
import torch as th
from gymnasium import spaces
from tests.helpers import LAYOUTS
from hypothesis import given, settings
from hypothesis import strategies as st
from stable_baselines3 import A2C, DDPG, DQN, PPO, SAC, TD3
from stable_baselines3.common.env_checker import check_env
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

import sb3_aac
from sb3_aac import DiscretizeParameterizedAction, FlattenParameterizedAction
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.wrappers import (
    action_to_grid,
    action_to_scores,
    grid_size,
    grid_to_action,
    make_grid,
    scores_to_action,
)


@pytest.fixture(autouse=True)
def one_torch_thread():
    # Tiny networks: a second thread only adds contention on a 2-core machine
    threads = th.get_num_threads()
    th.set_num_threads(1)
    yield
    th.set_num_threads(threads)


WRAPPERS = [FlattenParameterizedAction, DiscretizeParameterizedAction]
# Float64 bounds for which mid - half * 1 or mid + half * 1 is not the bound itself
AWKWARD_LOW = np.array([0.1, -0.3, 0.2, 1 / 3, -1.1, 0.15])
AWKWARD_HIGH = np.array([0.7, 0.9, 0.9, 2.0, 0.3, 0.45])


class SpaceEnv(gym.Env):
    """Any action space; checks each action is in it and records it."""

    def __init__(self, action_space: spaces.Space):
        self.action_space = action_space
        self.observation_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.last_action = None

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(1, np.float32), {}

    def step(self, action):
        assert self.action_space.contains(action), action
        self.last_action = action
        return np.zeros(1, np.float32), 0.0, False, False, {}


def type_params(spec: ParameterizedActionSpec, action) -> tuple[int, np.ndarray]:
    """Env type (0-based) and the chosen type's parameters (env units, flattened) of an env action."""
    if spec.layout == "oneof":
        return action[0], np.ravel(action[1])
    k = action[0] - spec.start
    if spec.layout == "shared":
        return k, np.ravel(action[1])
    values = action[1] if spec.layout == "nested" else action[1:]
    return k, np.ravel(values[k])


# --------------------------------------------------------------------------------------------------------------------
# Flatten
# --------------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("layout", LAYOUTS)
def test_flatten_space(layout):
    inner = ParameterizedTargetEnv(layout)
    env = FlattenParameterizedAction(inner)
    n_params = 6 if layout == "shared" else 5  # shared: each of the 3 types has its own copy of the Box(2)
    assert env.action_space == spaces.Box(-1.0, 1.0, (3 + n_params,), np.float32)
    assert env.observation_space == inner.observation_space
    assert env.action_spec.n_params == n_params


@pytest.mark.parametrize("layout", LAYOUTS)
def test_flatten_round_trips(layout):
    env = FlattenParameterizedAction(ParameterizedTargetEnv(layout))
    spec = env.action_spec
    env.unwrapped.action_space.seed(0)
    env.action_space.seed(0)
    for _ in range(50):
        # env action -> flat -> env action: same type, same parameters of that type (all of them when nested/flat)
        original = env.unwrapped.action_space.sample()
        flat = env.reverse_action(original)
        assert env.action_space.contains(flat)
        assert np.sum(flat[:3] == 1.0) == 1 and np.sum(flat[:3] == -1.0) == 2
        back = env.action(flat)
        assert env.unwrapped.action_space.contains(back)
        k0, p0 = type_params(spec, original)
        k1, p1 = type_params(spec, back)
        assert k1 == k0
        np.testing.assert_allclose(p1, p0, rtol=1e-6, atol=1e-6)
        if layout in ("nested", "flat"):  # the env receives every type's parameters: all of them survive
            np.testing.assert_allclose(spec.from_env([back])[1], spec.from_env([original])[1], atol=1e-6)
        # flat -> env action -> flat -> env action: the same env action
        flat = env.action_space.sample()
        action = env.action(flat)
        again = env.action(env.reverse_action(action))
        assert again[0] == action[0]
        np.testing.assert_allclose(type_params(spec, again)[1], type_params(spec, action)[1], rtol=1e-6)


def test_flatten_decodes_argmax_with_ties_to_lowest_index():
    env = FlattenParameterizedAction(ParameterizedTargetEnv("oneof"))
    params = np.zeros(5, np.float32)
    cases = [([0.3, 0.9, 0.9], 1), ([0.5, 0.5, 0.5], 0), ([-0.9, -0.8, -0.95], 1), ([-1, -1, 1], 2), ([0, 0, 0], 0)]
    for scores, expected in cases:
        assert env.action(np.concatenate([np.array(scores, np.float32), params]))[0] == expected, scores
    # The pure function, batched, scores outside [-1, 1] too
    k, _ = scores_to_action(np.array([[2.0, 2.0, 5.0], [7.0, 7.0, -3.0], [-3.0, 0.0, 0.0]]), 3)
    np.testing.assert_array_equal(k, [2, 0, 1])


def test_flatten_runs_the_chosen_types_parameters():
    env = FlattenParameterizedAction(ParameterizedTargetEnv("nested"))
    # type 1 (bounds [0, 1] x [0, 10]) with scaled (0, 0.5): the middle of the first, 3/4 of the second
    flat = np.array([0.0, 1.0, 0.0, -1.0, 0.0, 0.5, 0.2, 0.2], np.float32)
    k, values = env.action(flat)
    assert k == 1
    np.testing.assert_allclose(values[1], [0.5, 7.5])
    np.testing.assert_allclose(values[0], [-2.0])
    oneof = FlattenParameterizedAction(ParameterizedTargetEnv("oneof")).action(flat)
    assert oneof[0] == 1
    np.testing.assert_allclose(oneof[1], [0.5, 7.5])


@pytest.mark.parametrize("layout", LAYOUTS)
def test_flatten_unscaling_hits_bounds_exactly_and_clips(layout):
    env = FlattenParameterizedAction(ParameterizedTargetEnv(layout))
    spec = env.action_spec
    for k in range(3):
        box = spec.boxes[k]
        for value, bound in ((1.0, box.high), (5.0, box.high), (-1.0, box.low), (-5.0, box.low)):
            flat = np.zeros(env.action_space.shape, np.float32)
            flat[k] = 1.0
            flat[3:] = value
            action = env.action(flat)
            assert action[0] == k
            assert type_params(spec, action)[1].tolist() == bound.ravel().tolist()


def test_flatten_unscaling_hits_awkward_float64_bounds_exactly():
    box = spaces.Box(AWKWARD_LOW, AWKWARD_HIGH, dtype=np.float64)
    env = FlattenParameterizedAction(SpaceEnv(spaces.Tuple((spaces.Discrete(2, start=4), box))))
    high = env.action(np.array([0, 1] + [1.0] * 12, np.float32))
    low = env.action(np.array([0, 1] + [-1.0] * 12, np.float32))
    assert high[0] == 5 and low[0] == 5
    assert high[1].tolist() == AWKWARD_HIGH.tolist()
    assert low[1].tolist() == AWKWARD_LOW.tolist()


def test_score_functions():
    k = np.array([2, 0, 1])
    params = np.array([[0.5, -2.0], [0.0, 0.25], [1.5, -1.0]])
    flat = action_to_scores(k, params, 3)
    assert flat.dtype == np.float32 and flat.shape == (3, 5)
    np.testing.assert_array_equal(flat[:, :3], [[-1, -1, 1], [1, -1, -1], [-1, 1, -1]])
    k_back, params_back = scores_to_action(flat, 3)
    np.testing.assert_array_equal(k_back, k)
    np.testing.assert_array_equal(params_back, np.clip(params, -1, 1))
    with pytest.raises(ValueError, match="NaN"):
        scores_to_action(np.array([[0.0, np.nan, 0.0]]), 2)
    with pytest.raises(ValueError, match="shape"):
        scores_to_action(np.zeros(5), 3)
    with pytest.raises(ValueError, match="out of range"):
        action_to_scores(np.array([3]), np.zeros((1, 2)), 3)


def test_flatten_rejects_wrong_shape():
    env = FlattenParameterizedAction(ParameterizedTargetEnv("nested"))
    with pytest.raises(ValueError, match=re.escape("shape (8,)")):
        env.step(np.zeros(7, np.float32))


# --------------------------------------------------------------------------------------------------------------------
# Discretize
# --------------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "layout, bins, size",
    [
        ("nested", 3, 3 + 9 + 9),
        ("flat", 2, 2 + 4 + 4),
        ("oneof", (5, 2, 3, 1, 4), 5 + 6 + 4),
        ("shared", 3, 9 + 9 + 9),  # type 0 owns both shared coordinates though the env reads only the first
        ("shared", (3, 1, 3, 3, 3, 3), 3 + 9 + 9),
    ],
)
def test_discretize_table_size(layout, bins, size):
    inner = ParameterizedTargetEnv(layout)
    env = DiscretizeParameterizedAction(inner, bins=bins)
    assert env.action_space == spaces.Discrete(size)
    assert env.observation_space == inner.observation_space
    assert env.types.shape == (size,) and env.params_scaled.shape == (size, env.action_spec.n_params)
    assert grid_size(env.action_spec.dims, bins) == size
    assert sum(env.type_sizes) == size
    np.testing.assert_array_equal(np.bincount(env.types), env.type_sizes)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_discretize_grid_includes_both_ends(layout):
    env = DiscretizeParameterizedAction(ParameterizedTargetEnv(layout), bins=3)
    spec = env.action_spec
    for k in range(3):
        box = spec.boxes[k]
        params = np.array([type_params(spec, env.action(i))[1] for i in range(env.action_space.n) if env.types[i] == k])
        assert len(params) == 3 ** spec.dims[k]
        assert len({tuple(p) for p in params}) == len(params)  # no duplicates
        for j in range(spec.dims[k]):
            low, high = box.low.ravel()[j], box.high.ravel()[j]
            assert sorted(set(params[:, j].tolist())) == [low, (low + high) / 2, high]
            assert (params[:, j] == low).sum() == 3 ** (spec.dims[k] - 1)


def test_discretize_awkward_float64_bounds_and_start():
    box = spaces.Box(AWKWARD_LOW[:2], AWKWARD_HIGH[:2], dtype=np.float64)
    inner = SpaceEnv(spaces.Tuple((spaces.Discrete(2, start=4), spaces.Tuple((box, box)))))
    env = DiscretizeParameterizedAction(inner, bins=2)
    assert env.action_space.n == 8
    assert env.action(0)[0] == 4 and env.action(7)[0] == 5
    assert env.action(4)[1][1].tolist() == AWKWARD_LOW[:2].tolist()
    assert env.action(7)[1][1].tolist() == AWKWARD_HIGH[:2].tolist()
    assert env.describe(5) == "action 5: type 5, parameters [0.1, 0.9]"


def test_discretize_describe_and_order():
    env = DiscretizeParameterizedAction(ParameterizedTargetEnv("nested"), bins=3)
    assert env.describe(0) == "action 0: type 0, parameters [-2]"
    assert env.describe(2) == "action 2: type 0, parameters [2]"
    # type 1 ([0, 1] x [0, 10]): its last parameter varies fastest
    assert env.describe(3) == "action 3: type 1, parameters [0, 0]"
    assert env.describe(4) == "action 4: type 1, parameters [0, 5]"
    assert env.describe(6) == "action 6: type 1, parameters [0.5, 0]"
    assert env.describe(11) == "action 11: type 1, parameters [1, 10]"
    assert env.describe(np.int64(20)) == "action 20: type 2, parameters [1, 1]"
    k, values = env.action(6)
    assert k == 1 and values[1].tolist() == [0.5, 0.0]
    with pytest.raises(ValueError, match=re.escape("out of range [0, 21)")):
        env.describe(21)
    with pytest.raises(ValueError, match="out of range"):
        env.step(-1)
    with pytest.raises(ValueError, match="one integer"):
        env.step(1.0)


def test_discretize_type_without_parameters():
    no_params = spaces.Box(-1.0, 1.0, (0,), np.float32)
    space = spaces.Tuple((spaces.Discrete(3), spaces.Tuple((no_params, spaces.Box(-1.0, 1.0, (2,), np.float32), no_params))))
    env = DiscretizeParameterizedAction(SpaceEnv(space), bins=4)
    assert env.action_space.n == 1 + 16 + 1
    assert env.describe(0) == "action 0: type 0, parameters []"
    assert env.describe(17) == "action 17: type 2, parameters []"
    env.step(17)
    assert env.unwrapped.last_action[0] == 2
    flat = FlattenParameterizedAction(SpaceEnv(space))
    assert flat.action_space.shape == (5,)
    flat.step(np.array([0, 0, 1, 0, 0], np.float32))
    assert flat.unwrapped.last_action[0] == 2


@pytest.mark.parametrize("layout", LAYOUTS)
def test_discretize_reverse_action_round_trips(layout):
    env = DiscretizeParameterizedAction(ParameterizedTargetEnv(layout), bins=(3, 2, 4, 3, 2, 2)[: 5 + (layout == "shared")])
    for i in range(env.action_space.n):
        assert env.reverse_action(env.action(i)) == i


@settings(max_examples=40, deadline=None)
@given(
    dims=st.lists(st.integers(0, 3), min_size=1, max_size=3),
    data=st.data(),
)
def test_grid_functions_agree_with_brute_force(dims, data):
    n_params = sum(dims)
    bins = data.draw(st.lists(st.integers(1, 4), min_size=n_params, max_size=n_params))
    types, params = make_grid(dims, bins)
    assert len(types) == grid_size(dims, bins)
    index = np.arange(len(types))
    k, p = grid_to_action(index, types, params)
    np.testing.assert_array_equal(action_to_grid(k, p, dims, bins), index)
    # The nearest grid point of a random point, by brute force over that type's rows
    k = data.draw(st.integers(0, len(dims) - 1))
    point = np.array(data.draw(st.lists(st.floats(-1.5, 1.5), min_size=n_params, max_size=n_params)))
    found = action_to_grid(np.array([k]), point[None], dims, bins)[0]
    assert types[found] == k
    own = np.repeat(np.arange(len(dims)), dims) == k
    rows = np.flatnonzero(types == k)
    distances = np.abs(params[rows][:, own] - np.clip(point[own], -1, 1)).max(axis=1) if own.any() else np.zeros(1)
    assert np.abs(params[found, own] - np.clip(point[own], -1, 1)).max(initial=0) <= distances.min() + 1e-9


# --------------------------------------------------------------------------------------------------------------------
# Both: SB3 compatibility
# --------------------------------------------------------------------------------------------------------------------


def test_sb3_check_env_fails_on_a_raw_env_where_gymnasiums_passes():
    """What the quick start's "Checking an env" says: SB3's checker has no Tuple action spaces; Gymnasium's checks
    these envs (and SB3's checks them behind a wrapper, below)."""
    from gymnasium.utils.env_checker import check_env as gymnasium_check_env

    with pytest.warns(UserWarning, match="Dict or Tuple space"), pytest.raises(ValueError):
        check_env(ParameterizedTargetEnv())
    gymnasium_check_env(ParameterizedTargetEnv())


@pytest.mark.parametrize("wrapper", WRAPPERS)
@pytest.mark.parametrize("layout", LAYOUTS)
def test_sb3_check_env_passes(wrapper, layout):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning either: SB3 takes the wrapped env as it is
        check_env(wrapper(ParameterizedTargetEnv(layout)))


@pytest.mark.parametrize("wrapper", WRAPPERS)
@pytest.mark.parametrize(
    "space",
    [
        spaces.Box(-1, 1, (3,)),
        spaces.Discrete(4),
        spaces.Dict({"k": spaces.Discrete(2), "p": spaces.Box(-1, 1, (2,))}),
        spaces.Tuple((spaces.Discrete(2), spaces.Box(-np.inf, 1, (2,)))),
    ],
)
def test_non_parameterized_spaces_are_rejected(wrapper, space):
    with pytest.raises(ValueError, match="Unsupported parameterized action space") as info:
        wrapper(SpaceEnv(space))
    assert "Supported:" in str(info.value)


def test_huge_grids_are_rejected():
    space = spaces.Tuple((spaces.Discrete(2), spaces.Box(-1, 1, (4,), np.float32), spaces.Box(-1, 1, (11,), np.float32)))
    with pytest.raises(ValueError) as info:
        DiscretizeParameterizedAction(SpaceEnv(space), bins=3)
    message = str(info.value)
    assert f"{3**4 + 3**11} discrete actions" in message
    assert "type 0: 3 x 3 x 3 x 3" in message and "max_actions=100000" in message
    assert "fewer bins" in message
    # allowed when asked for, and cheap to count without building
    assert grid_size((4, 11), 3) == 3**4 + 3**11
    assert DiscretizeParameterizedAction(SpaceEnv(space), bins=[3] * 4 + [2] * 11).action_space.n == 81 + 2048
    with pytest.raises(ValueError, match="more than max_actions=50"):
        DiscretizeParameterizedAction(ParameterizedTargetEnv("nested"), bins=5, max_actions=50)
    # a grid whose size overflows int64 is counted exactly and refused before anything is allocated
    with pytest.raises(ValueError, match=str(1000**40)):
        DiscretizeParameterizedAction(SpaceEnv(spaces.OneOf((spaces.Box(-1, 1, (40,), np.float32),))), bins=1000)


@pytest.mark.parametrize("bins, message", [(0, "int >= 1"), ((3, 3), "one int per parameter"), (2.5, "one int per")])
def test_bad_bins_are_rejected(bins, message):
    with pytest.raises(ValueError, match=message):
        DiscretizeParameterizedAction(ParameterizedTargetEnv("nested"), bins=bins)


@pytest.mark.parametrize("vec_env_cls", [DummyVecEnv, SubprocVecEnv])
@pytest.mark.parametrize("layout", ["nested", "oneof"])
def test_make_vec_env(vec_env_cls, layout):
    kwargs = {"start_method": "fork"} if vec_env_cls is SubprocVecEnv else None
    for wrapper, wrapper_kwargs in ((FlattenParameterizedAction, None), (DiscretizeParameterizedAction, {"bins": 2})):
        vec_env = make_vec_env(
            ParameterizedTargetEnv,
            n_envs=2,
            seed=0,
            env_kwargs={"layout": layout},
            wrapper_class=wrapper,
            wrapper_kwargs=wrapper_kwargs,
            vec_env_cls=vec_env_cls,
            vec_env_kwargs=kwargs,
        )
        try:
            assert vec_env.observation_space == spaces.Box(-1.0, 1.0, (2,), np.float32)
            expected = spaces.Discrete(10) if wrapper is DiscretizeParameterizedAction else spaces.Box(-1, 1, (8,), np.float32)
            assert vec_env.action_space == expected
            vec_env.reset()
            vec_env.action_space.seed(0)
            for _ in range(12):  # past the 10-step truncation
                obs, rewards, _dones, _infos = vec_env.step(np.array([vec_env.action_space.sample() for _ in range(2)]))
                assert obs.shape == (2, 2) and rewards.shape == (2,) and all(0 <= r <= 1 for r in rewards)
        finally:
            vec_env.close()


@pytest.mark.parametrize("algo", [PPO, A2C, SAC, TD3, DDPG])
def test_continuous_algorithms_learn_on_flatten(algo):
    kwargs = {"n_steps": 64} if algo in (PPO, A2C) else {"learning_starts": 64, "buffer_size": 1000}
    model = algo("MlpPolicy", FlattenParameterizedAction(ParameterizedTargetEnv("flat")), seed=0, device="cpu", **kwargs)
    model.learn(256 if algo is PPO else 128)
    assert model.num_timesteps >= 128
    action, _ = model.predict(model.env.observation_space.sample())
    assert action.shape == (8,) and model.env.action_space.contains(action)


@pytest.mark.parametrize("algo", [DQN, PPO])
def test_discrete_algorithms_learn_on_discretize(algo):
    env = DiscretizeParameterizedAction(ParameterizedTargetEnv("shared"), bins=(3, 1, 3, 3, 3, 3))
    kwargs = {"learning_starts": 64} if algo is DQN else {"n_steps": 64}
    model = algo("MlpPolicy", env, seed=0, device="cpu", **kwargs).learn(256)
    assert model.num_timesteps == 256
    assert model.action_space == spaces.Discrete(21)


def test_ppo_on_flatten_beats_random():
    def eval_env():
        return make_vec_env(ParameterizedTargetEnv, n_envs=1, seed=100, wrapper_class=FlattenParameterizedAction)

    class Random:
        def __init__(self, space):
            self.space = space
            self.space.seed(0)

        def predict(self, obs, state=None, episode_start=None, deterministic=False):
            return np.array([self.space.sample() for _ in range(len(obs))]), None

    env = eval_env()
    random_mean, _ = evaluate_policy(Random(env.action_space), env, n_eval_episodes=30)
    vec_env = make_vec_env(ParameterizedTargetEnv, n_envs=4, seed=0, wrapper_class=FlattenParameterizedAction)
    model = PPO("MlpPolicy", vec_env, n_steps=64, batch_size=64, learning_rate=1e-3, gamma=0.9, seed=0, device="cpu")
    model.learn(1024)
    mean, _ = evaluate_policy(model, eval_env(), n_eval_episodes=30, deterministic=True)
    # random: about 0.2 (the ball is lost after two steps); PPO after 1024 steps: 4 to 5 of the optimal 10
    assert random_mean < 0.5
    assert mean > 2.0 and mean > 5 * random_mean, (mean, random_mean)


def test_module_docstring_example_runs():
    example = sb3_aac.wrappers.__doc__.split("Example::")[1]
    namespace: dict = {}
    exec(compile(textwrap.dedent(example), "wrappers-docstring", "exec"), namespace)
    assert namespace["model"].num_timesteps == 256


def test_exported():
    assert sb3_aac.FlattenParameterizedAction is FlattenParameterizedAction
    assert sb3_aac.DiscretizeParameterizedAction is DiscretizeParameterizedAction
    assert {"FlattenParameterizedAction", "DiscretizeParameterizedAction"} <= set(sb3_aac.__all__)


def test_select_observation_keeps_the_box_part():
    class TupleObsEnv(ParameterizedTargetEnv):
        def __init__(self):
            super().__init__()
            self.observation_space = spaces.Tuple((self.observation_space, spaces.Discrete(5)))

        def reset(self, **kwargs):
            obs, info = super().reset(**kwargs)
            return (obs, 0), info

        def step(self, action):
            obs, *rest = super().step(action)
            return (obs, 1), *rest

    env = sb3_aac.SelectObservation(TupleObsEnv(), 0)
    assert env.observation_space == ParameterizedTargetEnv().observation_space
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    obs, *_ = env.step(env.action_space.sample())
    assert env.observation_space.contains(obs)
    with pytest.raises(ValueError, match="Box parts are at \\[0\\]"):
        sb3_aac.SelectObservation(TupleObsEnv(), 1)
    with pytest.raises(ValueError, match="needs a Tuple"):
        sb3_aac.SelectObservation(ParameterizedTargetEnv())
