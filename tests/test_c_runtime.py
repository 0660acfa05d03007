"""The C runtime (sb3_aac/runtime/c/aacp.h) decides as RuntimePolicy.act and refuses what the Python reader refuses.

The header is compiled once per session with the machine's ``cc`` into the driver tests/c_runtime/aacp_check.c,
with warnings as errors and a second time under AddressSanitizer and UndefinedBehaviorSanitizer; without a C
compiler (or a sanitizer runtime) these tests are skipped, saying so.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import re
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sb3_aac import RuntimePolicy, export_policy
from sb3_aac.export import encode_policy_file
from sb3_aac.runtime.format import MAGIC, PREAMBLE, read_policy_file
from sb3_aac.runtime.c import header_path
from tests.helpers import LAYOUTS, POLICIES
from tests.test_export import header_only_file, observations, randomised_model, rewrite
from tests.test_file_properties import CUTS, FLIPS, JSON_VALUES, SECTIONS, damaged
from tests.test_pdqn_export import ALGORITHMS, randomised_pdqn

ROOT = Path(__file__).resolve().parents[1]
DRIVER = ROOT / "tests" / "c_runtime" / "aacp_check.c"
EXAMPLE = ROOT / "examples" / "c" / "dribble_agent.cpp"
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]
SANITIZE = ["-O1", "-g", "-fno-omit-frame-pointer", "-fsanitize=address,undefined", "-fno-sanitize-recover=all"]
SANITIZER_ENV = {"ASAN_OPTIONS": "detect_leaks=1:abort_on_error=0", "UBSAN_OPTIONS": "print_stacktrace=1"}
N_OBS = 10_000  # observations compared per policy file
N_CORPUS = 150  # damaged and crafted files drawn from each of the Python reader's hypothesis strategies
REFUSED = "is not a usable sb3-aac policy file"


def compile_c(compiler: str, flags: list[str], source: Path, out: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    command = [compiler, *flags, "-I", str(header_path().parent), str(source), "-o", str(out), *extra]
    return subprocess.run(command, capture_output=True, text=True, check=False)


@pytest.fixture(scope="session")
def drivers(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path | str]:
    """The driver built strictly (``"strict"``) and under the sanitizers (``"sanitized"``, or why it could not be)."""
    compiler = shutil.which("cc")
    if compiler is None:
        pytest.skip("no C compiler (cc) on PATH")
    folder = tmp_path_factory.mktemp("c_runtime")
    built = compile_c(compiler, [*STRICT, "-O2"], DRIVER, folder / "aacp_check", "-lm")
    assert built.returncode == 0, built.stderr
    found: dict[str, Path | str] = {"strict": folder / "aacp_check"}
    probe = folder / "probe.c"
    probe.write_text("int main(void) { return 0; }\n")
    if compile_c(compiler, SANITIZE, probe, folder / "probe").returncode != 0:
        found["sanitized"] = "this cc cannot build with -fsanitize=address,undefined (no sanitizer runtime)"
    else:
        built = compile_c(compiler, [*STRICT, *SANITIZE], DRIVER, folder / "aacp_check_sanitized", "-lm")
        assert built.returncode == 0, built.stderr
        found["sanitized"] = folder / "aacp_check_sanitized"
    return found


def run(driver: Path, *args: str) -> str:
    """The driver's stdout; it must exit 0 with nothing on stderr (no sanitizer report)."""
    result = subprocess.run(
        [str(driver), *args], capture_output=True, check=False, timeout=300, env={**os.environ, **SANITIZER_ENV}
    )
    stderr = result.stderr.decode(errors="replace")
    assert result.returncode == 0 and not stderr, f"{driver.name} {args[:2]}: exit {result.returncode}\n{stderr[-3000:]}"
    return result.stdout.decode(errors="replace")


def builds(drivers: dict[str, Path | str]) -> list[Path]:
    """Both builds, or the strict one alone when there is no sanitizer runtime."""
    return [d for d in (drivers["strict"], drivers["sanitized"]) if isinstance(d, Path)]


# ------------------------------------------------------------------------------------------------ same decisions


def policy_kinds() -> dict[str, tuple[str, str, dict]]:
    """Every policy kind under every layout (as tests/test_export.py exports them), plus the RBF window at work, and
    P-DQN / MP-DQN under every layout (as tests/test_pdqn_export.py exports them) and with tanh-bounded parameters."""
    kinds = {}
    for policy in POLICIES:
        for layout in LAYOUTS:
            if policy == "TilePolicy":
                kwargs: dict = {"tiles_per_input": 5, "n_tilings": 3}
            elif policy == "DeepPolicy":
                kwargs = {"net_arch": [8, 8]}
            else:
                kwargs = {"n_rbf": 7 if policy != "MlpPolicy" else None, "hidden_units": None if policy == "RbfPolicy" else 4}
            kinds[f"{policy}-{layout}"] = (policy, layout, kwargs)
    # 50 RBFs per input: the window keeps about 11 of them
    kinds["RbfPolicy-window"] = ("RbfPolicy", "nested", {"n_rbf": 50})
    kinds["RbfMlpPolicy-window"] = ("RbfMlpPolicy", "flat", {"n_rbf": 30, "hidden_units": 3})
    for algorithm in ALGORITHMS:
        for layout in LAYOUTS:
            kinds[f"{algorithm}-{layout}"] = (algorithm, layout, {"net_arch": [16, 16]})
        kinds[f"{algorithm}-tanh"] = (algorithm, "shared", {"net_arch": [8], "param_bounding": "tanh"})
    return kinds


KINDS = policy_kinds()


@pytest.fixture(scope="module")
def policy_files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, np.ndarray]]:
    folder = tmp_path_factory.mktemp("policies")
    files = {}
    for name, (policy, layout, kwargs) in KINDS.items():
        model = (
            randomised_pdqn(policy, layout, **kwargs) if policy in ALGORITHMS else randomised_model(policy, layout, **kwargs)
        )
        files[name] = (export_policy(model, folder / name), observations(model, N_OBS))  # type: ignore[arg-type]
    return files


@pytest.mark.parametrize("name", list(KINDS))
def test_same_decisions_as_runtime_policy(name: str, policy_files, drivers, tmp_path: Path) -> None:
    """On 10,000 observations (20% outside the bounds): the same action types as RuntimePolicy.act, and parameters
    within 1e-5 of act()'s (cast to their Box dtype, float32) and within 1e-9 of the float64 batch values; both
    builds identical."""
    path, obs = policy_files[name]
    assert_same_decisions(path, obs, drivers, tmp_path)


def assert_same_decisions(path: Path, obs: np.ndarray, drivers, tmp_path: Path, every_type: bool = True) -> None:
    flat = obs.reshape(len(obs), -1).astype(np.float64)
    flat.tofile(tmp_path / "obs.bin")
    outputs = []
    for driver in builds(drivers):
        run(driver, "act", str(path), str(tmp_path / "obs.bin"), str(tmp_path / "out.bin"))
        outputs.append(np.fromfile(tmp_path / "out.bin").reshape(len(obs), -1))
    for other in outputs[1:]:
        np.testing.assert_array_equal(other, outputs[0])
    c_out = outputs[0]
    runtime = RuntimePolicy.load(path)  # as users load it: numba when importable (its equality to numpy: test_export)
    _, batch_params = runtime.act_batch(flat)
    decisions = [runtime.act(o) for o in flat]
    types = np.array([k for k, _ in decisions])
    np.testing.assert_array_equal(c_out[:, 0], types)
    # act()'s parameters and the float64 batch values of the chosen type, NaN-padded as the driver writes them
    width = c_out.shape[1] - 1
    python = np.full((len(obs), width), np.nan)
    exact = np.full((len(obs), width), np.nan)
    for i, (k, params) in enumerate(decisions):
        python[i, : len(params)] = params
        exact[i, : len(params)] = batch_params[i, runtime.type_slice(k - runtime.type_start)]
    np.testing.assert_array_equal(np.isnan(c_out[:, 1:]), np.isnan(python))
    assert np.nanmax(np.abs(c_out[:, 1:] - python), initial=0.0) <= 1e-5
    assert np.nanmax(np.abs(c_out[:, 1:] - exact), initial=0.0) <= 1e-9
    if every_type:
        assert len(set(types.tolist())) == runtime.n_types, "every action type must be chosen somewhere"


NO_NETWORKS = (
    "this checkout's Python reader has no networks head (format version 3, DeepPolicy: branch deep), so there is "
    "nothing to compare the C runtime's networks with"
)


def networks_supported() -> bool:
    from sb3_aac.runtime import format as policy_format

    return 3 in policy_format.SUPPORTED_VERSIONS


def every_layer_kind(path: Path, seed: int) -> bytes:
    """A DeepPolicy file rewritten with random networks that use every layer kind and group the columns unevenly:
    network 0 writes Q (linear, affine layer norm, tanh, linear, relu, linear), network 1 the first two parameters
    (linear, plain layer norm, leaky ReLU, linear), network 2 the other parameters and V (one linear layer)."""
    header, arrays = read_policy_file(path)
    header = {k: v for k, v in header.items() if k not in ("arrays", "blob_size")}
    d, k, a = header["observation"]["size"], header["action"]["n_types"], header["approximators"]["n_outputs"]
    networks = [
        {"columns": [0, k], "layers": [
            {"type": "linear", "in": d, "out": 6}, {"type": "layernorm", "size": 6, "eps": 1e-5, "affine": True},
            {"type": "activation", "function": "tanh"}, {"type": "linear", "in": 6, "out": 5},
            {"type": "activation", "function": "relu"}, {"type": "linear", "in": 5, "out": k}]},
        {"columns": [k, k + 2], "layers": [
            {"type": "linear", "in": d, "out": 7}, {"type": "layernorm", "size": 7, "eps": 1e-3, "affine": False},
            {"type": "activation", "function": "leaky_relu", "slope": 0.1}, {"type": "linear", "in": 7, "out": 2}]},
        {"columns": [k + 2, a], "layers": [{"type": "linear", "in": d, "out": a - k - 2}]},
    ]  # fmt: skip
    header["approximators"]["head"] = {"type": "networks", "networks": networks}
    from sb3_aac.runtime.forward import network_array_shapes  # type: ignore[attr-defined]  # only with branch deep

    rng = np.random.default_rng(seed)
    kept = {name: np.array(arrays[name]) for name in ("obs_low", "obs_high", "obs_mid", "obs_half", "param_low", "param_high")}
    random = {name: rng.normal(size=shape) for name, shape in network_array_shapes(networks).items()}
    return encode_policy_file(header, {**kept, **random})


@pytest.mark.skipif(not networks_supported(), reason=NO_NETWORKS)
@pytest.mark.parametrize("layout", LAYOUTS)
def test_networks_decide_as_runtime_policy(layout: str, drivers, tmp_path: Path) -> None:
    """A DeepPolicy export (version 3, networks head), and the same file with networks of every layer kind: the
    decisions of RuntimePolicy.act on 10,000 observations, as for the other kinds."""
    from sb3_aac import SarsaAAC
    from sb3_aac.common.envs import ParameterizedTargetEnv

    env = ParameterizedTargetEnv(layout=layout, n_types=3)
    model = SarsaAAC("DeepPolicy", env, seed=0, policy_kwargs={"net_arch": [8, 8]}).learn(300)
    path = export_policy(model, tmp_path / "deep.aacp")
    obs = observations(model, N_OBS)
    assert_same_decisions(path, obs, drivers, tmp_path, every_type=False)
    for seed in range(20):  # the first random networks under which every type wins somewhere
        (tmp_path / "layers.aacp").write_bytes(every_layer_kind(path, seed))
        types = RuntimePolicy.load(tmp_path / "layers.aacp").act_batch(obs.reshape(len(obs), -1))[0]
        if len(set(types.tolist())) == 3:
            break
    assert_same_decisions(tmp_path / "layers.aacp", obs, drivers, tmp_path)


# ------------------------------------------------------------------------------------------------ refused files


def file_bytes(text: bytes, blob: bytes) -> bytes:
    """A file of a header text (space-padded) and a blob, with a valid checksum."""
    text += b" " * (-(PREAMBLE.size + len(text)) % 8)
    body = PREAMBLE.pack(MAGIC, len(text)) + text + blob
    return body + hashlib.sha256(body).digest()


def raw_file(header: dict, blob: bytes) -> bytes:
    """A file with a given header (its arrays table and blob_size as given) and a valid checksum."""
    return file_bytes(json.dumps(header).encode(), blob)


def header_and_blob(path: Path) -> tuple[dict, bytes]:
    data = path.read_bytes()
    (length,) = struct.unpack_from("<Q", data, 8)
    return json.loads(data[16 : 16 + length]), data[16 + length : -32]


def explicit_cases(good: Path, tiles: Path) -> list[tuple[str, bytes, str | None]]:
    """(label, file bytes, a pattern the C message must hold or None): tests/test_export.py's bad files and more."""
    data = good.read_bytes()
    cases: list[tuple[str, bytes, str | None]] = [
        (f"cut {cut}", data[:cut], "truncated|checksum") for cut in (0, 10, 100, -33, -1)
    ]
    for where in (3, 20, 200, -40, -5):
        altered = bytearray(data)
        altered[where] ^= 0x01
        cases.append((f"byte {where}", bytes(altered), "checksum|magic"))
    cases += [
        ("trailing", data + b"\0" * 8, "checksum|announces"),
        ("pickle", pickle.dumps({"a": 1}) * 4, "magic"),
        ("header length 2**40", PREAMBLE.pack(MAGIC, 2**40) + b"\0" * 64, "header length"),
        ("header length odd", PREAMBLE.pack(MAGIC, 13) + b"\0" * 64, "header length"),
        ("deep arrays", header_only_file(b"[" * 100_000 + b"]" * 100_000), "nests too deeply"),
        ("deep objects", header_only_file(b'{"a":' * 50_000 + b"1" + b"}" * 50_000), "nests too deeply"),
        ("not JSON", header_only_file(b"{'format': 1}"), "JSON"),
        ("not UTF-8", header_only_file(b'{"format": "\xff"}'), "UTF-8"),
        ("BOM", header_only_file(b"\xef\xbb\xbf{}"), "JSON"),
        ("empty header", header_only_file(b""), "JSON"),
        ("a list", header_only_file(b"[1, 2]"), "format"),
    ]

    def edit(label: str, change, pattern: str | None, arrays=None, path: Path = good) -> None:
        cases.append((label, rewrite(path, change, arrays), pattern))

    def set_in(*keys, value):
        def change(h):
            target = h
            for key in keys[:-1]:
                target = target[key]
            target[keys[-1]] = value

        return change

    edit("version 5", set_in("version", value=5), "unknown format version 5")
    edit("format other", set_in("format", value="other"), "format")
    edit("version 1", set_in("version", value=1), "unknown format version 1")
    edit("version 2.0", set_in("version", value=2.0), None)  # Python: 2.0 == 2
    edit("version true", set_in("version", value=True), "unknown format version")
    edit("version '2'", set_in("version", value="2"), "version")
    edit("no weight2", None, "missing array 'weight2'", lambda a: a.pop("weight2"))
    edit("bias2 shape", None, "shape", lambda a: a.update(bias2=np.zeros(2)))
    edit("NaN weight", None, "NaN", lambda a: a["weight1"].__setitem__((0, 0, 0), np.nan))
    edit("inf bias", None, "NaN or inf", lambda a: a["bias1"].__setitem__((0, 0), np.inf))
    edit("NaN obs_low", None, "NaN", lambda a: a["obs_low"].__setitem__(0, np.nan))
    edit("-inf obs_low", None, None, lambda a: a["obs_low"].__setitem__(0, -np.inf))  # bounds may be infinite
    edit("obs_half 0", None, "obs_half", lambda a: a["obs_half"].__setitem__(0, 0.0))
    edit("param_low > high", None, "param_low", lambda a: a["param_low"].__setitem__(0, 1e9))
    edit("rbf width 0", None, "rbf_widths", lambda a: a["rbf_widths"].__setitem__((0, 0), 0.0))
    edit("extra array", None, None, lambda a: a.update(notes=np.ones(3)))  # unknown arrays are ignored
    edit("bad dim", lambda h: h["action"]["types"][1].update(dim=5), "disagree")
    edit("bad layout", set_in("action", "layout", value="diagonal"), "layout")
    edit("no head", lambda h: h["approximators"].pop("head"), "lacks")
    edit("negative shape", lambda h: h["action"]["types"][1].update(shape=[-1, -h["action"]["types"][1]["dim"]]), "disagree")
    edit("float shape", lambda h: h["observation"].update(shape=[float(h["observation"]["size"])]), "disagree")
    edit("bool start", set_in("action", "type_start", value=True), "type_start")
    edit("negative start", set_in("action", "type_start", value=-3), None)
    edit("start 2**70", set_in("action", "type_start", value=2**70), "type_start")  # Python takes it; C refuses

    def huge(h):
        h["observation"].update(size=10**12, shape=[10**12])
        h["approximators"]["features"]["n_features"] = 10**12 * h["approximators"]["features"]["n_rbf"]

    edit("huge obs", huge, "shape")
    edit("n_features 2**80", set_in("approximators", "features", "n_features", value=2**80), "n_features")
    edit("window -1", set_in("approximators", "features", "rbf_window", value=-1.0), "rbf_window")
    edit("window '5'", set_in("approximators", "features", "rbf_window", value="5"), "rbf_window")
    edit("window true", set_in("approximators", "features", "rbf_window", value=True), "rbf_window")
    edit("window null", set_in("approximators", "features", "rbf_window", value=None), None)
    edit("window 3", set_in("approximators", "features", "rbf_window", value=3), None)
    edit("outputs floats", lambda h: h["approximators"]["outputs"].update(q=[0.0, float(h["action"]["n_types"])]), None)
    edit("outputs extra", lambda h: h["approximators"]["outputs"].update(extra=1), "outputs")
    edit("dtype float8", lambda h: h["action"]["types"][0].update(dtype="float8"), "dtype")
    edit("metadata", set_in("metadata", value={"big": 10**30, "x": [1.5e300, -0.0, "\u00e9\ud83d\ude00"], "n": None}), None)
    edit("tiles past", None, "reach past the", lambda a: a["tile_bases"].__setitem__(-1, a["tile_bases"][-1] + 1), tiles)
    edit("tiles 2.5", None, "whole numbers", lambda a: a["tile_inputs"].__setitem__((0, 0), 2.5), tiles)
    edit("tiles input", None, "tile_inputs", lambda a: a["tile_inputs"].__setitem__((0, 0), 99.0), tiles)
    edit("tiles mlp", lambda h: h["approximators"].update(head={"type": "tanh_mlp", "hidden_units": 2}), "tile", path=tiles)

    header, blob = header_and_blob(good)
    first = next(iter(header["arrays"]))

    def table(label: str, change, pattern: str) -> None:
        crafted = json.loads(json.dumps(header))
        change(crafted)
        cases.append((label, raw_file(crafted, blob), pattern))

    table("blob_size 2**31", lambda h: h.update(blob_size=2**31), "more than this reader accepts")
    table("blob_size -1", lambda h: h.update(blob_size=len(blob) - 8), "trailing|announces|offset")
    table("offset 4", lambda h: h["arrays"][first].update(offset=4), "offset")
    table("offset past", lambda h: h["arrays"][first].update(offset=len(blob)), "offset")
    table("nbytes", lambda h: h["arrays"][first].update(nbytes=8), "nbytes")
    table("dtype <f4", lambda h: h["arrays"][first].update(dtype="<f4"), "dtype")
    table("entry list", lambda h: h["arrays"].update({first: [1]}), "missing array")
    table("no nbytes", lambda h: h["arrays"][first].pop("nbytes"), "malformed entry")
    # a repeated key: the last wins, as in Python
    text = json.dumps(header)
    cases.append(("repeated key", with_member_first(text, '"version": 3, ', blob), None))
    return cases


def with_member_first(text: str, member: str, blob: bytes) -> bytes:
    """A file whose header is the JSON object ``text`` with ``member`` inserted first (a repeated key: the original,
    last, wins)."""
    return file_bytes(("{" + member + text[1:]).encode(), blob)


def network_cases(folder: Path) -> list[tuple[str, bytes, str | None]]:
    """Damaged networks heads (version 3), from a DeepPolicy export and its every-layer-kind rewrite."""
    from sb3_aac import SarsaAAC
    from sb3_aac.common.envs import ParameterizedTargetEnv

    model = SarsaAAC("DeepPolicy", ParameterizedTargetEnv(n_types=3), seed=0, policy_kwargs={"net_arch": [8, 8]})
    deep = export_policy(model, folder / "deep.aacp")
    layers = folder / "layers.aacp"
    layers.write_bytes(every_layer_kind(deep, 0))
    cases: list[tuple[str, bytes, str | None]] = [("deep", deep.read_bytes(), None), ("layers", layers.read_bytes(), None)]

    def edit(label: str, change, pattern: str | None, arrays=None, path: Path = layers) -> None:
        cases.append((label, rewrite(path, change, arrays), pattern))

    def layer(i: int, j: int, **fields):
        return lambda h: h["approximators"]["head"]["networks"][i]["layers"][j].update(fields)

    def network(i: int, **fields):
        return lambda h: h["approximators"]["head"]["networks"][i].update(fields)

    edit("version 2", lambda h: h.update(version=2), "version >= 3", path=deep)
    edit("version 3.0", lambda h: h.update(version=3.0), None, path=deep)
    edit("no weight", None, "missing array 'net0_0_weight'", lambda a: a.pop("net0_0_weight"))
    edit("NaN weight", None, "NaN", lambda a: a["net1_0_weight"].__setitem__((0, 0), np.nan))
    edit("overlap", network(1, columns=[2, 4]), "exactly once")
    edit("gap", network(2, layers=[{"type": "linear", "in": 2, "out": 1}]), "in=|ends with")
    edit("columns 3", network(0, columns=[0, 3, 4]), "columns")
    edit("in", layer(1, 0, **{"in": 5}), "in=")
    edit("out 0", layer(2, 0, out=0), "out >= 1")
    edit("gelu", layer(1, 2, function="gelu"), "unknown activation")
    edit("slope 1", layer(1, 2, slope=1), "slope")
    edit("eps 0", layer(1, 1, eps=0.0), "eps > 0")
    edit("eps 1", layer(1, 1, eps=1), "eps > 0")
    edit("size 7.0", layer(1, 1, size=7.0), None)  # Python: 7.0 == 7
    edit("affine 1", layer(1, 1, affine=1), "affine")
    edit("dropout", lambda h: h["approximators"]["head"]["networks"][0]["layers"].append({"type": "dropout"}), "layer type")
    edit("no networks", lambda h: h["approximators"]["head"].update(networks=[]), "non-empty")

    def rbf_features(h):
        d = h["observation"]["size"]
        h["approximators"]["features"] = {"type": "rbf", "n_rbf": 2, "rbf_window": 5.0, "n_features": 2 * d}

    edit("rbf features", rbf_features, "scaled features")
    return cases + pdqn_cases(folder)


def pdqn_cases(folder: Path) -> list[tuple[str, bytes, str | None]]:
    """Damaged pdqn heads (version 4) and damaged P-DQN / MP-DQN files."""
    from sb3_aac.common.envs import ParameterizedTargetEnv

    files = {}
    for name, algorithm in ALGORITHMS.items():
        model = algorithm("MlpPolicy", ParameterizedTargetEnv(n_types=3), seed=0, policy_kwargs={"net_arch": [8, 8]})
        files[name] = export_policy(model, folder / f"{name}.aacp")
    mpdqn = files["MPDQN"]
    data = mpdqn.read_bytes()
    cases: list[tuple[str, bytes, str | None]] = [(name, path.read_bytes(), None) for name, path in files.items()]
    cases += [(f"pdqn cut {cut}", data[:cut], "truncated|checksum") for cut in (100, len(data) // 2, -33, -1)]
    altered = bytearray(data)
    altered[len(data) // 2] ^= 0x10
    cases.append(("pdqn byte", bytes(altered), "checksum"))

    def edit(label: str, change, pattern: str | None, arrays=None, path: Path = mpdqn) -> None:
        cases.append((label, rewrite(path, change, arrays), pattern))

    def head(**fields):
        return lambda h: h["approximators"]["head"].update(fields)

    def networks(change):
        return lambda h: change(h["approximators"]["head"]["networks"])

    edit("pdqn version 3", lambda h: h.update(version=3), "version >= 4")
    edit("pdqn version 4.0", lambda h: h.update(version=4.0), None)
    edit("multi_pass 1", head(multi_pass=1), "multi_pass")
    edit("multi_pass null", head(multi_pass=None), "multi_pass")
    edit("no multi_pass", lambda h: h["approximators"]["head"].pop("multi_pass"), "lacks")
    edit("single pass", head(multi_pass=False), None)
    edit("networks head", head(type="networks"), "exactly once|in=")
    edit("three networks", networks(lambda n: n.append(n[0])), "two networks")
    edit("swapped", networks(lambda n: n.reverse()), "in=|columns")
    edit("q reads D", networks(lambda n: n[1]["layers"][0].update({"in": 2})), "in=")
    edit("actor columns", networks(lambda n: n[0].update(columns=[0, 3])), "columns")
    edit("pdqn NaN", None, "NaN", lambda a: a["net1_0_weight"].__setitem__((0, 0), np.nan))
    edit("pdqn inf bias", None, "NaN or inf", lambda a: a["net0_4_bias"].__setitem__(0, np.inf))
    edit("pdqn no weight", None, "missing array 'net1_2_weight'", lambda a: a.pop("net1_2_weight"))
    edit("pdqn shape", None, "shape", lambda a: a.update(net1_0_bias=np.zeros(3)))

    def rbf_features(h):
        d = h["observation"]["size"]
        h["approximators"]["features"] = {"type": "rbf", "n_rbf": 2, "rbf_window": 5.0, "n_features": 2 * d}

    edit("pdqn rbf", rbf_features, "scaled features")
    return cases


def drawn(strategy: st.SearchStrategy, n: int) -> list:
    """``n`` examples of a hypothesis strategy, the same on every run."""
    found: list = []

    @settings(max_examples=n, deadline=None, derandomize=True, database=None, suppress_health_check=list(HealthCheck))
    @given(strategy)
    def gather(example) -> None:
        found.append(example)

    gather()
    return found


def hypothesis_cases(good: Path) -> list[tuple[str, bytes, str | None]]:
    """tests/test_file_properties.py's damaged (bit flips, cuts) and crafted (one header field replaced) files."""
    data = good.read_bytes()
    cases: list[tuple[str, bytes, str | None]] = []
    for i, (flips, cut) in enumerate(drawn(st.tuples(FLIPS.filter(bool), CUTS), N_CORPUS)):
        bad = damaged(data, flips, cut)
        if bad != data:
            cases.append((f"damaged {i}", bad, None))
    header, arrays = read_policy_file(good)
    header = {k: v for k, v in header.items() if k not in ("arrays", "blob_size")}
    keys = st.text(max_size=12) | st.sampled_from(
        ["size", "shape", "types", "n_types", "type_start", "layout", "features", "head", "outputs", "n_outputs", "n_params"]
    )
    for i, (section, key, value) in enumerate(drawn(st.tuples(st.sampled_from(SECTIONS), keys, JSON_VALUES), N_CORPUS)):
        crafted = dict(header)
        crafted[section] = {**header[section], key: value} if isinstance(header.get(section), dict) else value
        encoded = encode_policy_file(crafted, {k: np.array(v) for k, v in arrays.items()})
        cases.append((f"crafted {i}: {section}.{key}", encoded, None))
    return cases


def python_outcome(path: Path) -> tuple[int | None, str]:
    """The action type RuntimePolicy.load(path).act(zeros) gives, or None and why the Python reader refuses the file."""
    try:
        policy = RuntimePolicy.load(path, backend="numpy")
    except ValueError as error:
        return None, str(error)
    return policy.act(np.zeros(policy.obs_size))[0], ""


def c_reads_more(python_refusal: str) -> bool:
    """The C runtime reads format version 3 (networks); a Python reader of this checkout that predates it refuses it."""
    return not networks_supported() and "unknown format version 3;" in python_refusal


@pytest.fixture(scope="module")
def good_files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("good")
    good = export_policy(randomised_model("RbfMlpPolicy", "flat", n_rbf=3, hidden_units=2), folder / "good.aacp")
    tiles = export_policy(randomised_model("TilePolicy", "nested", tiles_per_input=5, n_tilings=3), folder / "tiles.aacp")
    return good, tiles


@pytest.mark.parametrize("source", ["explicit", "hypothesis", "networks"])
def test_refuses_what_the_python_reader_refuses(source: str, good_files, drivers, tmp_path: Path) -> None:
    """Truncated, altered, crafted, wrong-version, non-finite and huge files: aacp_load_file and aacp_load_memory
    (on a heap buffer of exactly the file's size) refuse exactly the files RuntimePolicy.load refuses, with a one-line
    message naming the file, and decide as it does on the rest; under the sanitizers without a report."""
    if source == "networks" and not networks_supported():
        pytest.skip(NO_NETWORKS)
    if source == "explicit":
        cases = explicit_cases(*good_files)
    else:
        cases = hypothesis_cases(good_files[0]) if source == "hypothesis" else network_cases(tmp_path)
    paths = []
    for i, (_, data, _) in enumerate(cases):
        paths.append(tmp_path / f"case{i}.aacp")
        paths[-1].write_bytes(data)
    expected = [python_outcome(path) for path in paths]
    known_differences = {"start 2**70"}  # type_start beyond int64: Python takes it, the C runtime refuses it
    refused = 0
    for driver in builds(drivers):
        lines = run(driver, "load", *map(str, paths)).splitlines()
        assert len(lines) == len(cases)
        for (label, _, pattern), path, (want, why), line in zip(cases, paths, expected, lines, strict=True):
            code, action_type, message = line.split(" ", 2)
            if label in known_differences:
                assert want is not None and code != "0", (label, line)
                continue
            if c_reads_more(why):
                continue  # refused by either reader for another reason, or read by the C one: both fine
            if want is None:
                assert code != "0", f"{label}: the Python reader refuses it, the C runtime loads it"
                assert message.startswith(f"{path} {REFUSED}: "), (label, message)
                assert pattern is None or re.search(pattern, message), (label, pattern, message)
                refused += 1
            else:
                assert code == "0", f"{label}: the Python reader loads it, the C runtime says {message}"
                assert int(action_type) == want, label
    assert refused >= len(cases) // 2


def test_an_unusable_observation_is_named_for_what_it_is(policy_files, drivers, tmp_path: Path) -> None:
    """NaN is "NaN or inf"; a finite value whose square overflows (1e300) is "too large", as RuntimePolicy says."""
    path, obs = policy_files["RbfPolicy-nested"]
    for value, message in ((np.nan, "holds NaN or inf values"), (1e300, "holds values too large to compute with")):
        np.full((1, obs.reshape(len(obs), -1).shape[1]), value).tofile(tmp_path / "obs.bin")
        for driver in builds(drivers):
            argv = [str(driver), "act", str(path), str(tmp_path / "obs.bin"), str(tmp_path / "out.bin")]
            result = subprocess.run(argv, capture_output=True, check=False, timeout=300, env={**os.environ, **SANITIZER_ENV})
            assert result.returncode != 0 and f"observation 0: the observation {message}" in result.stderr.decode()


def test_files_by_name(policy_files, drivers, tmp_path: Path) -> None:
    """aacp_load_file takes the name export_policy was given (".aacp" appended), and refuses a directory, a missing
    file, a link to an endless device (after reading its first bytes) and a named pipe (without waiting for a writer)."""
    path, _ = policy_files["RbfPolicy-nested"]
    (tmp_path / "folder.aacp").mkdir()
    os.mkfifo(tmp_path / "fifo.aacp")
    names = [str(path)[: -len(".aacp")], str(tmp_path / "folder.aacp"), str(tmp_path / "absent.aacp")]
    names.append(str(tmp_path / "fifo.aacp"))
    expected = [r"0 - ok", r"2 - cannot read .*folder\.aacp", r"2 - cannot open .*absent\.aacp"]
    expected.append(r"2 - cannot read .*fifo\.aacp: it is a named pipe \(FIFO\)")
    if Path("/dev/zero").exists():
        (tmp_path / "zero.aacp").symlink_to("/dev/zero")
        names.append(str(tmp_path / "zero.aacp"))
        expected.append(rf"4 - .*zero\.aacp {REFUSED}: it does not start with the magic bytes")
    for driver in builds(drivers):
        lines = run(driver, "file", *names).splitlines()
        for line, pattern in zip(lines, expected, strict=True):
            assert re.match(pattern, line), (line, pattern)


# ------------------------------------------------------------------------------------------------ the C++ example


def test_cpp_example_decides_as_python(drivers, tmp_path: Path) -> None:
    """examples/c/dribble_agent.cpp builds with c++ (warnings as errors) and, on a trained dribbling policy, prints
    the decision RuntimePolicy.act takes on the observation it built, and a server command."""
    compiler = shutil.which("c++")
    if compiler is None:
        pytest.skip("no C++ compiler (c++) on PATH")
    built = compile_c(compiler, ["-std=c++11", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic"], EXAMPLE, tmp_path / "agent")
    assert built.returncode == 0, built.stderr
    from robocup_dribble import DribbleVecEnv

    from sb3_aac import SarsaAAC

    model = SarsaAAC("RbfPolicy", DribbleVecEnv(4, profile="v19"), seed=0).learn(300)
    path = export_policy(model, tmp_path / "dribbler.aacp")
    result = subprocess.run([str(tmp_path / "agent"), str(path)], capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr
    lines = dict(line.split(": ", 1) for line in result.stdout.splitlines())
    obs = np.array(lines["observation"].split(), dtype=np.float64)
    decision = lines["decision"].split()
    k, params = RuntimePolicy.load(path).act(obs)
    assert int(decision[0]) == k
    np.testing.assert_allclose(np.array(decision[1:], dtype=np.float64), params, rtol=0, atol=1e-5)
    assert re.fullmatch(r"\((dash|kick) -?\d+\.\d\d -?\d+\.\d\d\)", lines["command"])


def test_header_ships_with_the_package() -> None:
    """aacp.h is package data, and ``sb3-aac c-header`` prints where it is."""
    tomllib = pytest.importorskip("tomllib")
    package_data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["sb3_aac"]
    assert "runtime/c/aacp.h" in package_data
    assert header_path().is_file()
    assert header_path().read_text().startswith("/*\n * aacp.h")
    result = subprocess.run(
        [sys.executable, "-m", "sb3_aac.cli", "c-header"],
        capture_output=True, text=True, cwd=ROOT, check=False,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[0] == str(header_path())
