"""HybridDistribution: log-probability and entropy against hand-computed numbers; unused parameters never count."""

import math

import numpy as np
import torch as th
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats

from sb3_aac.hppo.distributions import HybridDistribution

# Two types: type 0 owns parameter 0, type 1 owns parameters 1 and 2.
PARAM_TYPE = np.array([0, 1, 1])
LOGITS = th.tensor([[0.0, math.log(3.0)]])  # p = (1/4, 3/4)
MEAN = th.tensor([[0.5, -0.5, 0.0]])
LOG_STD = th.tensor([0.0, math.log(2.0), math.log(0.5)])


def distribution(logits=LOGITS, mean=MEAN, log_std=LOG_STD):
    return HybridDistribution(PARAM_TYPE, 2).proba_distribution(logits, mean, log_std)


def test_log_prob_by_hand():
    # k = 1 with x_1 = (0.5, 1.0); the 9.0 in type 0's slot is not part of the executed action.
    action = th.tensor([[1.0, 9.0, 0.5, 1.0]])
    half_log_2pi = 0.5 * math.log(2 * math.pi)
    log_p_type = math.log(0.75)
    # N(0.5; -0.5, 2): z = 0.5; N(1.0; 0, 0.5): z = 2
    log_p_params = (-0.5 * 0.5**2 - math.log(2.0) - half_log_2pi) + (-0.5 * 2.0**2 - math.log(0.5) - half_log_2pi)
    type_part, param_part = distribution().log_prob_parts(action)
    assert abs(type_part.item() - log_p_type) < 1e-6
    assert abs(param_part.item() - log_p_params) < 1e-5
    assert abs(distribution().log_prob(action).item() - (log_p_type + log_p_params)) < 1e-5
    # k = 0 with x_0 = 0.5 (its mean): only N(0.5; 0.5, 1) counts.
    action0 = th.tensor([[0.0, 0.5, 100.0, -100.0]])
    assert abs(distribution().log_prob(action0).item() - (math.log(0.25) - half_log_2pi)) < 1e-5


def test_entropy_by_hand():
    h_type = -(0.25 * math.log(0.25) + 0.75 * math.log(0.75))
    h_unit = 0.5 * math.log(2 * math.pi * math.e)  # N(0, 1)
    h_0 = h_unit  # sigma 1
    h_1 = (math.log(2.0) + h_unit) + (math.log(0.5) + h_unit)
    h_params = 0.25 * h_0 + 0.75 * h_1
    dist = distribution()
    type_part, param_part = dist.entropy_parts()
    assert abs(type_part.item() - h_type) < 1e-6
    assert abs(param_part.item() - h_params) < 1e-5
    assert abs(dist.entropy().item() - (h_type + h_params)) < 1e-5


def test_parameter_entropy_does_not_pull_the_types():
    """entropy_parts' weights are detached; entropy() is the exact joint entropy, differentiable in the logits."""
    logits, log_std = LOGITS.clone().requires_grad_(), LOG_STD.clone().requires_grad_()
    distribution(logits=logits, log_std=log_std).entropy_parts()[1].sum().backward()
    assert logits.grad is None and th.all(log_std.grad != 0)
    logits = LOGITS.clone().requires_grad_()
    distribution(logits=logits).entropy().sum().backward()
    assert logits.grad is not None and th.any(logits.grad != 0)


def test_mode_is_the_most_probable_type_and_its_means():
    mode = distribution().mode()
    assert th.equal(mode, th.tensor([[1.0, 0.5, -0.5, 0.0]]))


def test_sample_shape_and_types():
    th.manual_seed(0)
    logits = LOGITS.repeat(4000, 1)
    dist = distribution(logits=logits, mean=MEAN.repeat(4000, 1))
    sample = dist.sample()
    assert sample.shape == (4000, 4)
    assert abs((sample[:, 0] == 1).float().mean().item() - 0.75) < 0.03
    assert abs(sample[:, 3].std().item() - 0.5) < 0.03  # sigma of parameter 2


@st.composite
def hybrid_cases(draw):
    n_types = draw(st.integers(1, 4))
    dims = draw(st.lists(st.integers(0, 3), min_size=n_types, max_size=n_types).filter(lambda d: sum(d) > 0))
    param_type = np.repeat(np.arange(n_types), dims)
    floats = st.floats(-3.0, 3.0, allow_nan=False, width=32)
    n = len(param_type)
    logits = draw(st.lists(floats, min_size=n_types, max_size=n_types))
    mean = draw(st.lists(floats, min_size=n, max_size=n))
    log_std = draw(st.lists(st.floats(-2.0, 1.0, width=32), min_size=n, max_size=n))
    k = draw(st.integers(0, n_types - 1))
    x = draw(st.lists(floats, min_size=n, max_size=n))
    other_x = draw(st.lists(floats, min_size=n, max_size=n))
    other_mean = draw(st.lists(floats, min_size=n, max_size=n))
    return param_type, n_types, logits, mean, log_std, k, x, other_x, other_mean


@settings(max_examples=100, deadline=None)
@given(hybrid_cases())
def test_log_prob_counts_only_the_chosen_types_parameters(case):
    param_type, n_types, logits, mean, log_std, k, x, other_x, other_mean = case
    owned = param_type == k

    def log_prob(x_values, mean_values):
        dist = HybridDistribution(param_type, n_types).proba_distribution(
            th.tensor([logits]), th.as_tensor(np.asarray([mean_values]), dtype=th.float32), th.tensor(log_std)
        )
        return dist.log_prob(th.as_tensor(np.asarray([[k, *x_values]]), dtype=th.float32)).item()

    # The reference: log softmax(logits)[k] + sum over type k's parameters of the normal log-density.
    log_softmax = np.asarray(logits, dtype=np.float64) - np.logaddexp.reduce(np.asarray(logits, dtype=np.float64))
    expected = (
        log_softmax[k]
        + stats.norm.logpdf(np.asarray(x)[owned], np.asarray(mean)[owned], np.exp(np.asarray(log_std))[owned]).sum()
    )
    assert abs(log_prob(x, mean) - expected) <= 1e-3 * max(1.0, abs(expected))
    # Replacing every other type's parameters and means leaves the log-probability exactly as it was.
    x_changed = np.where(owned, x, other_x)
    mean_changed = np.where(owned, mean, other_mean)
    assert log_prob(x_changed, mean_changed) == log_prob(x, mean)


def test_the_type_part_is_torchs_categorical_bit_for_bit():
    """Log-probabilities, entropy, mode and seeded samples of the types are torch.distributions.Categorical's."""
    generator = th.Generator().manual_seed(0)
    logits = th.randn(64, 2, generator=generator) * 3
    dist = distribution(logits=logits, mean=MEAN.repeat(64, 1))
    categorical = th.distributions.Categorical(logits=logits)
    types = th.randint(0, 2, (64,), generator=generator)
    actions = th.cat((types.unsqueeze(1).float(), th.zeros(64, 3)), dim=1)
    assert th.equal(dist.log_prob_parts(actions)[0], categorical.log_prob(types))
    assert th.equal(dist.type_entropy(), categorical.entropy())
    assert th.equal(dist.mode()[:, 0].long(), categorical.logits.argmax(1))
    th.manual_seed(1)
    sampled = dist.sample()[:, 0].long()
    th.manual_seed(1)
    assert th.equal(sampled, categorical.sample())
