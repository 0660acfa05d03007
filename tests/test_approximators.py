import copy

import numpy as np
import pytest
import torch as th

from sb3_aac.sarsa_aac.approximators import ApproximatorBank, rbf_layout

CONFIGS = {
    "mlp": dict(n_rbf=None, hidden_units=5),
    "rbf_mlp": dict(n_rbf=4, hidden_units=5),
    "rbf": dict(n_rbf=4, hidden_units=None),
    "linear": dict(n_rbf=None, hidden_units=None),
}
LOW, HIGH = np.array([-1.0, 0.0, -5.0]), np.array([1.0, 2.0, 5.0])


def make_bank(name: str, n_outputs: int = 4) -> ApproximatorBank:
    th.manual_seed(0)
    return ApproximatorBank(LOW, HIGH, n_outputs, **CONFIGS[name])


def torch_reference(tensors: dict[str, th.Tensor], obs: th.Tensor) -> tuple[th.Tensor, th.Tensor, th.Tensor | None]:
    """
    Test-only reference: the module docstring's formulas written directly in torch (unfolded constants), for
    autograd. Returns the features, the outputs and the hidden activations (None for a linear head).
    """
    x = (obs - tensors["obs_mid"]) / tensors["obs_half"]
    if "rbf_centers" in tensors:
        z = (x[:, :, None] - tensors["rbf_centers"]) / tensors["rbf_widths"]
        x = th.exp(-0.5 * z * z).reshape(len(obs), -1)
    if "weight" in tensors:
        return x, x @ tensors["weight"].T + tensors["bias"], None
    hidden = th.tanh(th.einsum("nf,ahf->nah", x, tensors["weight1"]) + tensors["bias1"])
    return x, (hidden * tensors["weight2"]).sum(-1) + tensors["bias2"], hidden


@pytest.mark.parametrize("name", CONFIGS)
def test_forward_matches_torch_reference(name):
    bank = make_bank(name)
    obs = np.random.default_rng(0).uniform(LOW, HIGH, (7, 3))
    out, cache = bank.numpy_kernel().forward(obs)
    x, expected, hidden = torch_reference(bank.state_dict(), th.as_tensor(obs))
    np.testing.assert_allclose(out, expected.numpy(), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(cache.x, x.numpy(), rtol=1e-12, atol=1e-12)
    if hidden is not None:
        np.testing.assert_allclose(cache.hidden, hidden.numpy(), rtol=1e-12, atol=1e-12)
    assert out.shape == (7, 4)
    # The module's forward (a tensor, as SB3 calls it) is the same numpy code.
    tensor_out = bank(th.as_tensor(obs))
    assert tensor_out.dtype == th.float64
    np.testing.assert_array_equal(tensor_out.numpy(), out)


@pytest.mark.parametrize("name", CONFIGS)
def test_update_equals_normalised_gradient_step(name):
    """The closed-form update is a gradient step on 0.5 * err^2, each layer's step divided by 1 + ||its input||^2."""
    bank = make_bank(name)
    obs = np.random.default_rng(1).uniform(LOW, HIGH, (1, 3))
    kernel = bank.numpy_kernel()
    _, cache = kernel.forward(obs)
    err = np.array([[0.5, 0.0, -1.0, 2.0]])
    lr = np.array([0.1, 0.2, 0.3, 0.4])

    params = {pname: p.detach().clone().requires_grad_(True) for pname, p in bank.named_parameters()}
    x, output, hidden = torch_reference({**dict(bank.named_buffers()), **params}, th.as_tensor(obs))
    # d/dw of sum(lr * err * output) is the descent direction for 0.5 * err^2 with err held fixed.
    (output * th.as_tensor(lr * err)).sum().backward()
    expected = {}
    with th.no_grad():
        x_scale = 1.0 / (1.0 + (x * x).sum())
    for pname, p in params.items():
        if pname in ("weight2", "bias2"):
            with th.no_grad():
                scale = 1.0 / (1.0 + (hidden[0] ** 2).sum(-1))  # per approximator
            scale = scale[:, None] if pname == "weight2" else scale
            expected[pname] = p.detach() + p.grad * scale
        else:
            expected[pname] = p.detach() + p.grad * x_scale
    kernel.update(cache, err, lr)
    for pname, p in bank.named_parameters():
        np.testing.assert_allclose(p.numpy(), expected[pname].numpy(), rtol=1e-10, atol=1e-12, err_msg=pname)


def test_linear_rate_one_hits_target():
    """Normalised LMS: with a learning rate of 1 a linear approximator reaches its target on that sample."""
    for n_rbf in (10, 30, 50):
        bank = ApproximatorBank(LOW, HIGH, 2, n_rbf=n_rbf)
        kernel = bank.numpy_kernel()
        obs = np.array([[0.3, 1.2, -2.0]])
        out, cache = kernel.forward(obs)
        target = out + np.array([[1.0, -3.0]])
        kernel.update(cache, target - out, np.ones(2))
        np.testing.assert_allclose(kernel.forward(obs)[0], target, atol=1e-12)


def test_zero_error_changes_nothing_and_outputs_are_independent():
    bank = make_bank("rbf_mlp")
    kernel = bank.numpy_kernel()
    before = {k: v.clone() for k, v in bank.state_dict().items()}
    obs = np.zeros((2, 3))
    _, cache = kernel.forward(obs)
    err = np.zeros((2, 4))
    err[:, 1] = 1.0
    kernel.update(cache, err, np.ones(4))
    after = bank.state_dict()
    for key in ("weight1", "bias1", "weight2", "bias2"):
        changed = ~np.isclose(after[key].numpy(), before[key].numpy()).reshape(4, -1).all(1)
        np.testing.assert_array_equal(changed, [False, True, False, False], err_msg=key)


def test_rbf_layout_and_features():
    centers, widths = rbf_layout(2, 5, 1.0)
    np.testing.assert_allclose(centers[0], [-1, -0.5, 0, 0.5, 1])
    np.testing.assert_allclose(widths, 0.5)
    bank = ApproximatorBank(np.array([0.0, 10.0]), np.array([4.0, 20.0]), 1, n_rbf=5)
    # The low bound of each input sits on its first centre, the high bound on its last.
    x = bank.numpy_kernel().features(np.array([[0.0, 20.0]]))
    assert x.shape == (1, 10)
    assert x[0, 0] == pytest.approx(1.0) and x[0, 9] == pytest.approx(1.0)
    assert x[0, 1] == pytest.approx(np.exp(-0.5))


def test_kernel_views_follow_load_state_dict_and_moves():
    bank = make_bank("rbf")
    kernel = bank.numpy_kernel()
    assert bank.numpy_kernel() is kernel  # cached
    obs = np.zeros((1, 3))
    other = make_bank("rbf")
    with th.no_grad():
        other.weight.add_(1.0)
        other.rbf_widths.mul_(2.0)
    bank.load_state_dict(other.state_dict())
    reference = torch_reference(other.state_dict(), th.as_tensor(obs))[1].numpy()
    np.testing.assert_allclose(bank.numpy_kernel().forward(obs)[0], reference)
    bank.to(th.float64)
    assert bank.numpy_kernel() is not kernel
    clone = copy.deepcopy(bank)
    clone.numpy_kernel().update(clone.numpy_kernel().forward(obs)[1], np.ones((1, 4)), np.ones(4))
    assert not np.allclose(clone.weight.numpy(), bank.weight.numpy())


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(low=np.array([-np.inf, 0]), high=np.array([1, 1]), n_rbf=5), "RBF features need finite bounds"),
        (dict(low=np.array([1, 0]), high=np.array([1, 1])), "Need low < high"),
        (dict(low=np.zeros(2), high=np.ones(2), hidden_units=0), "hidden_units must be a whole number >= 1"),
        (dict(low=np.zeros(2), high=np.ones(2), n_rbf=0), "n_rbf must be a whole number >= 1"),
        (dict(low=np.zeros(2), high=np.ones(2), n_rbf=3, rbf_width=0.0), "rbf_width must be > 0"),
    ],
)
def test_bad_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ApproximatorBank(n_outputs=2, **kwargs)


def test_infinite_bounds_without_rbf_pass_inputs_unscaled():
    bank = ApproximatorBank(np.array([-np.inf, 0.0]), np.array([np.inf, 2.0]), 1)
    np.testing.assert_allclose(bank.numpy_kernel().features(np.array([[7.0, 2.0]])), [[7.0, 1.0]])


@pytest.mark.parametrize("n_rbf", [None, 10])
@pytest.mark.parametrize("n", [1, 256])
def test_rate_one_lands_identical_samples_on_target(n_rbf, n):
    """n copies of one sample: the first lands on the target with a rate of 1, the others then have nothing left to move."""
    bank = ApproximatorBank(LOW, HIGH, 2, n_rbf=n_rbf)
    kernel = bank.numpy_kernel()
    obs = np.tile([[0.3, 1.2, -2.0]], (n, 1))
    out, cache = kernel.forward(obs)
    kernel.update(cache, np.tile([[1.0, -3.0]], (n, 1)), np.ones(2))
    np.testing.assert_allclose(kernel.forward(obs[:1])[0], out[:1] + np.array([[1.0, -3.0]]), atol=1e-12)


@pytest.mark.parametrize("name", CONFIGS)
def test_a_batch_takes_its_samples_one_after_another(name):
    """n lanes at once take the steps of n one-sample updates, each toward its target fixed before the batch."""
    rng = np.random.default_rng(4)
    obs = rng.uniform(LOW, HIGH, (5, 3))
    obs[3] = obs[1]
    err = rng.standard_normal((5, 4))
    lr = np.array([0.1, 0.5, 1.0, 0.3])
    batch, single = make_bank(name), make_bank(name)
    single.load_state_dict(batch.state_dict())
    targets = batch.evaluate(obs) + err
    batch.numpy_kernel().update(batch.numpy_kernel().forward(obs)[1], err, lr)
    kernel = single.numpy_kernel()
    for i in range(len(obs)):
        out, cache = kernel.forward(obs[i : i + 1])
        kernel.update(cache, targets[i : i + 1] - out, lr)
    for (key, value), other in zip(batch.state_dict().items(), single.state_dict().values(), strict=True):
        np.testing.assert_allclose(value.numpy(), other.numpy(), rtol=1e-10, atol=1e-12, err_msg=key)


@pytest.mark.parametrize("n_rbf", [7, 30, 50, 80])
@pytest.mark.parametrize("rbf_window", [1.5, 5.0])
def test_rbf_window_is_the_masked_dense_features(n_rbf: int, rbf_window: float) -> None:
    """Windowed features equal the dense ones where z * z <= r**2 / 2 and are exactly 0 elsewhere, bit for bit,
    for a large batch (the gathered window), a small one (dense, then the mask) and one observation."""
    from sb3_aac.runtime.forward import WINDOW_MIN_ROWS, BankForward

    rng = np.random.default_rng(n_rbf)
    low, high = rng.uniform(-5, 0, 6), rng.uniform(1, 5, 6)
    bank = ApproximatorBank(low, high, 3, n_rbf=n_rbf, rbf_width=0.7, rbf_window=rbf_window)
    windowed, dense = bank.numpy_kernel(), BankForward(**bank.arrays())
    obs = rng.uniform(low - 0.5 * (high - low), high + 0.5 * (high - low), (2 * WINDOW_MIN_ROWS, 6))
    z = obs[..., None] * dense.feature_a - dense.feature_b
    expected = np.where(z * z <= rbf_window**2 / 2, dense.features(obs).reshape(z.shape), 0.0).reshape(len(obs), -1)
    assert 0 < (expected == 0).mean() < 1
    np.testing.assert_array_equal(windowed.features(obs), expected)
    np.testing.assert_array_equal(windowed.features(obs[:3]), expected[:3])
    np.testing.assert_array_equal(windowed.features(obs[0], out=np.empty(dense.feature_a.shape)), expected[0])
    # The documented bound: each dropped feature is below exp(-r**2 / 2).
    dropped = dense.features(obs) - expected
    assert dropped.max() <= np.exp(-(rbf_window**2) / 2)


def test_rbf_window_validation() -> None:
    for bad in (0, -1.0, float("inf"), float("nan"), "5", True):
        with pytest.raises(ValueError, match="rbf_window"):
            ApproximatorBank(np.zeros(2), np.ones(2), 3, n_rbf=5, rbf_window=bad)
