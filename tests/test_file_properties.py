"""Property-based fault tests (hypothesis): damaged model files, damaged or crafted policy files and hostile command
lines are refused with one ValueError naming the file (one line and exit status 2 at the CLI), never a traceback,
a hang or a half-written output."""

from __future__ import annotations

import contextlib
import io
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sb3_aac import RuntimePolicy, SarsaAAC, export_policy
from sb3_aac.cli import main
from sb3_aac.common.model_files import check_model_file, load_checked
from sb3_aac.export import encode_policy_file
from sb3_aac.runtime import read_policy_file

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    from robocup_dribble import DribbleVecEnv

    folder = tmp_path_factory.mktemp("files")
    model = SarsaAAC("RbfPolicy", DribbleVecEnv(2, profile="v11"), seed=0, policy_kwargs={"n_rbf": 3})
    model.learn(100)
    model.save(folder / "model.zip")
    export_policy(model, folder / "policy.aacp")
    return {"folder": folder, "model": folder / "model.zip", "policy": folder / "policy.aacp"}


def damaged(data: bytes, flips: list[tuple[int, int]], cut: int | None) -> bytes:
    out = bytearray(data)
    for where, bit in flips:
        out[where % len(out)] ^= 1 << bit
    return bytes(out if cut is None else out[: cut % len(out)])


FLIPS = st.lists(st.tuples(st.integers(0, 2**31), st.integers(0, 7)), max_size=4)
CUTS = st.none() | st.integers(0, 2**31)


# ------------------------------------------------------------------------------------------------------ model.zip


@SETTINGS
@given(flips=FLIPS, cut=CUTS)
def test_damaged_model_zip_is_refused_or_loads(files, flips, cut) -> None:
    path = files["folder"] / "damaged.zip"
    path.write_bytes(damaged(files["model"].read_bytes(), flips, cut))
    try:
        model = load_checked(SarsaAAC, path)
    except ValueError as error:
        assert str(path) in str(error)
        return
    # only a flip the zip format does not cover (e.g. a timestamp or a comment) can leave a loadable model
    assert model.observation_space.shape == (10,)


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=8),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=8), children, max_size=4),
    max_leaves=20,
)


@SETTINGS
@given(drop=st.sets(st.sampled_from(["policy_class", "observation_space", "action_space", "num_timesteps", "gamma"])),
       replace=st.dictionaries(st.sampled_from(["policy_class", "observation_space", "action_space", "gamma", "n_envs"]),
                               JSON_VALUES, max_size=2),
       whole=st.none() | JSON_VALUES)  # fmt: skip
def test_crafted_model_data_is_refused_or_loads(files, drop, replace, whole) -> None:
    with zipfile.ZipFile(files["model"]) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    data = json.loads(members["data"])
    data = whole if whole is not None else {**{k: v for k, v in data.items() if k not in drop}, **replace}
    members["data"] = json.dumps(data).encode()
    path = files["folder"] / "crafted.zip"
    with zipfile.ZipFile(path, "w") as archive:
        for name, content in members.items():
            archive.writestr(name, content)
    try:
        load_checked(SarsaAAC, path)
    except ValueError as error:
        assert str(path) in str(error) and "\n" not in str(error)


def test_model_check_takes_names_and_file_objects(files) -> None:
    check_model_file(files["model"])
    check_model_file(str(files["model"])[: -len(".zip")])  # SB3 appends .zip
    buffer = io.BytesIO(files["model"].read_bytes())
    buffer.seek(3)
    check_model_file(buffer)
    assert buffer.tell() == 3
    with pytest.raises(FileNotFoundError):
        check_model_file(files["folder"] / "absent.zip")


# ------------------------------------------------------------------------------------------------------ .aacp


@SETTINGS
@given(flips=FLIPS.filter(bool), cut=CUTS)
def test_damaged_policy_file_is_refused(files, flips, cut) -> None:
    data = files["policy"].read_bytes()
    bad = damaged(data, flips, cut)
    if bad == data:
        return  # flips that cancel out
    path = files["folder"] / "damaged.aacp"
    path.write_bytes(bad)
    with pytest.raises(ValueError, match="not a usable sb3-aac policy file"):
        RuntimePolicy.load(path)


SECTIONS = ["observation", "action", "approximators", "metadata", "format", "version"]


@SETTINGS
@given(section=st.sampled_from(SECTIONS), key=st.text(max_size=12) | st.sampled_from(["size", "shape", "types", "n_types",
       "type_start", "layout", "features", "head", "outputs", "n_outputs", "n_params"]), value=JSON_VALUES)  # fmt: skip
def test_crafted_policy_header_is_refused_or_equivalent(files, section, key, value) -> None:
    """A header with one field replaced (re-encoded with a valid checksum): refused, or it still describes the same
    arrays (then the policy must act as the original)."""
    header, arrays = read_policy_file(files["policy"])
    header = {k: v for k, v in header.items() if k not in ("arrays", "blob_size")}
    if isinstance(header.get(section), dict):
        header[section] = {**header[section], key: value}
    else:
        header[section] = value
    path = files["folder"] / "crafted.aacp"
    path.write_bytes(encode_policy_file(header, {k: np.array(v) for k, v in arrays.items()}))
    try:
        policy = RuntimePolicy.load(path, backend="numpy")
    except ValueError as error:
        assert "not a usable sb3-aac policy file" in str(error) or "backend" not in str(error)
        return
    original = RuntimePolicy.load(files["policy"], backend="numpy")
    obs = np.zeros(original.obs_size)
    assert policy.act(obs)[0] - policy.type_start == original.act(obs)[0] - original.type_start


# ------------------------------------------------------------------------------------------------------ the CLI

HOSTILE = ["", "-1", "0", "nan", "inf", "1e309", "0x10", "1_0", "\u0661", "abc", "--", "/proc", "/proc/x.png", "a\x00b",
           "a\x00b.zip", "x" * 300, "x" * 300 + ".zip", "x" * 300 + ".png", "/dev/zero", "/dev/zero/x.gif", "."]  # fmt: skip
SMALL = ["1", "2", "3"]


def model_args(files) -> st.SearchStrategy[str]:
    return st.sampled_from(
        ["dribbler", str(files["model"]), str(files["policy"]), str(files["folder"]), "missing.zip", *HOSTILE]
    )


def command_lines(files) -> st.SearchStrategy[list[str]]:
    value = st.sampled_from(SMALL + HOSTILE)
    out_file = st.sampled_from([str(files["folder"] / "o" / n) for n in ("x.png", "x.gif", "x.aacp", "x.mp4", "x")] + HOSTILE)
    options = {
        "train": ["--timesteps", "--episodes", "--n-envs", "--seed", "--set", "--env", "--policy", "--out", "--tensorboard",
                  "--eval-episodes", "--verbose", "--gym-package"],
        "evaluate": ["--episodes", "--seed", "--profile"],
        "reliability": ["--players", "--seed", "--profile", "--out"],
        "render": ["--seed", "--profile", "--out", "--fps"],
        "export": [],
    }  # fmt: skip

    @st.composite
    def build(draw):
        command = draw(st.sampled_from(sorted(options)))
        argv = [command]
        if command != "train":
            argv.append(draw(model_args(files)))
        if command == "export":
            argv.append(draw(out_file))
        for option in draw(st.lists(st.sampled_from(options[command] or ["--help"]), max_size=3, unique=True)):
            if option == "--help":
                continue
            if option in ("--out", "--tensorboard"):
                argv += [
                    option,
                    draw(out_file if command != "train" else st.sampled_from([str(files["folder"] / "run"), *HOSTILE])),
                ]
            elif option == "--set":
                argv += [option, draw(st.sampled_from(["gamma=0.5", "gamma=nan", "gamma=-1", "n_rbf=0", "x=1", "=", "gamma"]))]
            else:
                argv += [option, draw(value)]
        if command == "train":
            argv += ["--n-envs", "2", "--eval-episodes", "2", "--timesteps", "50"] if "--episodes" not in argv else []
        if command in ("evaluate",) and "--episodes" not in argv:
            argv += ["--episodes", "2"]
        if command == "reliability" and "--players" not in argv:
            argv += ["--players", "3"]
        if command == "render" and "--out" not in argv:
            argv += ["--out", str(files["folder"] / "o" / "x.gif")]
        if command == "reliability" and "--out" not in argv:
            argv += ["--out", str(files["folder"] / "o" / "x.png")]
        return argv

    return build()


@pytest.mark.slow
def test_hostile_command_lines_exit_0_or_2_with_one_line(files, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # hostile relative names ("1e309", "abc") become folders here, not in the checkout

    @settings(max_examples=40, deadline=None)
    @given(argv=command_lines(files))
    def check(argv: list[str]) -> None:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            try:
                code = main(argv)
            except SystemExit as exit_:
                code = exit_.code
        text = err.getvalue()
        assert "Traceback" not in text, (argv, text)
        assert code in (0, 2), (argv, code, text)
        if code == 2:
            errors = [line for line in text.splitlines() if ": error: " in line]
            assert len(errors) == 1, (argv, text)
        leftovers = [p for p in files["folder"].rglob(".*") if ".tmp" in p.name]
        assert not leftovers, (argv, leftovers)

    check()
