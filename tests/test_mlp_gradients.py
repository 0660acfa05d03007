"""The explicit MLP gradients (sb3_aac.common.mlp_gradients) and the Q network's pass algebra against autograd."""

import numpy as np
import pytest
import torch as th
from hypothesis import given, settings
from hypothesis import strategies as st
from stable_baselines3.common.torch_layers import create_mlp
from torch import nn

from sb3_aac.common import mlp_gradients
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.pdqn.policies import ParamActor, QNetwork
from sb3_aac.common.envs import ParameterizedTargetEnv

# Every activation with an ATen kernel, and one without (autograd differentiates it).
ACTIVATIONS = [*mlp_gradients.ACTIVATION_BACKWARDS, nn.Softplus]


def autograd_gradients(layers: nn.Sequential, x: th.Tensor, grad: th.Tensor) -> tuple[list[th.Tensor], th.Tensor]:
    """The gradients of ``(layers(x) * grad).sum()`` with respect to the layers' parameters and ``x``."""
    leaf = x.detach().requires_grad_()
    *params, input_grad = th.autograd.grad(layers(leaf), [*layers.parameters(), leaf], grad)
    return params, input_grad


@pytest.mark.parametrize("activation", ACTIVATIONS, ids=lambda a: a.__name__)
@settings(max_examples=10, deadline=None)
@given(
    seed=st.integers(0, 2**16),
    rows=st.integers(1, 9),
    sizes=st.lists(st.integers(1, 7), min_size=2, max_size=4),
)
def test_backward_is_autograds(activation, seed, rows, sizes):
    th.manual_seed(seed)
    layers = nn.Sequential(*create_mlp(sizes[0], sizes[-1], sizes[1:-1], activation))
    if activation is nn.LeakyReLU:
        layers = nn.Sequential(*(nn.LeakyReLU(0.2) if isinstance(m, nn.LeakyReLU) else m for m in layers))
    x, grad = th.randn(rows, sizes[0]), th.randn(rows, sizes[-1])
    expected_params, expected_input = autograd_gradients(layers, x, grad)
    with th.no_grad():
        out, saved = mlp_gradients.forward(layers, x)
        params, input_grad = mlp_gradients.backward(layers, saved, grad)
        _, input_only = mlp_gradients.backward(layers, saved, grad, weights=False)
    assert th.equal(out, layers(x))
    assert len(params) == len(expected_params)
    for got, want in zip(params, expected_params, strict=True):
        assert got.shape == want.shape
        th.testing.assert_close(got, want, rtol=1e-5, atol=1e-6)
    th.testing.assert_close(input_grad, expected_input, rtol=1e-5, atol=1e-6)
    assert th.equal(input_only, input_grad)


def test_a_layer_without_bias_has_one_gradient():
    layers = nn.Sequential(nn.Linear(3, 4, bias=False), nn.ReLU(), nn.Linear(4, 2))
    x, grad = th.randn(5, 3), th.randn(5, 2)
    with th.no_grad():
        params, _ = mlp_gradients.backward(layers, mlp_gradients.forward(layers, x)[1], grad)
    assert [p.shape for p in params] == [p.shape for p in layers.parameters()]


@pytest.mark.parametrize("multi_pass", [False, True])
def test_the_q_networks_pass_algebra_is_autograds(multi_pass):
    th.manual_seed(0)
    spec = ParameterizedActionSpec.from_space(ParameterizedTargetEnv().action_space)
    q_net = QNetwork(6, spec, [8, 8], nn.Tanh, multi_pass)
    n = 5
    features, params = th.randn(n, 6), th.randn(n, spec.n_params)
    types = th.as_tensor(np.arange(n) % spec.n_types)
    value_grads = th.randn(n, spec.n_types)
    leaf = params.clone().requires_grad_()
    values = q_net(features, leaf)
    (expected,) = th.autograd.grad((values * value_grads).sum(), leaf)
    with th.no_grad():
        outputs, saved = mlp_gradients.forward(q_net.net, q_net.pass_inputs(features, params))
        _, input_grads = mlp_gradients.backward(q_net.net, saved, q_net.output_grads(value_grads), weights=False)
        chosen = q_net.net(q_net.chosen_inputs(features, params, types)).gather(1, types.unsqueeze(1)).squeeze(1)
    assert th.equal(q_net.values(outputs), values.detach())
    th.testing.assert_close(q_net.param_grads(input_grads, 6), expected)
    th.testing.assert_close(chosen, values.detach().gather(1, types.unsqueeze(1)).squeeze(1))


@pytest.mark.parametrize("squash", [False, True])
def test_the_actors_bound_and_its_gradient_are_autograds(squash):
    th.manual_seed(0)
    actor = ParamActor(4, 3, [8], nn.ReLU, np.array([0.5, -0.2, 0.0]), squash)
    features, grads = th.randn(6, 4), th.randn(6, 3)
    mlp_out = actor.net(features).detach().requires_grad_()
    (expected,) = th.autograd.grad((actor.bound(mlp_out) * grads).sum(), mlp_out)
    with th.no_grad():
        got = actor.mlp_output_grads(grads, actor.bound(mlp_out))
    assert th.equal(actor.bound(mlp_out).detach(), actor(features).detach())
    th.testing.assert_close(got, expected)
