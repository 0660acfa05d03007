"""The sequential lane steps (sb3_aac.sarsa_aac.lane_steps): one sample is normalised LMS, a batch is its samples in turn."""

import numpy as np
import pytest

from sb3_aac.sarsa_aac.lane_steps import linear_steps, mlp_steps, tile_steps, traced_tile_steps

A, F, H, N_FEATURES, C = 4, 6, 3, 40, 5


def linear_head(rng):
    return [rng.standard_normal((A, F)), rng.standard_normal(A)]


def mlp_head(rng):
    return [rng.standard_normal((A, H, F)), rng.standard_normal((A, H)), rng.standard_normal((A, H)), rng.standard_normal(A)]


def tile_head(rng):
    return [rng.standard_normal((N_FEATURES, A)), rng.standard_normal(A)]


def linear_out(weights, x):
    w, b = weights
    return x @ w.T + b


def mlp_out(weights, x):
    w1, b1, w2, b2 = weights
    return (np.tanh(np.einsum("ahf,nf->nah", w1, x) + b1) * w2).sum(-1) + b2


def tile_out(weights, active):
    w, b = weights
    return w[active].sum(1) + b


def tile_inputs(rng, n):
    return np.stack([rng.choice(N_FEATURES, C, replace=False) for _ in range(n)])


GAIN = np.array([1.0, 0.5, 2.0, 0.25])
KERNELS = {
    "linear": (
        linear_head,
        lambda rng, n: rng.standard_normal((n, F)),
        linear_out,
        lambda ws, x, e, lr: linear_steps(*ws, x, e, lr),
    ),
    "mlp": (
        mlp_head,
        lambda rng, n: rng.standard_normal((n, F)),
        mlp_out,
        lambda ws, x, e, lr: mlp_steps(*ws, x, e, lr, GAIN),
    ),
    "tile": (tile_head, tile_inputs, tile_out, lambda ws, x, e, lr: tile_steps(*ws, x, e, lr)),
}


def test_one_sample_is_the_normalised_lms_step():
    rng = np.random.default_rng(0)
    lr = np.array([0.1, 0.5, 1.0, 0.3])
    err = rng.standard_normal((1, A))
    x = rng.standard_normal((1, F))
    w, b = linear_head(rng)
    expected_w = w + (lr * err[0])[:, None] * x / (1 + x @ x.T)
    expected_b = b + lr * err[0] / (1 + x @ x.T)[0]
    linear_steps(w, b, x, err, lr)
    np.testing.assert_allclose(w, expected_w, rtol=1e-12)
    np.testing.assert_allclose(b, expected_b, rtol=1e-12)

    w1, b1, w2, b2 = mlp_head(rng)
    h = np.tanh(w1 @ x[0] + b1)  # (A, H)
    g = lr * err[0]
    g_hidden = (g * GAIN)[:, None] * w2 * (1 - h * h) / (1 + x[0] @ x[0])
    expected = (
        w1 + g_hidden[:, :, None] * x[0],
        b1 + g_hidden,
        w2 + g[:, None] * h / (1 + (h * h).sum(1, keepdims=True)),
        b2 + g / (1 + (h * h).sum(1)),
    )
    mlp_steps(w1, b1, w2, b2, x, err, lr, GAIN)
    for got, want in zip((w1, b1, w2, b2), expected, strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-12)

    w, b = tile_head(rng)
    active = tile_inputs(rng, 1)
    expected_w = w.copy()
    expected_w[active[0]] += lr * err[0] / (1 + C)
    expected_b = b + lr * err[0] / (1 + C)
    tile_steps(w, b, active, err, lr)
    np.testing.assert_allclose(w, expected_w, rtol=1e-12)
    np.testing.assert_allclose(b, expected_b, rtol=1e-12)


@pytest.mark.parametrize("kind", KERNELS)
@pytest.mark.parametrize("seed", range(3))
def test_a_batch_is_its_samples_one_after_another(kind, seed):
    """n lanes at once take exactly the steps of n one-lane calls, each toward its target fixed before the batch."""
    make_head, make_inputs, out, step = KERNELS[kind]
    rng = np.random.default_rng(seed)
    n = 7
    weights = make_head(rng)
    x = make_inputs(rng, n)
    if kind == "tile":
        x[3] = x[1]  # a repeated sample and overlapping ones: the recomputed errors matter
    err = rng.standard_normal((n, A)) * (rng.random((n, A)) < 0.7)  # zeros: no target
    lr = rng.uniform(0.1, 1.0, A)
    targets = out(weights, x) + err
    one_by_one = [w.copy() for w in weights]
    for i in range(n):
        row_err = np.where(err[i] != 0, targets[i] - out(one_by_one, x[i : i + 1])[0], 0.0)
        step(one_by_one, x[i : i + 1], row_err[None], lr)
    step(weights, x, err, lr)
    for batch, single in zip(weights, one_by_one, strict=True):
        np.testing.assert_allclose(batch, single, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("kind", KERNELS)
def test_zero_errors_change_nothing(kind):
    make_head, make_inputs, _, step = KERNELS[kind]
    rng = np.random.default_rng(1)
    weights = make_head(rng)
    before = [w.copy() for w in weights]
    step(weights, make_inputs(rng, 5), np.zeros((5, A)), np.ones(A))
    for w, w0 in zip(weights, before, strict=True):
        np.testing.assert_array_equal(w, w0)


@pytest.mark.parametrize("kind", ["linear", "tile"])
@pytest.mark.parametrize("n", [1, 16, 256])
def test_rate_one_lands_the_last_sample_and_never_overshoots(kind, n):
    """With rate 1 a linear head's output lands on the last sample's target; every lane's error shrinks (rate < 1)."""
    make_head, make_inputs, out, step = KERNELS[kind]
    rng = np.random.default_rng(2)
    weights = make_head(rng)
    x = make_inputs(rng, n)
    x[:] = x[0]  # identical samples: the batch rule that sums the lanes' steps would move n times too far
    err = rng.standard_normal((n, A))
    target = out(weights, x[:1]) + err[-1]
    step(weights, x, err, np.ones(A))
    np.testing.assert_allclose(out(weights, x[:1]), target, atol=1e-10)
    weights = make_head(rng)
    start = out(weights, x[:1])[0]
    err = np.tile(rng.standard_normal(A), (n, 1))
    step(weights, x, err, np.full(A, 0.5))
    remaining = (start + err[0]) - out(weights, x[:1])[0]
    np.testing.assert_allclose(remaining, err[0] * 0.5**n, atol=1e-10)


def test_traces_with_zero_decay_are_the_plain_steps():
    rng = np.random.default_rng(3)
    n, lanes = 6, 6
    weights = tile_head(rng)
    plain = [w.copy() for w in weights]
    active = tile_inputs(rng, n)
    err = rng.standard_normal((n, A)) * (rng.random((n, A)) < 0.7)
    lr = rng.uniform(0.1, 1.0, A)
    trace_column = np.array([0, -1, -1, 1])  # columns 0 and 3 traced
    hit = np.ones((n, 2))
    trace = np.zeros((lanes, N_FEATURES, 2))
    listed = np.zeros((lanes, N_FEATURES), dtype=np.bool_)
    live, n_live = np.zeros((lanes, N_FEATURES), dtype=np.int64), np.zeros(lanes, dtype=np.int64)
    bias_trace = np.zeros((lanes, 2))
    traced_tile_steps(*weights, active, err, lr, trace_column, hit, 0.0, True, 1e-3, trace, bias_trace, listed, live, n_live)
    tile_steps(*plain, active, err, lr)
    for got, want in zip(weights, plain, strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-14)
