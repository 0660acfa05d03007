"""HybridPPO's .aacp networks head (format version 3, docs/export-format.md), computed by the documented formulas."""

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.torch_layers import FlattenExtractor

from sb3_aac import HybridPPO
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.hppo.export import export_contents
from sb3_aac.runtime.actions import unscale
from tests.helpers import LAYOUTS

SMALL = dict(n_steps=32, batch_size=32, n_epochs=2)


def documented_outputs(header, arrays, obs):
    """Steps 1-3 of 'Computing an action' with the networks head: the A outputs for each row of ``obs``."""
    x = (obs.reshape(len(obs), -1) - arrays["obs_mid"]) / arrays["obs_half"]
    outputs = np.zeros((len(obs), header["approximators"]["n_outputs"]))
    for i, network in enumerate(header["approximators"]["head"]["networks"]):
        h = x
        for j, layer in enumerate(network["layers"]):
            if layer["type"] == "linear":
                h = h @ arrays[f"net{i}_{j}_weight"].T + arrays[f"net{i}_{j}_bias"]
            elif layer["function"] == "tanh":
                h = np.tanh(h)
            elif layer["function"] == "relu":
                h = np.maximum(h, 0.0)
            else:
                h = np.where(h > 0, h, layer["slope"] * h)
        start, stop = network["columns"]
        outputs[:, start:stop] = h
    return outputs


@pytest.mark.parametrize(
    "layout, policy_kwargs",
    zip(
        LAYOUTS,
        [
            {},
            dict(net_arch=dict(shared=[16], type=[8], params=[], vf=[8]), activation_fn=th.nn.ReLU),
            dict(net_arch=[8], activation_fn=th.nn.LeakyReLU, features_extractor_class=FlattenExtractor),
            dict(net_arch=dict(shared=[8], type=[], params=[], vf=[])),
        ],
        strict=True,
    ),
)
def test_documented_forward_gives_the_mode(layout, policy_kwargs):
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(layout=layout), seed=0, policy_kwargs=policy_kwargs, **SMALL)
    model.learn(64)
    header, arrays = export_contents(model.policy, {"env_id": "toy"})
    assert header["version"] == 3 and header["algorithm"] == "HybridPPO"
    obs = np.random.default_rng(0).uniform(-1, 1, (50, 2)).astype(np.float32)
    outputs = documented_outputs(header, arrays, obs.astype(np.float64))
    spec = model.policy.spec
    k_expected, params_expected = spec.from_env(model.predict(obs, deterministic=True)[0])
    q = outputs[:, slice(*header["approximators"]["outputs"]["q"])]
    np.testing.assert_array_equal(q.argmax(1), k_expected)  # step 4: argmax of the Q columns is the mode
    params = unscale(
        arrays["param_low"], arrays["param_high"], outputs[:, slice(*header["approximators"]["outputs"]["params"])]
    )
    for row, k in enumerate(k_expected):  # step 5: the chosen type's parameters, clipped to the bounds
        np.testing.assert_allclose(
            spec.scale(params[row])[spec.type_slice(k)], params_expected[row][spec.type_slice(k)], atol=1e-5
        )
    with th.no_grad():
        values = model.policy.predict_values(th.as_tensor(obs)).numpy()
    np.testing.assert_allclose(outputs[:, header["approximators"]["outputs"]["value"]], values, atol=1e-5)
    assert all(a.dtype == np.float64 and a.flags.c_contiguous for a in arrays.values())


def test_unsupported_layers_are_refused():
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(), policy_kwargs=dict(activation_fn=th.nn.GELU), **SMALL)
    with pytest.raises(ValueError, match="Cannot export a GELU layer"):
        export_contents(model.policy)
