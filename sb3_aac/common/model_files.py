"""
Check a saved model (Stable-Baselines3's ``model.zip``) before loading it, so every way the file can be wrong gives one
:class:`ValueError` naming the file and what is wrong, instead of a traceback from deep inside ``torch`` or SB3.

The check reads the archive without unpickling anything: the zip's structure and CRCs, the ``data`` member as a
JSON object with the keys ``load`` needs, and every ``*.pth`` member with ``torch.load(weights_only=True)`` as a
dictionary of finite tensors. The check alone cannot make loading a ``.zip`` from a stranger safe: SB3 stores some fields
(spaces, schedules) as pickles, which ``load`` executes; :func:`pickle_free_objects` stands in for every one of them
(what the command line does unless told to trust the file). Exported ``.aacp`` policies never execute anything.
"""

from __future__ import annotations

import io
import json
import os
import re
import zipfile
import zlib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

REQUIRED_MEMBERS = ("data", "policy.pth")
REQUIRED_DATA_KEYS = ("policy_class", "observation_space", "action_space", "num_timesteps")
MAX_UNPACKED_BYTES = 1 << 31  # a model of this library is kilobytes to megabytes; refuse zip bombs


def check_policy_class(algorithm: Any, base: type) -> None:
    """Raise a :class:`ValueError` unless ``algorithm.policy_class`` is ``base`` or a subclass of it (a model loaded
    from another algorithm's file brings its own policy class)."""
    policy_class = algorithm.policy_class
    if not (isinstance(policy_class, type) and issubclass(policy_class, base)):
        raise ValueError(
            f"{type(algorithm).__name__} needs a {base.__name__} ({', '.join(algorithm.policy_aliases)} or a subclass), "
            f"got {policy_class} (loading a model saved by another algorithm?)"
        )


def model_zip_path(path: str | os.PathLike[str]) -> Path:
    """The file SB3's ``load`` opens for ``path``: the path itself, or with ``.zip`` appended when that exists."""
    path = Path(path)
    if not path.exists() and path.suffix != ".zip" and path.with_name(path.name + ".zip").exists():
        return path.with_name(path.name + ".zip")
    return path


def _fail(name: Any, why: str) -> ValueError:
    return ValueError(f"{name} is not a usable saved model: {why}")


def _check_archive(archive: zipfile.ZipFile, name: Any) -> None:
    members = archive.namelist()
    missing = [m for m in REQUIRED_MEMBERS if m not in members]
    if missing:
        raise _fail(name, f"the archive lacks {missing} (it holds {members}); was it saved by model.save?")
    unpacked = sum(info.file_size for info in archive.infolist())
    if unpacked > MAX_UNPACKED_BYTES:
        raise _fail(name, f"the archive unpacks to {unpacked} bytes, more than any model ({MAX_UNPACKED_BYTES})")
    bad = archive.testzip()
    if bad is not None:
        raise _fail(name, f"member {bad!r} fails its CRC check (the file is corrupted)")
    try:
        data = json.loads(archive.read("data").decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as error:
        raise _fail(name, f"its 'data' member is not UTF-8 JSON ({type(error).__name__}: {error})") from None
    if not isinstance(data, dict):
        raise _fail(name, f"its 'data' member is a JSON {type(data).__name__}, expected an object of the model's fields")
    absent = [key for key in REQUIRED_DATA_KEYS if key not in data]
    if absent:
        raise _fail(name, f"its 'data' member lacks the fields {absent}")
    for key in ("observation_space", "action_space"):
        if not (isinstance(data[key], dict) and ":serialized:" in data[key]):
            raise _fail(name, f"its 'data' field {key!r} is not a saved space")
    for member in (m for m in members if m.endswith(".pth")):
        _check_tensors(archive.read(member), member, name)


def _check_tensors(raw: bytes, member: str, name: Any) -> None:
    import torch as th

    try:
        tensors = th.load(io.BytesIO(raw), map_location="cpu", weights_only=True)
    except Exception as error:  # torch raises many types for garbage (UnpicklingError, RuntimeError, EOFError, ...)
        first = str(error).strip().splitlines()[0] if str(error).strip() else ""
        raise _fail(name, f"its {member!r} is not a torch tensor file ({type(error).__name__}: {first[:200]})") from None
    if not isinstance(tensors, dict):
        raise _fail(name, f"its {member!r} holds a {type(tensors).__name__}, expected a dictionary of tensors")
    for key, value in tensors.items():
        if isinstance(value, th.Tensor) and value.is_floating_point() and not th.isfinite(value).all():
            raise _fail(name, f"its {member!r} tensor {key!r} holds NaN or inf values (saved from a diverged run?)")


def check_model_file(path: Any) -> None:
    """
    Check that ``path`` (a file name, with or without ``.zip``, or a binary file object) holds a complete,
    undamaged saved model, without executing anything from it.

    :raises ValueError: naming the file and what is wrong (empty, not a zip, a bad CRC, a missing member or key,
        ``data`` not a JSON object, a ``.pth`` member that is not a dictionary of finite tensors)
    :raises FileNotFoundError: if there is no such file
    """
    if hasattr(path, "read") and hasattr(path, "seek"):
        start = path.tell()
        try:
            _check_source(path, getattr(path, "name", "the model file object"))
        finally:
            path.seek(start)
        return
    file = model_zip_path(path)
    if not file.exists():
        raise FileNotFoundError(f"{path} does not exist")
    if not file.is_file():  # a directory, a device (a link to /dev/zero would be read without end), a pipe
        raise _fail(file, "it is not a regular file")
    _check_source(file, file)


def _check_source(source: Any, name: Any) -> None:
    try:
        archive = zipfile.ZipFile(source)
    except zipfile.BadZipFile as error:
        size = os.path.getsize(source) if isinstance(source, Path) else None
        raise _fail(name, "it is empty (0 bytes)" if size == 0 else f"it is not a zip archive ({error})") from None
    except (EOFError, OSError) as error:
        if isinstance(error, FileNotFoundError):
            raise
        raise _fail(name, f"reading it failed ({type(error).__name__}: {error})") from None
    with archive:
        try:
            _check_archive(archive, name)
        except (zipfile.BadZipFile, EOFError, NotImplementedError, zlib.error, OSError) as error:
            raise _fail(name, f"a member cannot be unpacked ({type(error).__name__}: {error})") from None


def load_checked(cls: Any, path: Any, **kwargs: Any) -> Any:
    """
    ``cls.load(path, **kwargs)`` after :func:`check_model_file`, with any failure of ``load`` itself (an
    algorithm's own checks, a space that does not fit) turned into one :class:`ValueError` naming the file.

    :raises FileNotFoundError: if there is no such file
    """
    check_model_file(path)
    name = model_zip_path(path) if isinstance(path, (str, os.PathLike)) else path
    try:
        return cls.load(path, **kwargs)
    except FileNotFoundError:
        raise
    except Exception as error:  # anything load raises on a file that passed the structural check
        text = " ".join(str(error).split())
        if isinstance(error, ValueError) and text.startswith(str(name)):
            raise ValueError(text) from error
        raise _fail(name, f"{cls.__name__}.load failed ({type(error).__name__}: {text[:300]})") from error


# A pickled entry's readable fields may name memory addresses, which differ between processes.
_ADDRESS = re.compile(r" at 0x[0-9a-fA-F]+")
# Stand-ins for the pickled entries acting does not read, by type: the state of a run under way (last observations,
# episode statistics, running moments: None, which ``learn`` starts afresh) and off-policy training's collection
# frequency (a NamedTuple that prints no fields: one step).
TRAINING_ONLY_STAND_INS: dict[str, Any] = {
    "<class 'numpy.ndarray'>": None,
    "<class 'collections.deque'>": None,
    "<class 'stable_baselines3.common.type_aliases.TrainFreq'>": (1, "step"),
}
# SB3's schedules print their numbers exactly (Python's shortest round-trip float repr), so they are rebuilt from them.
_SCHEDULE = re.compile(r"^(ConstantSchedule\(val=(?P<val>[^,()]+)\)|LinearSchedule\(start=(?P<start>[^,()]+), "
                       r"end=(?P<end>[^,()]+), end_fraction=(?P<fraction>[^,()]+)\))$")  # fmt: skip


class PickledEntryError(ValueError):
    """A pickled entry of a model.zip that :func:`pickle_free_objects` cannot stand in for (``entry`` names it)."""

    def __init__(self, message: str, entry: str) -> None:
        super().__init__(message)
        self.entry = entry


def _readable_fields(serialized: dict[str, Any]) -> dict[str, Any]:
    """What SB3 wrote beside a pickle for humans (type and first-level fields), without addresses or RNG state."""
    return {
        key: _ADDRESS.sub("", value) if isinstance(value, str) else value
        for key, value in serialized.items()
        if key not in (":serialized:", "_np_random")
    }


def _description(obj: Any) -> dict[str, Any]:
    """The readable fields SB3 writes for ``obj`` when it pickles it."""
    from stable_baselines3.common.save_util import data_to_json

    entry = json.loads(data_to_json({"entry": obj}))["entry"]
    return _readable_fields(entry) if isinstance(entry, dict) and ":serialized:" in entry else {}


def _schedule(fields: dict[str, Any]) -> Any:
    """An SB3 schedule rebuilt from its readable fields, or None if they do not describe a constant or linear one."""
    from stable_baselines3.common.utils import ConstantSchedule, FloatSchedule, LinearSchedule

    kind = fields.get(":type:", "")
    text = {
        "<class 'stable_baselines3.common.utils.FloatSchedule'>": fields.get("value_schedule"),
        "<class 'stable_baselines3.common.utils.ConstantSchedule'>": f"ConstantSchedule(val={fields.get('val')})",
        "<class 'stable_baselines3.common.utils.LinearSchedule'>": (
            f"LinearSchedule(start={fields.get('start')}, end={fields.get('end')}, end_fraction={fields.get('end_fraction')})"
        ),
    }.get(kind)
    match = _SCHEDULE.match(text) if isinstance(text, str) else None
    if match is None:
        return None
    try:
        if match["val"] is not None:
            schedule: Any = ConstantSchedule(float(match["val"]))
        else:
            schedule = LinearSchedule(float(match["start"]), float(match["end"]), float(match["fraction"]))
    except ValueError:
        return None
    return FloatSchedule(schedule) if kind.endswith("FloatSchedule'>") else schedule


def pickle_free_objects(path: Any, policy_classes: Iterable[type], spaces: Iterable[Any]) -> dict[str, Any]:
    """
    ``custom_objects`` for :meth:`~stable_baselines3.common.base_class.BaseAlgorithm.load` that stand in for every
    pickled entry of the model file ``path``, so that loading unpickles nothing (SB3 takes an entry named in
    ``custom_objects`` instead of reading it). The weights are read with ``torch.load(weights_only=True)`` as usual.

    - ``policy_class``: the one of ``policy_classes`` whose readable fields (module, docstring, methods) the file
      repeats; ``observation_space`` and ``action_space``: the one of ``spaces`` whose readable fields (type, dtype,
      shape, bounds as numpy prints them) the file repeats;
    - SB3's constant and linear schedules: rebuilt from the numbers they print (exactly);
    - what acting does not read (:data:`TRAINING_ONLY_STAND_INS`: numpy arrays and deques, ``TrainFreq``): None, or
      one step. The loaded model predicts and exports as the file's model does; to go on training it, load it the
      usual way.

    A file's readable fields are only compared, never trusted: whatever its pickles hold is not run.

    :raises PickledEntryError: naming the first entry that none of these can stand in for (a class, callable or
        space of the user's own): loading it needs its pickle, i.e. trusting the file
    """
    check_model_file(path)
    with zipfile.ZipFile(model_zip_path(path) if isinstance(path, (str, os.PathLike)) else path) as archive:
        data = json.loads(archive.read("data").decode("utf-8"))
    candidates = {"policy_class": list(policy_classes), "observation_space": list(spaces), "action_space": list(spaces)}
    objects: dict[str, Any] = {}
    for key, entry in data.items():
        if not (isinstance(entry, dict) and ":serialized:" in entry):
            continue
        fields = _readable_fields(entry)
        if key in candidates:
            found = [c for c in candidates[key] if _description(c) == fields]
            if not found:
                raise PickledEntryError(f"its {key} ({fields.get(':type:')}) is none of the known ones", key)
            objects[key] = found[0]
        elif fields.get(":type:") in TRAINING_ONLY_STAND_INS:
            objects[key] = TRAINING_ONLY_STAND_INS[fields[":type:"]]
        else:
            schedule = _schedule(fields)
            if schedule is None:
                raise PickledEntryError(f"its entry {key!r} is a pickled {fields.get(':type:')}", key)
            objects[key] = schedule
    return objects
