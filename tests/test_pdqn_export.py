"""P-DQN / MP-DQN in the .aacp format's pdqn head (format version 4, docs/export-format.md): the exported runtime (numpy
and numba) decides as ``predict(deterministic=True)``, the header is checked, and older readers name the version."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch as th

from sb3_aac import MPDQN, PDQN, RuntimePolicy, export_policy
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.runtime import format as policy_format
from sb3_aac.runtime import read_policy_file
from sb3_aac.runtime.forward import check_pdqn_head
from tests.helpers import LAYOUTS
from tests.test_export import load_bytes, observations, rewrite

N_OBS = 10_000  # observations compared per model, one at a time on each backend and as a batch
ALGORITHMS = {"PDQN": PDQN, "MPDQN": MPDQN}
# (algorithm, layout, policy_kwargs): both algorithms on every layout, two hidden layers; the tanh bounding and a
# leaky ReLU on one layout each.
CASES = [
    *((name, layout, {"net_arch": [16, 16]}) for name in ALGORITHMS for layout in LAYOUTS),
    ("PDQN", "shared", {"net_arch": [8], "param_bounding": "tanh"}),
    ("MPDQN", "flat", {"net_arch": [12], "activation_fn": th.nn.LeakyReLU, "param_bounding": "tanh"}),
]


def case_id(case: tuple[str, str, dict[str, Any]]) -> str:
    name, layout, kwargs = case
    extras = [kwargs["param_bounding"]] if "param_bounding" in kwargs else []
    return "-".join([name, layout, *extras])


def randomised_pdqn(name: str, layout: str, **policy_kwargs: Any) -> PDQN:
    """A P-DQN / MP-DQN model with random actor and Q weights under which every action type wins somewhere."""
    model = ALGORITHMS[name](
        "MlpPolicy", ParameterizedTargetEnv(layout=layout, n_types=3), seed=0, policy_kwargs=policy_kwargs
    )
    probe = observations(model, 2000)  # type: ignore[arg-type]  # a Box observation space, as SarsaAAC's
    networks = [*model.policy.actor.parameters(), *model.policy.q_net.parameters()]
    for attempt in range(50):
        generator = th.Generator().manual_seed(attempt)
        with th.no_grad():
            for param in networks:
                param.copy_(0.7 * th.randn(param.shape, generator=generator))
        types = [a[0] for a in model.predict(probe, deterministic=True)[0]]
        if min(np.unique(types, return_counts=True)[1]) >= 20 and len(set(types)) == 3:
            return model
    raise AssertionError(f"no seed gives {name} weights under which every type wins")


def chosen(action: tuple, layout: str, k: int) -> np.ndarray:
    """Type ``k``'s parameters (0-based) in an env action."""
    if layout in ("oneof", "shared"):
        return np.ravel(action[1])
    return np.ravel(action[1][k] if layout == "nested" else action[1 + k])


@pytest.mark.parametrize("case", CASES, ids=[case_id(case) for case in CASES])
def test_same_decisions_as_predict(case: tuple[str, str, dict[str, Any]], tmp_path: Path) -> None:
    """On 10,000 observations (20% outside the bounds): act() on both backends and act_batch give predict's types, and
    the chosen type's parameters within float32 rounding (predict computes in float32, the runtime in float64)."""
    name, layout, kwargs = case
    model = randomised_pdqn(name, layout, **kwargs)
    path = export_policy(model, tmp_path / "policy")
    obs = observations(model, N_OBS)  # type: ignore[arg-type]
    expected, _ = model.predict(obs, deterministic=True)
    spec = model.policy.spec
    types = np.array([int(a[0]) for a in expected])
    tolerance = 1e-5 * np.maximum(spec.high - spec.low, 1.0)
    for backend in ("numpy", "numba"):
        runtime = RuntimePolicy.load(path, backend=backend)
        assert runtime.backend == backend
        for o, e in zip(obs, expected, strict=True):
            k, params = runtime.act(o)
            assert k == int(e[0])
            want = chosen(e, layout, k - spec.start)
            assert params.shape == want.shape and params.dtype == want.dtype
            assert (np.abs(params - want) <= tolerance[spec.type_slice(k - spec.start)]).all()
    ks, all_params = runtime.act_batch(obs)
    np.testing.assert_array_equal(ks, types)
    _, want_scaled = spec.from_env(expected)
    owned = spec.param_type[None, :] == (types - spec.start)[:, None]  # the chosen type's columns
    assert (np.abs(all_params - spec.unscale(want_scaled)) <= tolerance)[owned].all()
    with th.no_grad():
        q, _, _ = model.policy.greedy(model.policy.features(th.as_tensor(obs[:100])))
    np.testing.assert_allclose(runtime.value(obs[:100]), q.max(1).values.numpy(), rtol=1e-4, atol=1e-4)


@pytest.fixture(scope="module")
def mpdqn_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    model = MPDQN("MlpPolicy", ParameterizedTargetEnv(n_types=3), seed=0, learning_starts=20, batch_size=16)
    model.learn(100)
    return export_policy(model, tmp_path_factory.mktemp("pdqn") / "mpdqn.aacp")


def test_header_is_version_4_with_the_two_networks(mpdqn_file: Path) -> None:
    header, arrays = read_policy_file(mpdqn_file)
    assert header["version"] == 4 and header["algorithm"] == "MPDQN" and header["policy_class"] == "PDQNPolicy"
    head = header["approximators"]["head"]
    k, p, d = header["action"]["n_types"], header["action"]["n_params"], header["observation"]["size"]
    assert head["type"] == "pdqn" and head["multi_pass"] is True
    assert [n["columns"] for n in head["networks"]] == [[k, k + p], [0, k]]
    assert head["networks"][1]["layers"][0] == {"type": "linear", "in": d + p, "out": 128}
    assert header["metadata"] == {"num_timesteps": 100}
    assert arrays["net0_2_bias"].shape == (p,)


def test_a_reader_that_predates_pdqn_names_the_version_it_needs(mpdqn_file: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(policy_format, "SUPPORTED_VERSIONS", (2, 3))
    with pytest.raises(ValueError, match=r"unknown format version 4; this reader supports versions \[2, 3\]"):
        RuntimePolicy.load(mpdqn_file)


def test_a_pdqn_head_needs_version_4(mpdqn_file: Path, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="pdqn head needs version >= 4"):
        load_bytes(tmp_path, rewrite(mpdqn_file, lambda h: h.update(version=3)))
    with pytest.raises(ValueError, match="missing array 'net1_0_weight'"):
        load_bytes(tmp_path, rewrite(mpdqn_file, arrays_edit=lambda a: a.pop("net1_0_weight")))


# A head on D = 2 inputs, K = 2 types of 1 and 2 parameters.
GOOD_HEAD = {
    "type": "pdqn",
    "multi_pass": False,
    "networks": [
        {"columns": [2, 5], "layers": [{"type": "linear", "in": 2, "out": 3}]},
        {"columns": [0, 2], "layers": [{"type": "linear", "in": 5, "out": 4}, {"type": "activation", "function": "relu"},
                                       {"type": "linear", "in": 4, "out": 2}]},
    ],
}  # fmt: skip


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda h: h.update(multi_pass=1), "multi_pass must be true or false"),
        (lambda h: h["networks"].pop(), "holds two networks"),
        (lambda h: h["networks"].reverse(), "in=2|in=5|columns"),
        (lambda h: h["networks"][1]["layers"][0].update({"in": 2}), "in=5"),
        (lambda h: h["networks"][0].update(columns=[2, 4]), "ends with 3 values"),
        (lambda h: h["networks"][1]["layers"][1].update(function="gelu"), "unknown activation"),
    ],
)
def test_bad_pdqn_heads_are_refused(edit, message: str) -> None:
    check_pdqn_head(GOOD_HEAD, 2, 2, 3)
    head = {**GOOD_HEAD, "networks": [{**n, "layers": [dict(layer) for layer in n["layers"]]} for n in GOOD_HEAD["networks"]]}
    edit(head)
    with pytest.raises(ValueError, match=message):
        check_pdqn_head(head, 2, 2, 3)


def test_unsupported_activations_are_refused(tmp_path: Path) -> None:
    model = PDQN("MlpPolicy", ParameterizedTargetEnv(), policy_kwargs={"activation_fn": th.nn.GELU})
    with pytest.raises(ValueError, match="Cannot export a GELU layer"):
        export_policy(model, tmp_path / "gelu.aacp")
    assert not list(tmp_path.iterdir())
