"""The shared gradient-step pieces give exactly the numbers of SB3's ``polyak_update`` and torch's ``clip_grad_norm_``."""

import pytest
import torch as th
from stable_baselines3.common.utils import polyak_update as sb3_polyak_update

from sb3_aac.common.updates import clip_grad_norm, make_optimizer, polyak_update

SHAPES = [(16, 5), (16,), (3, 16), (3,)]


def tensors(seed: int) -> list[th.Tensor]:
    generator = th.Generator().manual_seed(seed)
    return [th.randn(shape, generator=generator) for shape in SHAPES]


@pytest.mark.parametrize("tau", [0.001, 0.1, 1.0])
def test_polyak_update_is_sb3s(tau):
    params, targets, expected = tensors(0), tensors(1), tensors(1)
    polyak_update(params, targets, tau)
    sb3_polyak_update(params, expected, tau)
    assert all(th.equal(t, e) for t, e in zip(targets, expected, strict=True))


@pytest.mark.parametrize("max_norm", [1e-2, 1e3])  # clipped, not clipped
def test_clip_grad_norm_is_torchs(max_norm):
    grads = tensors(2)
    params = [th.zeros(shape, requires_grad=True) for shape in SHAPES]
    for param, grad in zip(params, tensors(2), strict=True):
        param.grad = grad
    norm = clip_grad_norm(grads, max_norm)
    expected_norm = th.nn.utils.clip_grad_norm_(params, max_norm)
    assert th.equal(norm, expected_norm)
    assert all(th.equal(g, p.grad) for g, p in zip(grads, params, strict=True))


def test_optimizers_get_the_fastest_implementation_unless_chosen():
    params = [th.zeros(3, requires_grad=True)]
    assert make_optimizer(th.optim.Adam, params, 1e-3, {}).defaults["fused"]
    assert make_optimizer(th.optim.RMSprop, params, 1e-3, {}).defaults["foreach"]  # no fused RMSprop
    chosen = make_optimizer(th.optim.Adam, params, 1e-3, {"foreach": False, "eps": 1e-5}).defaults
    assert chosen["foreach"] is False and not chosen["fused"] and chosen["eps"] == 1e-5
