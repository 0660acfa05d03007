"""The networks of P-DQN and MP-DQN: the multi-pass property, inverting gradients, bounds and predict."""

import numpy as np
import pytest
import torch as th
from hypothesis import given, settings
from hypothesis import strategies as st

from sb3_aac import MPDQN, PDQN
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.common.spaces import ParameterizedActionSpec
from sb3_aac.pdqn.pdqn import invert_gradients
from sb3_aac.pdqn.policies import QNetwork
from tests.helpers import LAYOUTS


def q_network(multi_pass: bool, layout: str = "nested") -> tuple[QNetwork, ParameterizedActionSpec]:
    spec = ParameterizedActionSpec.from_space(ParameterizedTargetEnv(layout=layout).action_space)
    th.manual_seed(0)
    return QNetwork(2, spec, [32, 32], th.nn.ReLU, multi_pass), spec


@pytest.mark.parametrize("layout", LAYOUTS)
def test_multi_pass_q_k_ignores_other_types_parameters(layout):
    """MP-DQN: changing any parameter of type j != k leaves Q_k unchanged; changing type k's own changes it."""
    net, spec = q_network(multi_pass=True, layout=layout)
    rng = np.random.default_rng(0)
    features = th.as_tensor(rng.uniform(-1, 1, (64, 2)), dtype=th.float32)
    params = th.as_tensor(rng.uniform(-1, 1, (64, spec.n_params)), dtype=th.float32)
    q = net(features, params)
    for j in range(spec.n_types):
        changed = params.clone()
        changed[:, spec.type_slice(j)] = th.as_tensor(rng.uniform(-1, 1, (64, spec.dims[j])), dtype=th.float32)
        q_changed = net(features, changed)
        for k in range(spec.n_types):
            if k == j:
                assert not th.allclose(q_changed[:, k], q[:, k])
            else:
                assert th.equal(q_changed[:, k], q[:, k]), (j, k)


def test_multi_pass_gradient_of_q_k_is_zero_for_other_types():
    net, spec = q_network(multi_pass=True)
    params = th.zeros(4, spec.n_params, requires_grad=True)
    net(th.ones(4, 2), params)[:, 1].sum().backward()
    owned = spec.param_type == 1
    assert th.all(params.grad[:, ~owned] == 0) and th.any(params.grad[:, owned] != 0)


def test_single_pass_q_k_depends_on_other_types_parameters():
    """P-DQN's single pass (the false gradients MP-DQN removes): Q_0 moves with type 1's parameters."""
    net, spec = q_network(multi_pass=False)
    features, params = th.zeros(8, 2), th.zeros(8, spec.n_params)
    changed = params.clone()
    changed[:, spec.type_slice(1)] = 1.0
    assert not th.allclose(net(features, params)[:, 0], net(features, changed)[:, 0])


def test_multi_pass_equals_k_separate_passes():
    net, spec = q_network(multi_pass=True)
    features, params = th.randn(5, 2), th.randn(5, spec.n_params)
    for k in range(spec.n_types):
        only_k = th.where(th.as_tensor(spec.param_type == k), params, th.zeros(()))
        expected = net.net(th.cat((features, only_k), 1))[:, k]
        th.testing.assert_close(net(features, params)[:, k], expected)


@settings(max_examples=50, deadline=None)
@given(
    st.lists(st.floats(-1, 1), min_size=1, max_size=20),
    st.lists(st.floats(-10, 10), min_size=20, max_size=20),
)
def test_invert_gradients(params, grads):
    """The ascent direction shrinks toward the bound it points to, keeps its sign inside [-1, 1], and is 0 at it."""
    p = th.tensor(params, dtype=th.float64)
    g = th.tensor(grads[: len(params)], dtype=th.float64)
    out = invert_gradients(g, p)
    assert th.all(out * g >= 0)
    assert th.all(out.abs() <= g.abs())
    assert th.all(out[(p == 1) & (g > 0)] == 0) and th.all(out[(p == -1) & (g < 0)] == 0)


def test_invert_gradients_reverses_beyond_the_bounds():
    out = invert_gradients(th.tensor([1.0, -1.0]), th.tensor([1.5, -1.5]))
    th.testing.assert_close(out, th.tensor([-0.25, 0.25]))


def test_tanh_bounding_keeps_actor_output_inside():
    model = PDQN("MlpPolicy", ParameterizedTargetEnv(), policy_kwargs=dict(param_bounding="tanh"), seed=0)
    with th.no_grad():
        for p in model.policy.actor.parameters():
            p.mul_(0).add_(50.0)
        out = model.policy.actor(th.ones(10, 2))
    assert th.all(out.abs() <= 1)


@pytest.mark.parametrize("algo", [PDQN, MPDQN])
@pytest.mark.parametrize("layout", LAYOUTS)
def test_predict_single_and_batch(algo, layout):
    env = ParameterizedTargetEnv(layout=layout)
    model = algo("MlpPolicy", env, seed=0)
    obs = np.random.default_rng(0).uniform(-1, 1, (6, 2)).astype(np.float32)
    batch, state = model.predict(obs, deterministic=True)
    assert state is None and batch.dtype == object and batch.shape == (6,)
    for i in range(6):
        single, _ = model.predict(obs[i], deterministic=True)
        assert isinstance(single, tuple) and env.action_space.contains(single)
        assert single[0] == batch[i][0]
        env.reset(seed=0)
        env.step(single)  # the env accepts it
    # The greedy type is the argmax of Q(s, k, x(s)).
    with th.no_grad():
        q, _, k = model.policy.greedy(model.policy.features(th.as_tensor(obs)))
    assert np.array_equal(k.numpy(), q.argmax(1).numpy())
    types = [a[0] for a in batch] if layout == "oneof" else [a[0] - env.action_space[0].start for a in batch]
    assert np.array_equal(types, k.numpy())


def test_predict_rejects_wrong_shape():
    model = PDQN("MlpPolicy", ParameterizedTargetEnv(), seed=0)
    with pytest.raises(ValueError, match="Unexpected observation shape"):
        model.predict(np.zeros(3, np.float32))


def test_policy_forward_and_save_load(tmp_path):
    model = MPDQN("MlpPolicy", ParameterizedTargetEnv(), seed=0)
    obs = th.rand(4, 2) * 2 - 1
    out = model.policy(obs)
    assert out.shape == (4, 1 + model.policy.spec.n_params) and th.all(out[:, 1:].abs() <= 1)
    model.policy.save(tmp_path / "policy.pkl")
    loaded = type(model.policy).load(tmp_path / "policy.pkl")
    assert loaded.multi_pass
    th.testing.assert_close(loaded(obs), out)
