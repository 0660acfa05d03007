"""The format's "networks" head (version 3): the numpy forward pass against torch, the numba kernel against numpy, the
reader's checks, and the version an older reader sees."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch as th

from sb3_aac import RuntimePolicy, SarsaAAC, export_policy
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.runtime import format as policy_format
from sb3_aac.runtime import read_policy_file
from sb3_aac.runtime.forward import NetworkForward, check_networks, network_array_shapes
from sb3_aac.runtime.kernel import network_kernel, network_kernel_arguments
from tests.test_export import load_bytes, rewrite

# Every layer kind, an affine and a plain layer norm; two networks writing 3 and 2 columns.
NETWORKS = [
    {
        "columns": [0, 3],
        "layers": [
            {"type": "linear", "in": 4, "out": 6},
            {"type": "layernorm", "size": 6, "eps": 1e-5, "affine": True},
            {"type": "activation", "function": "tanh"},
            {"type": "linear", "in": 6, "out": 5},
            {"type": "activation", "function": "relu"},
            {"type": "linear", "in": 5, "out": 3},
        ],
    },
    {
        "columns": [3, 5],
        "layers": [
            {"type": "linear", "in": 4, "out": 7},
            {"type": "layernorm", "size": 7, "eps": 1e-3, "affine": False},
            {"type": "activation", "function": "leaky_relu", "slope": 0.1},
            {"type": "linear", "in": 7, "out": 2},
        ],
    },
]


def random_arrays(rng: np.random.Generator) -> dict[str, np.ndarray]:
    return {name: rng.normal(size=shape) for name, shape in network_array_shapes(NETWORKS).items()}


def torch_outputs(arrays: dict[str, np.ndarray], x: np.ndarray) -> np.ndarray:
    """The same networks built from torch modules."""
    columns = []
    for i, network in enumerate(NETWORKS):
        modules: list[th.nn.Module] = []
        for j, layer in enumerate(network["layers"]):
            if layer["type"] == "linear":
                module = th.nn.Linear(layer["in"], layer["out"], dtype=th.float64)
            elif layer["type"] == "layernorm":
                module = th.nn.LayerNorm(layer["size"], eps=layer["eps"], elementwise_affine=layer["affine"], dtype=th.float64)
            else:
                function = layer["function"]
                module = (
                    th.nn.Tanh()
                    if function == "tanh"
                    else th.nn.ReLU()
                    if function == "relu"
                    else th.nn.LeakyReLU(layer["slope"])
                )
            if f"net{i}_{j}_weight" in arrays:
                module.weight.data = th.as_tensor(arrays[f"net{i}_{j}_weight"])
                module.bias.data = th.as_tensor(arrays[f"net{i}_{j}_bias"])
            modules.append(module)
        with th.no_grad():
            columns.append(th.nn.Sequential(*modules)(th.as_tensor(x)).numpy())
    return np.concatenate(columns, axis=1)


def test_forward_pass_equals_torch() -> None:
    rng = np.random.default_rng(0)
    arrays = random_arrays(rng)
    mid, half = rng.normal(size=4), rng.uniform(0.5, 2.0, 4)
    net = NetworkForward(mid, half, NETWORKS, arrays, 5)
    obs = rng.normal(size=(500, 4)) * 3
    out, _ = net.outputs(net.features(obs))
    np.testing.assert_allclose(out, torch_outputs(arrays, (obs - mid) / half), rtol=1e-12, atol=1e-12)


def test_numba_kernel_decides_as_numpy() -> None:
    kernel = network_kernel()
    if kernel is None:
        pytest.skip("numba is not installed")
    rng = np.random.default_rng(1)
    arrays = random_arrays(rng)
    # Two types of one parameter each, then V: network 0 writes Q_0, Q_1 and the first parameter, network 1 the second
    # parameter and V.
    net = NetworkForward(rng.normal(size=4), rng.uniform(0.5, 2.0, 4), NETWORKS, arrays, 5)
    low, high, offsets = np.array([-1.0, 0.0]), np.array([1.0, 5.0]), (0, 1, 2)
    pack, meta, width = network_kernel_arguments(net, low, high, offsets)
    scratch, out, params = np.empty((3, width)), np.empty(5), np.empty(1)
    obs = rng.normal(size=(1000, 4)) * 3
    expected, _ = net.outputs(net.features(obs))
    types = set()
    for o, e in zip(obs, expected, strict=True):
        k, dim = kernel(o, pack, meta, scratch, out, params)
        np.testing.assert_allclose(out[:4], e[:4], rtol=1e-9, atol=1e-12)
        assert k == e[:2].argmax() and dim == 1
        p = 0.5 * e[2 + k]
        assert params[0] == pytest.approx(min(max(low[k] * (0.5 - p) + high[k] * (0.5 + p), low[k]), high[k]), abs=1e-12)
        types.add(k)
    assert types == {0, 1}
    assert kernel(np.array([np.nan, 0.0, 0.0, 0.0]), pack, meta, scratch, out, params)[0] == -1


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda n: n[1].update(columns=[2, 4]), "exactly once"),
        (lambda n: n[1]["layers"][0].update({"in": 5}), "in=4"),
        (lambda n: n[1]["layers"][2].update(function="gelu"), "unknown activation"),
        (lambda n: n[1]["layers"][1].update(eps=0.0), "eps > 0"),
        (lambda n: n[1]["layers"][1].update(eps=1), "eps > 0"),
        (lambda n: n[0]["layers"].append({"type": "dropout"}), "unknown layer type"),
        (lambda n: n[1]["layers"].pop(), "ends with 7 values"),
        (lambda n: n[0].update(columns=[3, 0]), "columns"),
    ],
)
def test_bad_networks_are_refused(edit, message: str) -> None:
    networks = [{"columns": list(n["columns"]), "layers": [dict(layer) for layer in n["layers"]]} for n in NETWORKS]
    edit(networks)
    with pytest.raises(ValueError, match=message):
        check_networks(networks, 4, 5)


@pytest.fixture(scope="module")
def deep_file(tmp_path_factory) -> Path:
    model = SarsaAAC("DeepPolicy", ParameterizedTargetEnv(n_types=3), seed=0, policy_kwargs={"net_arch": [8, 8]})
    model.learn(300)
    return export_policy(model, tmp_path_factory.mktemp("networks") / "deep.aacp")


def test_deep_files_are_version_3_and_others_stay_version_2(deep_file: Path, tmp_path: Path) -> None:
    header, arrays = read_policy_file(deep_file)
    assert header["version"] == 3 and header["approximators"]["head"]["type"] == "networks"
    assert header["approximators"]["features"] == {"type": "scaled", "n_features": header["observation"]["size"]}
    assert set(network_array_shapes(header["approximators"]["head"]["networks"])) <= set(arrays)
    rbf = export_policy(SarsaAAC("RbfPolicy", ParameterizedTargetEnv(n_types=3), seed=0), tmp_path / "rbf.aacp")
    assert read_policy_file(rbf)[0]["version"] == 2


def test_a_reader_that_predates_networks_names_the_version_it_needs(deep_file: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(policy_format, "SUPPORTED_VERSIONS", (2,))
    with pytest.raises(ValueError, match=r"unknown format version 3; this reader supports versions \[2\]"):
        RuntimePolicy.load(deep_file)


def test_a_networks_head_needs_version_3_and_scaled_features(deep_file: Path, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="networks head needs version >= 3"):
        load_bytes(tmp_path, rewrite(deep_file, lambda h: h.update(version=2)))

    def rbf_features(h):
        d = h["observation"]["size"]
        h["approximators"]["features"] = {"type": "rbf", "n_rbf": 2, "rbf_width": 1.0, "rbf_window": None, "n_features": 2 * d}

    with pytest.raises(ValueError, match="scaled features"):
        load_bytes(tmp_path, rewrite(deep_file, rbf_features))
    with pytest.raises(ValueError, match="missing array 'net1_3_weight'"):
        load_bytes(tmp_path, rewrite(deep_file, arrays_edit=lambda a: a.pop("net1_3_weight")))
