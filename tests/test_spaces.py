import numpy as np
import pytest
from gymnasium import spaces
from hypothesis import given, settings
from hypothesis import strategies as st

from sb3_aac.common.spaces import ParameterizedActionSpec

BOXES = (
    spaces.Box(-2.0, 2.0, (1,), np.float32),
    spaces.Box(np.array([0.0, 0.0], np.float32), np.array([1.0, 10.0], np.float32)),
    spaces.Box(-1.0, 1.0, (2, 2), np.float64),
)


def make_space(layout: str, start: int = 0) -> spaces.Space:
    if layout == "nested":
        return spaces.Tuple((spaces.Discrete(3, start=start), spaces.Tuple(BOXES)))
    if layout == "flat":
        return spaces.Tuple((spaces.Discrete(3, start=start), *BOXES))
    if layout == "shared":
        return spaces.Tuple((spaces.Discrete(3, start=start), BOXES[1]))
    return spaces.OneOf(BOXES)


LAYOUTS = ["nested", "flat", "shared", "oneof"]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_parse(layout):
    spec = ParameterizedActionSpec.from_space(make_space(layout))
    assert spec.layout == layout
    assert spec.n_types == 3
    if layout == "shared":
        assert spec.dims == (2, 2, 2)
        np.testing.assert_array_equal(spec.param_type, [0, 0, 1, 1, 2, 2])
    else:
        assert spec.dims == (1, 2, 4)
        assert spec.offsets == (0, 1, 3, 7)
        np.testing.assert_array_equal(spec.low[:3], [-2, 0, 0])
        np.testing.assert_array_equal(spec.high[:3], [2, 1, 10])
    assert spec.type_slice(1) == slice(spec.offsets[1], spec.offsets[2])


@pytest.mark.parametrize("layout", LAYOUTS)
@pytest.mark.parametrize("start", [0, 5])
def test_to_env_actions_are_in_space(layout, start):
    space = make_space(layout, start)
    spec = ParameterizedActionSpec.from_space(space)
    rng = np.random.default_rng(0)
    k = np.array([0, 1, 2, 1])
    params = rng.uniform(-1.5, 1.5, (4, spec.n_params))  # some outside [-1, 1]: must be clipped
    actions = spec.to_env(k, params)
    assert actions.dtype == object and actions.shape == (4,)
    for i, action in enumerate(actions):
        assert isinstance(action, tuple)
        assert space.contains(action), action
        expected_k = k[i] if layout == "oneof" else k[i] + start
        assert type(action[0]) is int and action[0] == expected_k
    single = spec.to_env_single(2, params[0])
    assert space.contains(single)


@pytest.mark.parametrize("layout", ["nested", "flat"])
def test_round_trip_all_params(layout):
    spec = ParameterizedActionSpec.from_space(make_space(layout, start=2))
    params = np.random.default_rng(1).uniform(-1, 1, (5, spec.n_params))
    k = np.array([0, 1, 2, 2, 0])
    k_back, params_back = spec.from_env(spec.to_env(k, params))
    np.testing.assert_array_equal(k_back, k)
    np.testing.assert_allclose(params_back, params, atol=1e-6)  # float32 boxes


@pytest.mark.parametrize("layout", ["shared", "oneof"])
def test_round_trip_chosen_params(layout):
    spec = ParameterizedActionSpec.from_space(make_space(layout))
    params = np.random.default_rng(2).uniform(-1, 1, (3, spec.n_params))
    k = np.array([2, 0, 1])
    k_back, params_back = spec.from_env(spec.to_env(k, params))
    np.testing.assert_array_equal(k_back, k)
    for i in range(3):
        part = spec.type_slice(k[i])
        np.testing.assert_allclose(params_back[i, part], params[i, part], atol=1e-6)
        others = np.ones(spec.n_params, bool)
        others[part] = False
        np.testing.assert_array_equal(params_back[i, others], 0.0)


def test_values_hit_bounds_and_dtype():
    spec = ParameterizedActionSpec.from_space(make_space("nested"))
    action = spec.to_env_single(1, np.full(spec.n_params, -1.0))
    low_action = spec.to_env_single(1, np.full(spec.n_params, 1.0))
    np.testing.assert_array_equal(action[1][1], [0.0, 0.0])
    np.testing.assert_array_equal(low_action[1][1], [1.0, 10.0])
    assert action[1][0].dtype == np.float32 and action[1][2].dtype == np.float64
    assert action[1][2].shape == (2, 2)


@settings(max_examples=50, deadline=None)
@given(
    low=st.floats(-1e3, 1e3),
    width=st.floats(1e-3, 1e3),
    p=st.floats(-1, 1),
)
def test_scale_unscale_inverse(low, width, p):
    box = spaces.Box(np.float64(low), np.float64(low + width), (1,), np.float64)
    spec = ParameterizedActionSpec.from_space(spaces.Tuple((spaces.Discrete(1), box)))
    value = spec.unscale(np.array([p]))
    assert box.low[0] <= value[0] <= box.high[0]
    np.testing.assert_allclose(spec.scale(value), [p], atol=1e-9 * max(1.0, abs(low) / width))


@pytest.mark.parametrize(
    "space, message",
    [
        (spaces.Box(-1, 1, (3,)), "Box is not a parameterized action space"),
        (spaces.Discrete(3), "Discrete is not a parameterized action space"),
        (spaces.Tuple((spaces.Box(-1, 1, (2,)), spaces.Box(-1, 1, (2,)))), "must start with a Discrete"),
        (spaces.Tuple((spaces.Discrete(2),)), "must start with a Discrete"),
        (spaces.Tuple((spaces.Discrete(2), spaces.Box(-np.inf, 1, (2,)))), "infinite bounds"),
        (spaces.Tuple((spaces.Discrete(2), spaces.Box(-1, 1, (2,), np.int64))), "dtype int64"),
        (spaces.Tuple((spaces.Discrete(3), BOXES[0], BOXES[1])), "declares 3 action types but 2 Boxes"),
        (spaces.Tuple((spaces.Discrete(2), spaces.Tuple((BOXES[0], spaces.Discrete(2))))), "not a Box"),
        (spaces.OneOf((BOXES[0], spaces.Discrete(3))), "not a Box"),
        (spaces.Dict({"k": spaces.Discrete(2)}), "Dict is not a parameterized action space"),
    ],
)
def test_unsupported_spaces(space, message):
    with pytest.raises(ValueError, match=message) as info:
        ParameterizedActionSpec.from_space(space)
    assert "Supported:" in str(info.value)


def test_bad_batch_shapes():
    spec = ParameterizedActionSpec.from_space(make_space("nested"))
    with pytest.raises(ValueError, match="Expected k of shape"):
        spec.to_env(np.array([0, 1]), np.zeros((3, spec.n_params)))
    with pytest.raises(ValueError, match="out of range"):
        spec.to_env(np.array([3]), np.zeros((1, spec.n_params)))
    with pytest.raises(ValueError, match="is not an element"):
        spec.from_env([(0, 1.0)])


@settings(max_examples=100, deadline=None)
@given(
    low=st.floats(-1e3, 1e3),
    width=st.floats(1e-3, 1e3),
    dtype=st.sampled_from([np.float32, np.float64]),
)
def test_unscale_hits_bounds_exactly(low, width, dtype):
    # mid + half * p missed float64 bounds by one ulp for about one Box in five
    box = spaces.Box(np.array([low], dtype), np.array([low + width], dtype), (1,), dtype)
    spec = ParameterizedActionSpec.from_space(spaces.Tuple((spaces.Discrete(1), box)))
    assert spec.unscale(np.array([-1.0]))[0] == box.low[0]
    assert spec.unscale(np.array([1.0]))[0] == box.high[0]
    assert spec.unscale(np.array([-3.0]))[0] == box.low[0]
    assert spec.unscale(np.array([3.0]))[0] == box.high[0]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_to_env_predicted_is_a_batch_or_one_action(layout):
    spec = ParameterizedActionSpec.from_space(make_space(layout, 0))
    k, params = np.array([2, 0]), np.random.default_rng(1).uniform(-1, 1, (2, spec.n_params))
    batch = spec.to_env_predicted(k, params, vectorized=True)
    assert batch.dtype == object and repr(list(batch)) == repr(list(spec.to_env(k, params)))
    assert repr(spec.to_env_predicted(k[:1], params[:1], vectorized=False)) == repr(spec.to_env_single(2, params[0]))
