"""The benchmark's result files (``DIR/cells/<cell_id>.json``, ``DIR/reliability.json``, models, error files): where
they live, writing them atomically, the per-cell lock, and reading them so that a damaged file is named and skipped
(or recomputed), never fatal and never taken for a finished cell.

Light on purpose (no torch or SB3): the runner and the report both read and write results through here.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import math
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from sb3_aac.common import output_files
from sb3_aac.common.output_files import replaced_atomically

RESULT_KEYS = ("cell_id", "cell")  # every cell file has these, and "final" (trained) or "references"


def cell_path(out: Path, cell_id: str) -> Path:
    return Path(out) / "cells" / f"{cell_id}.json"


def read_json_object(path: Path) -> dict[str, Any]:
    """A JSON object from ``path``. :raises ValueError: naming the file and what is wrong with it."""
    try:
        data = json.loads(Path(path).read_bytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as error:
        raise ValueError(f"{path} is damaged (not UTF-8 JSON: {type(error).__name__}: {error})") from None
    except OSError as error:
        raise ValueError(f"{path} cannot be read ({error.strerror or error})") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path} is damaged (a JSON {type(data).__name__}, expected an object)")
    return data


# The fields the runner, the report and the figures read, with the JSON types they need (see _type_errors).
TRAINED_FIELDS = {"final": "scores", "curve": "curve", "env_steps": "count", "episodes": "count", "train_wall_s": "number",
                  "wall_s": "number", "model": "text"}  # fmt: skip
REFERENCE_FIELDS = {"references": "references", "wall_s": "number"}


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _is_scores(value: Any) -> bool:
    """A mapping of names to finite numbers or lists of them (a final evaluation's summary and per-episode scores)."""
    return isinstance(value, dict) and all(
        _is_number(v) or (isinstance(v, list) and all(map(_is_number, v))) for v in value.values()
    )


_KINDS = {
    "number": _is_number,
    "count": lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 0,
    "text": lambda v: isinstance(v, str),
    "scores": _is_scores,
    "curve": lambda v: isinstance(v, list) and all(_is_scores(point) for point in v),
    "references": lambda v: isinstance(v, dict) and all(map(_is_reference, v.values())),
}


def _is_reference(value: Any) -> bool:
    """A reference's result: numbers, labels, lists of numbers, and evaluations (see :func:`_is_scores`)."""
    return isinstance(value, dict) and all(
        isinstance(v, str) or _is_scores(v) or _is_scores({"value": v}) for v in value.values()
    )


def _type_errors(result: dict[str, Any]) -> list[str]:
    """The fields of a cell result that are missing or of the wrong type, for the kind of cell it is."""
    fields = REFERENCE_FIELDS if "references" in result else TRAINED_FIELDS
    return [f"{key} ({kind})" for key, kind in fields.items() if not (key in result and _KINDS[kind](result[key]))]


def read_cell_file(path: Path) -> dict[str, Any]:
    """
    A finished cell's result, its fields checked to have the types the report reads.

    :raises ValueError: naming the file and the fields, if it is damaged or not a finished cell's
    """
    result = read_json_object(path)
    missing = [key for key in RESULT_KEYS if key not in result]
    if missing or not isinstance(result["cell"], dict) or not ("final" in result or "references" in result):
        raise ValueError(f"{path} is damaged (it lacks {missing or ['final or references']})")
    if result["cell_id"] != Path(path).stem:
        raise ValueError(f"{path} is damaged (it holds the result of cell {result['cell_id']!r})")
    wrong = _type_errors(result)
    if wrong:
        raise ValueError(f"{path} is damaged (missing or wrong-typed fields: {', '.join(wrong)})")
    return result


def is_finished(out: Path, cell: Any) -> bool:
    """Whether ``cell`` has a sound result file of this very cell; a damaged one is reported and will be recomputed."""
    path = cell_path(out, cell.cell_id)
    if not path.exists():
        return False
    try:
        result = read_cell_file(path)
    except ValueError as error:
        warnings.warn(f"{error}; the cell will be computed again", stacklevel=2)
        return False
    if result["cell"] != cell.to_dict():
        warnings.warn(f"{path} holds another definition of the cell; it will be computed again", stacklevel=2)
        return False
    return True


def read_cells(out: Path) -> tuple[list[dict[str, Any]], list[str]]:
    """Every sound cell result in ``out/cells`` (hidden temporaries skipped), and a message for each damaged file."""
    results, damaged = [], []
    for path in sorted((Path(out) / "cells").glob("*.json")):
        if path.name.startswith("."):
            continue
        try:
            results.append(read_cell_file(path))
        except ValueError as error:
            damaged.append(str(error))
    return results, damaged


def load_cells(out: Path) -> list[dict[str, Any]]:
    """:func:`read_cells`' results, with a warning naming each damaged file (skipped)."""
    results, damaged = read_cells(out)
    for message in damaged:
        warnings.warn(f"{message}; skipped", stacklevel=2)
    return results


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (flushed to disk before the rename)."""
    with replaced_atomically(path) as tmp:
        tmp.write_text(text)


def atomic_write_json(path: Path, data: Any) -> None:
    """Serialise first (an unserialisable value raises before anything is written), then write atomically."""
    atomic_write_text(path, json.dumps(data, indent=1, allow_nan=False) + "\n")


def save_model_atomic(model: Any, path: Path) -> None:
    with replaced_atomically(path, suffix=".zip") as tmp:
        model.save(tmp)


RESULT_FOLDERS = ("cells", "models", "errors", "locks", "tb")
"""The folders a run writes into its results directory (each created when first needed)."""


def check_results_folder(out: Path, files: tuple[str, ...]) -> None:
    """Check, before any work, that what a run writes into ``out`` is not in the way: :data:`RESULT_FOLDERS` are
    folders and ``files`` (``runs.jsonl``) regular files where they exist.

    :raises ValueError: naming each entry of the wrong kind
    """
    wrong = [f"{name!r} is not a folder" for name in RESULT_FOLDERS if (out / name).exists() and not (out / name).is_dir()]
    wrong += [f"{name!r} is not a regular file" for name in files if (out / name).exists() and not (out / name).is_file()]
    if wrong:
        raise ValueError(f"the results folder {str(out)!r} cannot take this run: {'; '.join(wrong)} (move it away)")


def remove_stale_temporaries(out: Path) -> None:
    """Temporary files a killed process left behind; a live process's temporaries (a concurrent run) stay."""
    for sub in ("cells", "models", "errors"):
        output_files.remove_stale_temporaries(out / sub)


@contextlib.contextmanager
def cell_lock(out: Path, cell_id: str) -> Iterator[bool]:
    """
    Hold ``DIR/locks/<cell_id>.lock`` while a cell runs: yields False if another live process holds it (that
    cell is running elsewhere, so its TensorBoard folder and temporaries must not be touched). The lock is an
    ``flock``, released by the system when its holder dies, so a killed run never blocks a cell.
    """
    lock_dir = out / "locks"
    lock_dir.mkdir(parents=True, exist_ok=True)
    with open(lock_dir / f"{cell_id}.lock", "a") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            yield False
            return
        try:
            yield True
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)
