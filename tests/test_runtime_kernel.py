"""The numba act kernel's inputs: the named meta layout, and the one-parameter unscale it compiles."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sb3_aac.runtime.actions import unscale, unscale_value
from sb3_aac.runtime.forward import BankForward
from sb3_aac.runtime.kernel import META_FIELDS, M_OFFSETS, PACK_FIELDS, SIZE_FIELDS, act_kernel, kernel_arguments

FINITE = st.floats(-1e6, 1e6, allow_nan=False)


@given(scaled=st.floats(-2.0, 2.0, allow_nan=False), a=FINITE, b=FINITE)
def test_unscale_value_is_unscale_of_one_parameter(scaled: float, a: float, b: float) -> None:
    low, high = min(a, b), max(a, b)
    expected = unscale(np.array([low]), np.array([high]), np.array([scaled]))[0]
    assert unscale_value(scaled, low, high) == expected
    assert low <= unscale_value(scaled, low, high) <= high


def rbf_mlp_bank(rng: np.random.Generator, d: int = 3, m: int = 4, n_outputs: int = 6, hidden: int = 2) -> BankForward:
    return BankForward(
        obs_mid=rng.normal(size=d),
        obs_half=rng.uniform(0.5, 2.0, d),
        rbf_centers=np.tile(np.linspace(-1, 1, m), (d, 1)),
        rbf_widths=np.full((d, m), 0.5),
        weight1=rng.normal(size=(n_outputs, hidden, d * m)),
        bias1=rng.normal(size=(n_outputs, hidden)),
        weight2=rng.normal(size=(n_outputs, hidden)),
        bias2=rng.normal(size=n_outputs),
        rbf_window=3.0,
    )


def test_meta_names_every_size_and_where_each_array_starts_in_pack() -> None:
    bank = rbf_mlp_bank(np.random.default_rng(0))
    low, high, offsets = np.array([-1.0, 0.0, 2.0]), np.array([1.0, 5.0, 3.0]), (0, 1, 3)
    pack, meta = kernel_arguments(bank, low, high, offsets)
    sizes = dict(zip(SIZE_FIELDS, meta, strict=False))
    assert sizes == {"n_inputs": 3, "n_rbf": 4, "n_features": 12, "hidden_units": 2, "n_types": 2}
    arrays = {"feature_a": bank.feature_a, "feature_b": bank.feature_b, "head_w": bank.head_w, "head_b": bank.head_b}
    arrays.update(w2=bank.w2, b2=bank.b2, param_low=low, param_high=high, window_z2=np.array([bank.window_z2]))
    for name in PACK_FIELDS:
        start = meta[META_FIELDS.index(name)]
        np.testing.assert_array_equal(pack[start : start + arrays[name].size], np.ravel(arrays[name]), err_msg=name)
    assert len(pack) == sum(a.size for a in arrays.values())
    assert meta[M_OFFSETS:].tolist() == list(offsets)


def test_kernel_decides_as_the_numpy_forward_pass() -> None:
    kernel = act_kernel()
    if kernel is None:
        pytest.skip("numba is not installed")
    rng = np.random.default_rng(1)
    bank = rbf_mlp_bank(rng)
    low, high, offsets = np.array([-1.0, 0.0, 2.0]), np.array([1.0, 5.0, 3.0]), (0, 1, 3)
    pack, meta = kernel_arguments(bank, low, high, offsets)
    phi, active, params = np.empty(bank.feature_a.size), np.empty(bank.feature_a.size, np.int64), np.empty(2)
    for x in rng.normal(size=(200, 3)):
        out = bank.outputs(bank.features(x))[0]
        k, dim = kernel(x, pack, meta, phi, active, params)
        assert k == out[:2].argmax()
        start = 2 + offsets[k]
        expected = unscale(low[offsets[k] : offsets[k + 1]], high[offsets[k] : offsets[k + 1]], out[start : start + dim])
        np.testing.assert_allclose(params[:dim], expected, rtol=1e-12, atol=1e-12)
    assert kernel(np.array([0.0, np.nan, 0.0]), pack, meta, phi, active, params)[0] == -1
