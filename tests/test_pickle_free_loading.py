"""Loading a model.zip without unpickling anything (sb3_aac.common.model_files.pickle_free_objects), and the CLI's
refusal to run code from a model file unless told to trust it."""

from __future__ import annotations

import base64
import json
import zipfile
from pathlib import Path

import cloudpickle
import numpy as np
import pytest
from stable_baselines3.common.utils import ConstantSchedule, FloatSchedule, LinearSchedule

from robocup_dribble import DribbleEnv, DribbleVecEnv
from sb3_aac import MPDQN, SarsaAAC
from sb3_aac.cli import main
from sb3_aac.common.model_files import PickledEntryError, _schedule, _description, pickle_free_objects

SPACES = [space for profile in ("v11", "v19") for space in (DribbleEnv(profile=profile).observation_space,
                                                             DribbleEnv(profile=profile).action_space)]  # fmt: skip


class Payload:
    """Unpickling it creates ``marker``: the proof that a loader ran code from the file."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (open, (str(self.marker), "w"))


def planted(source: Path, target: Path, marker: Path) -> Path:
    """``source`` with every pickled entry's pickle replaced by :class:`Payload` (its readable fields kept)."""
    with zipfile.ZipFile(source) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    data = json.loads(members["data"])
    payload = base64.b64encode(cloudpickle.dumps(Payload(marker))).decode()
    for entry in data.values():
        if isinstance(entry, dict) and ":serialized:" in entry:
            entry[":serialized:"] = payload
    members["data"] = json.dumps(data).encode()
    with zipfile.ZipFile(target, "w") as archive:
        for name, raw in members.items():
            archive.writestr(name, raw)
    return target


@pytest.fixture(scope="module")
def saved(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("models")
    paths = {}
    for name, model in {
        "tile": SarsaAAC("TilePolicy", DribbleVecEnv(2, profile="v11"), seed=0, learning_rate=LinearSchedule(0.5, 0.1, 0.3)),
        "mpdqn": MPDQN("MlpPolicy", DribbleVecEnv(2, profile="v19"), seed=0, learning_starts=50),
    }.items():
        model.learn(200)
        paths[name] = folder / f"{name}.zip"
        model.save(paths[name])
    return paths


@pytest.mark.parametrize(("name", "cls"), [("tile", SarsaAAC), ("mpdqn", MPDQN)])
def test_pickle_free_load_predicts_as_the_usual_load(saved, name, cls) -> None:
    objects = pickle_free_objects(saved[name], cls.policy_aliases.values(), SPACES)
    assert {"policy_class", "observation_space", "action_space"} <= set(objects)
    usual, free = cls.load(saved[name]), cls.load(saved[name], custom_objects=objects)
    assert free.observation_space == usual.observation_space and free.action_space == usual.action_space
    obs = np.stack([usual.observation_space.sample() for _ in range(200)])
    (a_types, a_params), (b_types, b_params) = (
        (np.array([a[0] for a in actions]), np.array([np.concatenate(a[1]) for a in actions]))
        for actions in (m.predict(obs, deterministic=True)[0] for m in (usual, free))
    )
    np.testing.assert_array_equal(a_types, b_types)
    np.testing.assert_array_equal(a_params, b_params)


def test_schedules_are_rebuilt_exactly() -> None:
    schedules = [FloatSchedule(LinearSchedule(0.1 + 0.2, 1 / 3, 0.7)), FloatSchedule(0.123456789)]
    for schedule in (*schedules, LinearSchedule(1e-7, 2.5, 1.0), ConstantSchedule(0.3)):
        rebuilt = _schedule(_description(schedule))
        assert type(rebuilt) is type(schedule) and repr(rebuilt) == repr(schedule)
        assert all(rebuilt(p) == schedule(p) for p in (1.0, 0.61, 0.0))
    assert _schedule(_description(FloatSchedule(lambda p: p))) is None  # a user's callable needs its pickle


def test_an_unknown_space_or_class_is_named(saved) -> None:
    with pytest.raises(PickledEntryError, match="observation_space") as info:
        pickle_free_objects(saved["tile"], SarsaAAC.policy_aliases.values(), SPACES[2:])  # only v19's spaces
    assert info.value.entry == "observation_space"
    with pytest.raises(PickledEntryError) as info:
        pickle_free_objects(saved["tile"], MPDQN.policy_aliases.values(), SPACES)
    assert info.value.entry == "policy_class"


def test_cli_never_runs_code_from_a_model_file(saved, tmp_path, capsys) -> None:
    marker = tmp_path / "ran"
    for name in ("tile", "mpdqn"):
        crafted = planted(saved[name], tmp_path / f"crafted-{name}.zip", marker)
        assert main(["evaluate", str(crafted), "--episodes", "3"]) == 0
        assert main(["render", str(crafted), "--out", str(tmp_path / f"{name}.gif")]) == 0
        if name == "tile":
            assert main(["export", str(crafted), str(tmp_path / f"{name}.aacp")]) == 0
        assert not marker.exists(), f"loading {name} ran the file's pickled code"
    # The payload is live: loading with --trust (SB3's own unpickling) runs it (and then fails on what it returned),
    # so the check above can fail.
    with pytest.raises(SystemExit):
        main(["evaluate", str(tmp_path / "crafted-tile.zip"), "--episodes", "1", "--trust"])
    assert marker.exists()


def test_cli_refuses_a_file_that_needs_its_pickles(tmp_path, capsys) -> None:
    env = DribbleVecEnv(2, profile="v11")
    # obs_bounds as arrays make policy_kwargs a pickled dict, which nothing can stand in for.
    low, high = env.observation_space.low.astype(np.float64), env.observation_space.high.astype(np.float64)
    model = SarsaAAC("RbfPolicy", env, seed=0, policy_kwargs=dict(obs_bounds=(low, high), n_rbf=3))
    model.learn(100)
    model.save(tmp_path / "model.zip")
    with pytest.raises(SystemExit) as info:
        main(["evaluate", str(tmp_path / "model.zip"), "--episodes", "2"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "'policy_kwargs'" in err and "--trust" in err and "Traceback" not in err
    assert main(["evaluate", str(tmp_path / "model.zip"), "--episodes", "2", "--trust"]) == 0
