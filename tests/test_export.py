"""Exported policies (sb3_aac.export_policy / sb3_aac.RuntimePolicy) decide exactly as the model, and refuse bad files."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch as th

from sb3_aac import RuntimePolicy, SarsaAAC, export_policy
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.export import action_header, encode_policy_file
from sb3_aac.sarsa_aac.export import policy_arrays, policy_header
from sb3_aac.runtime import read_policy_file
from tests.helpers import LAYOUTS, POLICIES

N_OBS = 3000  # batched comparisons
N_SINGLE = 500  # one-observation comparisons, per backend


def randomised_model(policy: str, layout: str, seed: int = 0, **policy_kwargs) -> SarsaAAC:
    """A model with random weights under which every action type wins somewhere (the first such seed from ``seed``)."""
    model = SarsaAAC(policy, ParameterizedTargetEnv(layout=layout, n_types=3), seed=seed, policy_kwargs=policy_kwargs)
    probe = observations(model, 500)
    for attempt in range(seed, seed + 50):
        generator = th.Generator().manual_seed(attempt)
        with th.no_grad():
            for param in model.policy.approximators.parameters():
                param.copy_(th.randn(param.shape, generator=generator, dtype=param.dtype))
        model.policy.rebind()
        types = [a[0] for a in model.predict(probe, deterministic=True)[0]]
        if len(set(types)) == model.policy.n_types:
            return model
    raise AssertionError(f"no seed gives {policy} weights under which every type wins")


def observations(model: SarsaAAC, n: int = N_OBS, seed: int = 1) -> np.ndarray:
    space = model.observation_space
    span = space.high - space.low
    # Also 20% outside the bounds: predict does not clip observations, neither may the runtime.
    low, high = space.low - 0.2 * span, space.high + 0.2 * span
    return np.random.default_rng(seed).uniform(low, high, (n, *space.shape)).astype(np.float32)


def flat(value) -> np.ndarray:
    return np.concatenate([np.ravel(v) for v in value]) if isinstance(value, tuple) else np.ravel(value)


def assert_same_action(got: tuple, expected: tuple) -> None:
    assert type(got[0]) is type(expected[0]) or int(got[0]) == int(expected[0])
    assert int(got[0]) == int(expected[0])
    assert len(got) == len(expected)
    for g, e in zip(got[1:], expected[1:], strict=True):
        g_flat, e_flat = flat(g), flat(e)
        assert g_flat.dtype == e_flat.dtype
        # unscale may place a bound by the mid/half formula or by interpolation: at most an ulp apart.
        np.testing.assert_allclose(g_flat, e_flat, rtol=1e-6, atol=1e-6)


def chosen_params(action: tuple, layout: str, k: int) -> np.ndarray:
    """The parameters of the chosen (0-based) type ``k`` in an env action."""
    if layout in ("oneof", "shared"):
        return np.ravel(action[1])
    return np.ravel(action[1][k] if layout == "nested" else action[1 + k])


@pytest.fixture(scope="module")
def tmp_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("export")


@pytest.mark.parametrize("layout", LAYOUTS)
@pytest.mark.parametrize("policy", POLICIES)
def test_same_decisions_as_predict(policy: str, layout: str, tmp_dir: Path) -> None:
    if policy == "TilePolicy":
        model = randomised_model(policy, layout, tiles_per_input=5, n_tilings=3)
    elif policy == "DeepPolicy":
        model = randomised_model(policy, layout, net_arch=[16, 16])
    else:
        n_rbf, hidden_units = 7 if policy != "MlpPolicy" else None, None if policy == "RbfPolicy" else 4
        model = randomised_model(policy, layout, n_rbf=n_rbf, hidden_units=hidden_units)
    path = export_policy(model, tmp_dir / f"{policy}-{layout}")
    assert path.suffix == ".aacp"
    obs = observations(model)
    expected, _ = model.predict(obs, deterministic=True)
    spec = model.policy.spec
    types = np.array([a[0] for a in expected])
    assert len(np.unique(types)) == spec.n_types, "the test needs every type to be chosen somewhere"

    for backend in ("numpy",) if policy == "TilePolicy" else ("numpy", "numba"):
        runtime = RuntimePolicy.load(path, backend=backend)
        assert runtime.backend == backend
        # act(): one observation at a time, against predict on one observation
        for o, e in zip(obs[:N_SINGLE], expected[:N_SINGLE], strict=True):
            k, params = runtime.act(o)
            chosen = model.predict(o, deterministic=True)[0]
            assert k == int(chosen[0]) == int(e[0])
            want = chosen_params(chosen, layout, k - spec.start)
            assert params.shape == want.shape and params.dtype == want.dtype
            np.testing.assert_allclose(params, want, rtol=1e-6, atol=1e-6)

    runtime = RuntimePolicy.load(path, backend="numpy")
    # act_batch and predict(): the whole batch
    ks, params = runtime.act_batch(obs)
    np.testing.assert_array_equal(ks, types)
    got, _ = runtime.predict(obs)
    for g, e in zip(got, expected, strict=True):
        assert_same_action(g, e)
    assert_same_action(runtime.predict(obs[0])[0], model.predict(obs[0], deterministic=True)[0])
    # the critic comes along
    out, _ = model.policy.evaluate(obs[:50].astype(np.float64))
    np.testing.assert_allclose(runtime.value(obs[:50]), out[:, -1], rtol=1e-12, atol=1e-12)


def test_tile_files(tmp_dir: Path) -> None:
    """Tile policies run with numpy only, and a file whose grids reach past the table is refused."""
    model = randomised_model("TilePolicy", "nested", tiles_per_input=5, n_tilings=3)
    path = export_policy(model, tmp_dir / "tiles.aacp")
    assert RuntimePolicy.load(path).backend == "numpy"
    with pytest.raises(ValueError, match="dense features only"):
        RuntimePolicy.load(path, backend="numba")
    header, arrays = read_policy_file(path)
    arrays = {name: np.array(a) for name, a in arrays.items()}
    arrays["tile_bases"][-1] += 1
    bad = tmp_dir / "tiles-bad.aacp"
    bad.write_bytes(encode_policy_file({k: v for k, v in header.items() if k not in ("arrays", "blob_size")}, arrays))
    with pytest.raises(ValueError, match="reach past the"):
        RuntimePolicy.load(bad)


def test_dribbling_model_and_metadata(tmp_dir: Path) -> None:
    from robocup_dribble import DribbleVecEnv

    model = SarsaAAC("RbfPolicy", DribbleVecEnv(4, profile="v11"), seed=0).learn(500)
    path = export_policy(model, tmp_dir / "dribble.aacp", metadata={"env_id": "RoboCupDribblePaper-v0"})
    runtime = RuntimePolicy.load(path)
    assert runtime.header["metadata"] == {"env_id": "RoboCupDribblePaper-v0", "num_timesteps": 500}
    features = {"type": "rbf", "n_rbf": 10, "rbf_width": 1.0, "rbf_window": 5.0, "n_features": 100}
    assert runtime.header["approximators"]["features"] == features
    obs = observations(model, 2000)
    expected, _ = model.predict(obs, deterministic=True)
    for o, e in zip(obs, expected, strict=True):
        k, params = runtime.act(o)
        assert k == e[0]
        np.testing.assert_allclose(params, e[1][k], rtol=1e-6, atol=1e-6)


def test_runtime_imports_numpy_only(tmp_dir: Path) -> None:
    """The runtime package works copied out on its own: no torch, no SB3, not even the sb3_aac package."""
    model = randomised_model("RbfPolicy", "nested")
    path = export_policy(model, tmp_dir / "alone.aacp")
    source = Path(__file__).resolve().parents[1] / "sb3_aac" / "runtime"
    script = f"""
import importlib.util, sys
for name in ("torch", "stable_baselines3", "sb3_aac", "gymnasium"):
    sys.modules[name] = None  # any import of these fails
spec = importlib.util.spec_from_file_location(
    "runtime", {str(source / "__init__.py")!r}, submodule_search_locations=[{str(source)!r}]
)
runtime = sys.modules["runtime"] = importlib.util.module_from_spec(spec)
spec.loader.exec_module(runtime)
policy = runtime.RuntimePolicy.load({str(path)!r}, backend="numpy")
print(policy.act([0.1, -0.2])[0])
"""
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr
    assert int(result.stdout) == model.predict(np.array([0.1, -0.2], np.float32), deterministic=True)[0][0]


def test_importing_the_runtime_imports_no_ml_stack() -> None:
    """``sb3_aac``'s ``__init__`` loads the algorithms lazily: the runtime module imports no torch, SB3 or Gymnasium."""
    script = """
import sys
from sb3_aac.runtime import RuntimePolicy
import sb3_aac
print(sorted(name for name in ("torch", "stable_baselines3", "gymnasium") if name in sys.modules))
print(sb3_aac.RuntimePolicy is RuntimePolicy)
"""
    root = Path(__file__).resolve().parents[1]
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=root, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["[]", "True"]


def test_runtime_in_a_numpy_only_venv(tmp_path: Path) -> None:
    """As docs/export-format.md says: sb3_aac/runtime copied beside an agent, in a venv with numpy alone, acts the same."""
    model = randomised_model("RbfPolicy", "nested")
    policy_path = export_policy(model, tmp_path / "agent.aacp")
    obs = observations(model, 200)
    np.save(tmp_path / "obs.npy", obs)
    agent_dir = tmp_path / "agent"
    agent_dir.mkdir()
    source = Path(__file__).resolve().parents[1] / "sb3_aac" / "runtime"
    shutil.copytree(source, agent_dir / "runtime", ignore=shutil.ignore_patterns("__pycache__"))

    venv_dir = tmp_path / "venv"
    python = venv_dir / ("Scripts" if os.name == "nt" else "bin") / "python"
    for step, command in (
        ("create a venv", [sys.executable, "-m", "venv", str(venv_dir)]),
        ("pip install numpy", [str(python), "-m", "pip", "install", "-q", "--disable-pip-version-check", "numpy"]),
    ):
        made = subprocess.run(command, capture_output=True, text=True, check=False)
        if made.returncode != 0:
            pytest.skip(f"cannot {step} here (no venv/ensurepip module or no package index): {made.stderr[-500:]}")

    script = f"""
import importlib.util, json, sys
sys.path.insert(0, {str(agent_dir)!r})
missing = [name for name in ("torch", "stable_baselines3", "gymnasium", "sb3_aac", "numba")
           if importlib.util.find_spec(name) is not None]
assert not missing, f"the venv is not numpy-only: {{missing}}"
import numpy as np
import runtime
policy = runtime.RuntimePolicy.load({str(policy_path)!r})
decisions = map(policy.act, np.load({str(tmp_path / "obs.npy")!r}))
print(json.dumps([[action_type, params.tolist()] for action_type, params in decisions]))
"""
    # -I: no PYTHONPATH, no user site-packages, so nothing from this process's environment leaks in.
    result = subprocess.run([str(python), "-I", "-c", script], capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr
    decisions = json.loads(result.stdout)
    assert len(decisions) == len(obs)

    here = RuntimePolicy.load(policy_path, backend="numpy")
    for x, (action_type, params) in zip(obs, decisions, strict=True):
        expected_type, expected_params = here.act(x)
        assert action_type == expected_type
        np.testing.assert_array_equal(np.array(params, expected_params.dtype), expected_params)
        assert action_type == model.predict(x, deterministic=True)[0][0]


# ---------------------------------------------------------------------------------------------------- bad files


@pytest.fixture(scope="module")
def good_file(tmp_dir: Path) -> Path:
    return export_policy(randomised_model("RbfMlpPolicy", "flat", n_rbf=3, hidden_units=2), tmp_dir / "good.aacp")


def rewrite(path: Path, header_edit=None, arrays_edit=None) -> bytes:
    """The file re-encoded (with a valid checksum) after editing its header and/or arrays."""
    header, arrays = read_policy_file(path)
    header = {k: v for k, v in header.items() if k not in ("arrays", "blob_size")}
    arrays = {k: np.array(v) for k, v in arrays.items()}
    if header_edit:
        header_edit(header)
    if arrays_edit:
        arrays_edit(arrays)
    return encode_policy_file(header, arrays)


def load_bytes(tmp_dir: Path, data: bytes) -> RuntimePolicy:
    path = tmp_dir / "bad.aacp"
    path.write_bytes(data)
    return RuntimePolicy.load(path)


def test_good_file_round_trips(good_file: Path) -> None:
    header, arrays = read_policy_file(good_file)
    assert header["format"] == "sb3-aac-policy" and header["version"] == 2
    data = good_file.read_bytes()
    assert data[:8] == b"SB3AACP\x00"
    (header_len,) = struct.unpack_from("<Q", data, 8)
    assert (16 + header_len) % 8 == 0
    assert hashlib.sha256(data[:-32]).digest() == data[-32:]
    assert set(arrays) == {
        *("obs_low", "obs_high", "obs_mid", "obs_half", "param_low", "param_high"),
        *("rbf_centers", "rbf_widths", "weight1", "bias1", "weight2", "bias2"),
    }


@pytest.mark.parametrize("cut", [0, 10, 100, -33, -1])
def test_truncated(good_file: Path, tmp_dir: Path, cut: int) -> None:
    data = good_file.read_bytes()
    with pytest.raises(ValueError, match=r"truncated|checksum"):
        load_bytes(tmp_dir, data[:cut])


@pytest.mark.parametrize("where", [3, 20, 200, -40, -5])
def test_altered_byte(good_file: Path, tmp_dir: Path, where: int) -> None:
    data = bytearray(good_file.read_bytes())
    data[where] ^= 0x01
    with pytest.raises(ValueError, match=r"checksum|magic"):
        load_bytes(tmp_dir, bytes(data))


def test_trailing_garbage_and_pickle(good_file: Path, tmp_dir: Path) -> None:
    with pytest.raises(ValueError, match="checksum"):
        load_bytes(tmp_dir, good_file.read_bytes() + b"\x00" * 8)
    import pickle

    with pytest.raises(ValueError, match="magic"):
        load_bytes(tmp_dir, pickle.dumps({"a": 1}) * 4)


def test_unknown_version_and_format(good_file: Path, tmp_dir: Path) -> None:
    with pytest.raises(ValueError, match="unknown format version 5"):
        load_bytes(tmp_dir, rewrite(good_file, lambda h: h.update(version=5)))
    with pytest.raises(ValueError, match="format"):
        load_bytes(tmp_dir, rewrite(good_file, lambda h: h.update(format="other")))


def test_missing_or_misshapen_array(good_file: Path, tmp_dir: Path) -> None:
    with pytest.raises(ValueError, match="missing array 'weight2'"):
        load_bytes(tmp_dir, rewrite(good_file, arrays_edit=lambda a: a.pop("weight2")))
    with pytest.raises(ValueError, match="shape"):
        load_bytes(tmp_dir, rewrite(good_file, arrays_edit=lambda a: a.update(bias2=np.zeros(2))))
    with pytest.raises(ValueError, match="NaN"):
        load_bytes(tmp_dir, rewrite(good_file, arrays_edit=lambda a: a["weight1"].__setitem__((0, 0, 0), np.nan)))


def test_inconsistent_header(good_file: Path, tmp_dir: Path) -> None:
    def bad_dim(h):
        h["action"]["types"][1]["dim"] = 5

    def bad_layout(h):
        h["action"]["layout"] = "diagonal"

    def no_head(h):
        del h["approximators"]["head"]

    for edit, message in [(bad_dim, "disagree"), (bad_layout, "layout"), (no_head, "lacks")]:
        with pytest.raises(ValueError, match=message):
            load_bytes(tmp_dir, rewrite(good_file, edit))


def test_wrong_observations(good_file: Path) -> None:
    for backend in ("numpy", "numba"):
        runtime = RuntimePolicy.load(good_file, backend=backend)
        with pytest.raises(ValueError, match="shape"):
            runtime.act(np.zeros(3))
        with pytest.raises(ValueError, match="shape"):
            runtime.act(np.zeros((2, 2)))
        with pytest.raises(ValueError, match="NaN or inf"):
            runtime.act(np.array([np.nan, 0.0]))
        with pytest.raises(ValueError, match="NaN or inf"):
            runtime.act(np.array([np.inf, 0.0]))
    with pytest.raises(ValueError, match="shape"):
        runtime.act_batch(np.zeros((4, 3)))
    with pytest.raises(ValueError, match=r"Observation\(s\) \[1\]"):
        runtime.act_batch(np.array([[0.0, 0.0], [np.inf, 0.0]]))


def test_not_a_sarsa_model(tmp_dir: Path) -> None:
    with pytest.raises(ValueError, match="SarsaAAC model"):
        export_policy(object(), tmp_dir / "x.aacp")
    with pytest.raises(ValueError, match="backend"):
        RuntimePolicy({}, {}, backend="gpu")


def test_header_is_plain_json(good_file: Path) -> None:
    data = good_file.read_bytes()
    (header_len,) = struct.unpack_from("<Q", data, 8)
    header = json.loads(data[16 : 16 + header_len])
    model = randomised_model("RbfMlpPolicy", "flat", n_rbf=3, hidden_units=2)
    expected = policy_header(model.policy, action_header(model.policy.spec))
    for key in ("observation", "action", "approximators"):
        assert header[key] == expected[key]
    shapes = {name: list(a.shape) for name, a in policy_arrays(model.policy).items()}
    assert {name: entry["shape"] for name, entry in header["arrays"].items()} == shapes


# ---------------------------------------------------------------------------------------------------- hostile files


def header_only_file(text: bytes) -> bytes:
    """A file with the magic, a given header and a valid checksum (no arrays)."""
    from sb3_aac.runtime.format import MAGIC, PREAMBLE

    text += b" " * (-(PREAMBLE.size + len(text)) % 8)
    body = PREAMBLE.pack(MAGIC, len(text)) + text
    return body + hashlib.sha256(body).digest()


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom"])
def test_a_link_to_an_endless_file_is_refused_at_once(tmp_dir: Path, device: str) -> None:
    if not Path(device).exists():
        pytest.skip(f"no {device}")
    link = tmp_dir / f"{Path(device).name}.aacp"
    link.unlink(missing_ok=True)
    link.symlink_to(device)
    with pytest.raises(ValueError, match="not a regular file"):
        RuntimePolicy.load(link)


def test_endless_stream_is_read_header_first(tmp_dir: Path) -> None:
    """Through an open stream (as a pipe would give), only the preamble is read before the magic is checked, and a
    lying header length is refused before it is read."""
    from sb3_aac.runtime.format import MAGIC, PREAMBLE

    class Endless:
        def __init__(self, start: bytes):
            self.start, self.served = start, 0

        def read(self, n: int) -> bytes:
            self.served += n
            return (self.start + b"\0" * n)[:n] if self.served == n else b"\0" * n

    import sb3_aac.runtime.format as runtime

    for start, message in [(b"", "magic"), (PREAMBLE.pack(MAGIC, 2**40), "header length")]:
        stream = Endless(start)
        try:
            runtime.open = lambda *args, _stream=stream, **kwargs: contextlib.nullcontext(_stream)  # type: ignore[attr-defined]
            with pytest.raises(ValueError, match=message):
                read_policy_file(tmp_dir / "good.aacp")
        finally:
            del runtime.open
        assert stream.served <= PREAMBLE.size


@pytest.mark.parametrize("nesting", [b"[" * 100_000 + b"]" * 100_000, b'{"a":' * 50_000 + b"1" + b"}" * 50_000])
def test_a_deeply_nested_header_is_a_value_error(tmp_dir: Path, nesting: bytes) -> None:
    with pytest.raises(ValueError, match="nests too deeply"):
        load_bytes(tmp_dir, header_only_file(nesting))


def test_negative_float_and_bool_sizes_are_refused(good_file: Path, tmp_dir: Path) -> None:
    def negative_shape(h):
        h["action"]["types"][1]["shape"] = [-1, -h["action"]["types"][1]["dim"]]

    def float_shape(h):
        h["observation"]["shape"] = [float(h["observation"]["size"])]

    def float_dim(h):
        dim = h["action"]["types"][0]["dim"]
        h["action"]["types"][0].update(dim=float(dim), shape=[float(dim)])

    def bool_start(h):
        h["action"]["type_start"] = True

    def huge(h):
        h["observation"].update(size=10**12, shape=[10**12])
        h["approximators"]["features"]["n_features"] = 10**12 * h["approximators"]["features"]["n_rbf"]

    for edit in (negative_shape, float_shape, float_dim, bool_start, huge):
        with pytest.raises(ValueError, match="not a usable sb3-aac policy file"):
            load_bytes(tmp_dir, rewrite(good_file, edit))


def test_not_a_regular_file(tmp_dir: Path) -> None:
    (tmp_dir / "folder.aacp").mkdir(exist_ok=True)
    with pytest.raises(ValueError, match="not a regular file"):
        RuntimePolicy.load(tmp_dir / "folder.aacp")
    fifo = tmp_dir / "fifo.aacp"
    fifo.unlink(missing_ok=True)
    os.mkfifo(fifo)  # opening it to read would wait for a writer
    with pytest.raises(ValueError, match="not a regular file"):
        RuntimePolicy.load(fifo)
    with pytest.raises(FileNotFoundError):
        RuntimePolicy.load(tmp_dir / "absent.aacp")


def test_export_into_a_folder_that_is_a_file_names_it(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("not a folder")
    model = randomised_model("RbfPolicy", "nested")
    for target in (tmp_path / "file" / "policy.aacp", tmp_path / "file" / "sub" / "policy.aacp"):
        with pytest.raises(NotADirectoryError, match="its folder, or one above it, is a file, not a folder"):
            export_policy(model, target)


def test_load_accepts_the_name_export_was_given(tmp_dir: Path, monkeypatch) -> None:
    model = randomised_model("RbfPolicy", "flat", n_rbf=3)
    monkeypatch.chdir(tmp_dir)
    assert export_policy(model, "policy") == Path("policy.aacp")
    assert RuntimePolicy.load("policy").header["format"] == "sb3-aac-policy"
    assert export_policy(model, tmp_dir / "sub" / "named") == tmp_dir / "sub" / "named.aacp"
    assert RuntimePolicy.load(tmp_dir / "sub" / "named").n_types == 3
    assert not [p for p in tmp_dir.rglob(".*")], "a stray temporary"


PAPER_RBF_POLICIES = [("RbfPolicy", {"n_rbf": 10}), ("RbfPolicy", {"n_rbf": 50}), ("RbfMlpPolicy", {"hidden_units": 2})]


@pytest.mark.parametrize(("policy", "policy_kwargs"), PAPER_RBF_POLICIES)
def test_rbf_window_decides_as_dense_evaluation(policy: str, policy_kwargs: dict, tmp_dir: Path) -> None:
    """A trained paper policy with the default RBF window decides as the dense evaluation of the same weights on
    thousands of observations, within the documented bound on the values; the exported runtime (both backends)
    decides as predict."""
    from robocup_dribble import DribbleVecEnv

    from sb3_aac.runtime.forward import BankForward

    model = SarsaAAC(policy, DribbleVecEnv(8, profile="v11"), seed=0, policy_kwargs=policy_kwargs).learn(2000)
    bank = model.policy.approximators
    assert bank.rbf_window == 5.0
    obs = observations(model, N_OBS).astype(np.float64)
    windowed, _ = model.policy.evaluate(obs)
    arrays = bank.arrays()
    dense = BankForward(**arrays).outputs(BankForward(**arrays).features(obs))[0]
    k = model.policy.n_types
    np.testing.assert_array_equal(windowed[:, :k].argmax(1), dense[:, :k].argmax(1))
    # |difference| <= exp(-r**2 / 2) * sum of |weights| on the dropped features (through tanh's slope <= 1 and the
    # output weights for an MLP head).
    dropped = (BankForward(**arrays).features(obs) > 0) & (model.policy.kernel().features(obs) == 0)
    first_layer = np.abs(arrays["weight"] if bank.hidden_units is None else arrays["weight1"].reshape(-1, bank.n_features))
    bound = np.exp(-12.5) * (dropped @ first_layer.T)
    if bank.hidden_units is not None:
        bound = (bound.reshape(len(obs), -1, bank.hidden_units) * np.abs(arrays["weight2"])).sum(-1)
    assert (np.abs(windowed - dense) <= bound + 1e-12).all()
    path = export_policy(model, tmp_dir / f"window-{policy}")
    expected, _ = model.predict(obs[:N_SINGLE], deterministic=True)
    for backend in ("numpy", "numba"):
        runtime = RuntimePolicy.load(path, backend=backend)
        for o, e in zip(obs[:N_SINGLE], expected, strict=True):
            assert runtime.act(o)[0] == int(e[0])


def test_rbf_window_header_is_checked(good_file: Path, tmp_dir: Path) -> None:
    def bad_window(h):
        h["approximators"]["features"]["rbf_window"] = -1.0

    with pytest.raises(ValueError, match="rbf_window"):
        load_bytes(tmp_dir, rewrite(good_file, bad_window))


def test_only_version_2_is_read_and_rbf_features_name_their_window(good_file: Path, tmp_dir: Path) -> None:
    def version_1(h):
        h["version"] = 1

    def no_window(h):
        del h["approximators"]["features"]["rbf_window"]

    with pytest.raises(ValueError, match=r"unknown format version 1; this reader supports versions \[2, 3, 4\]"):
        load_bytes(tmp_dir, rewrite(good_file, version_1))
    with pytest.raises(ValueError, match=r"lacks or mistypes a required field.*rbf_window"):
        load_bytes(tmp_dir, rewrite(good_file, no_window))
    assert RuntimePolicy.load(good_file)._bank.window_z2 == 12.5
