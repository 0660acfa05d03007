"""
Gradients of a small torch MLP (an ``nn.Sequential`` of ``nn.Linear`` layers and element-wise activations, as SB3's
``create_mlp`` builds) as explicit matrix products, without autograd.

On the minibatches of P-DQN and MP-DQN (128 rows, hidden layers of 64) autograd's graph building and bookkeeping cost
more than the sums; :func:`forward` keeps each layer's input and :func:`backward` runs the chain rule through them with
the same kind of calls autograd would make (``mm`` for the weights and the inputs, a row sum for the biases, ATen's
own backward kernel for each activation). The sums can be ordered differently from autograd's, so results agree to
rounding, not bit for bit. Call both under ``th.no_grad()``.
"""

from __future__ import annotations

from collections.abc import Callable

import torch as th
from torch import nn

# The derivative of an activation, applied to the gradient of its output: (module, gradient, its input, its output).
ActivationBackward = Callable[[nn.Module, th.Tensor, th.Tensor, th.Tensor], th.Tensor]

ACTIVATION_BACKWARDS: dict[type[nn.Module], ActivationBackward] = {
    nn.ReLU: lambda module, grad, x, y: th.ops.aten.threshold_backward(grad, y, 0),
    nn.Tanh: lambda module, grad, x, y: th.ops.aten.tanh_backward(grad, y),
    nn.Sigmoid: lambda module, grad, x, y: th.ops.aten.sigmoid_backward(grad, y),
    nn.SiLU: lambda module, grad, x, y: th.ops.aten.silu_backward(grad, x),
    nn.LeakyReLU: lambda module, grad, x, y: th.ops.aten.leaky_relu_backward(grad, x, module.negative_slope, False),
    nn.ELU: lambda module, grad, x, y: th.ops.aten.elu_backward(grad, module.alpha, 1, 1, False, x),
    nn.GELU: lambda module, grad, x, y: th.ops.aten.gelu_backward(grad, x, approximate=module.approximate),
}
"""The activations whose derivative is one ATen kernel; any other module is differentiated by autograd alone."""


def forward(layers: nn.Sequential, x: th.Tensor) -> tuple[th.Tensor, list[th.Tensor]]:
    """``layers(x)`` ``(n, out)``, and the input of every layer followed by the output (what :func:`backward` reads)."""
    saved = [x]
    for layer in layers:
        x = layer.forward(x)
        saved.append(x)
    return x, saved


def backward(
    layers: nn.Sequential, saved: list[th.Tensor], grad: th.Tensor, weights: bool = True
) -> tuple[list[th.Tensor], th.Tensor]:
    """
    The chain rule from ``grad``, the gradient of a loss with respect to the output of :func:`forward`.

    :param layers: the layers :func:`forward` ran
    :param saved: what :func:`forward` returned with the output
    :param grad: ``(n, out)``
    :param weights: whether to compute the gradients of the layers' parameters (else the input's only)
    :return: the gradients of the layers' parameters in the order of ``layers.parameters()`` (empty when
        ``weights`` is False), and the gradient with respect to the input ``(n, in)``
    """
    param_grads: list[th.Tensor] = []
    for i in range(len(layers) - 1, -1, -1):
        layer, x = layers[i], saved[i]
        if isinstance(layer, nn.Linear):
            if weights:
                if layer.bias is not None:
                    param_grads.append(grad.sum(0))
                param_grads.append(grad.t().mm(x))
            grad = grad.mm(layer.weight)
        else:
            grad = activation_backward(layer, grad, x, saved[i + 1])
    param_grads.reverse()
    return param_grads, grad


def activation_backward(module: nn.Module, grad: th.Tensor, x: th.Tensor, y: th.Tensor) -> th.Tensor:
    """The gradient with respect to the input ``x`` of an element-wise activation, given its output ``y``'s ``grad``."""
    kernel = ACTIVATION_BACKWARDS.get(type(module))
    if kernel is not None:
        return kernel(module, grad, x, y)
    with th.enable_grad():
        leaf = x.detach().requires_grad_()
        (input_grad,) = th.autograd.grad(module(leaf), leaf, grad)
    return input_grad
