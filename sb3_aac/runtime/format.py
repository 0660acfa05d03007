"""
The ``.aacp`` policy file format (``sb3-aac-policy`` versions 2 to 4, see ``docs/export-format.md``): its constants, the
arrays a header calls for, the byte layout (:func:`encode_policy_file`, which :func:`sb3_aac.export_policy` writes
with) and the reader. :func:`read_policy_file` checks the magic bytes, a SHA-256 over the whole file, the format
version, and the name, dtype, shape and placement of every array before returning any of them;
:func:`check_array_values` checks their values. Both raise a :class:`ValueError` saying what is wrong. Loading never
executes anything from the file.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import stat
import struct
from typing import Any

import numpy as np

from .actions import LAYOUTS
from .forward import check_networks, check_pdqn_head, check_rbf_window, network_array_shapes

FORMAT_NAME = "sb3-aac-policy"
# 2: the first released version; 3: adds the "networks" head (feed-forward networks); 4: adds the "pdqn" head (P-DQN's
# parameter actor and Q network in series). Older files are not read.
FORMAT_VERSION = 4
SUPPORTED_VERSIONS = (2, 3, 4)
NETWORKS_VERSION = 3  # the first version with a "networks" head
PDQN_VERSION = 4  # the first version with a "pdqn" head
MAGIC = b"SB3AACP\x00"  # 8 bytes
PREAMBLE = struct.Struct("<8sQ")  # magic, header length (bytes)
DIGEST_SIZE = 32  # the file ends with the SHA-256 of everything before it
ALIGNMENT = 8  # the blob and every array start at a multiple of 8 bytes
PARAM_DTYPES = ("float16", "float32", "float64")
ARRAY_DTYPE = "<f8"  # every array: little-endian IEEE-754 float64, C order
DEFAULT_SUFFIX = ".aacp"
MAX_HEADER_BYTES = 1 << 24  # a header is a few kilobytes; more is not a policy file
MAX_BLOB_BYTES = 1 << 30  # the arrays of the largest sensible policy are megabytes
CHECKSUM_MISMATCH = "SHA-256 checksum mismatch: the file is truncated, corrupted or was altered; export it again"

BANK_ARRAYS = ("obs_mid", "obs_half", "rbf_centers", "rbf_widths", "weight", "bias", "weight1", "bias1", "weight2", "bias2")
TILE_ARRAYS = (
    *("obs_mid", "obs_half", "tile_inputs", "tile_offsets", "tile_resolution", "tile_strides", "tile_bases"),
    *("tile_weight", "bias"),
)


def written_version(head: dict[str, Any]) -> int:
    """The version :func:`sb3_aac.export_policy` writes for a header's ``approximators.head``: the oldest that holds
    it (4 for a ``pdqn`` head, 3 for a ``networks`` head, else 2), so older readers keep reading the policies they
    can compute."""
    return {"pdqn": PDQN_VERSION, "networks": NETWORKS_VERSION}.get(head["type"], 2)


def expected_array_shapes(header: dict[str, Any]) -> dict[str, tuple[int, ...]]:
    """The arrays a file must hold, with their shapes, given its (checked) header."""
    d = header["observation"]["size"]
    n_params = header["action"]["n_params"]
    approx = header["approximators"]
    a, f = approx["n_outputs"], approx["features"]["n_features"]
    shapes: dict[str, tuple[int, ...]] = {
        "obs_low": (d,),
        "obs_high": (d,),
        "obs_mid": (d,),
        "obs_half": (d,),
        "param_low": (n_params,),
        "param_high": (n_params,),
    }
    if approx["features"]["type"] == "rbf":
        m = approx["features"]["n_rbf"]
        shapes["rbf_centers"] = shapes["rbf_widths"] = (d, m)
    if approx["features"]["type"] == "tiles":
        c, k = approx["features"]["n_codings"], approx["features"]["group_size"]
        shapes.update(tile_inputs=(c, k), tile_offsets=(c, k), tile_resolution=(c, k), tile_strides=(c, k), tile_bases=(c,))
        shapes.update(tile_weight=(f, a), bias=(a,))
    elif approx["head"]["type"] in ("networks", "pdqn"):
        shapes.update(network_array_shapes(approx["head"]["networks"]))
    elif approx["head"]["type"] == "linear":
        shapes.update(weight=(a, f), bias=(a,))
    else:
        h = approx["head"]["hidden_units"]
        shapes.update(weight1=(a, h, f), bias1=(a, h), weight2=(a, h), bias2=(a,))
    return shapes


def output_layout(n_types: int, n_params: int) -> tuple[int, dict[str, Any]]:
    """
    The number of approximator outputs and the header's ``outputs`` section: the Q values of the K types, then the
    ``n_params`` scaled parameters, then the value V (``[start, stop)`` column ranges, and V's column).
    """
    k = n_types
    return k + n_params + 1, {"q": [0, k], "params": [k, k + n_params], "value": k + n_params}


def check_array_values(header: dict[str, Any], arrays: dict[str, np.ndarray], path: Any = "<memory>") -> None:
    """
    A ``ValueError`` unless the arrays of a (checked) header hold usable values: finite (observation bounds may be
    infinite), ``obs_half`` and ``rbf_widths`` > 0, ``param_low <= param_high``, and tile-coding index arrays that
    stay inside the table. :func:`read_policy_file` checks the file's structure, this its values.
    """
    for name, values in arrays.items():
        if name in ("obs_low", "obs_high"):
            if np.isnan(values).any():
                raise _fail(path, f"array {name!r} holds NaN")
        elif not np.isfinite(values).all():
            raise _fail(path, f"array {name!r} holds NaN or inf values")
    if not (arrays["obs_half"] > 0).all():
        raise _fail(path, "obs_half must be > 0 everywhere")
    if not (arrays["param_low"] <= arrays["param_high"]).all():
        raise _fail(path, "param_low must be <= param_high everywhere")
    if "rbf_widths" in arrays and not (arrays["rbf_widths"] > 0).all():
        raise _fail(path, "rbf_widths must be > 0 everywhere")
    features = header["approximators"]["features"]
    if features["type"] == "tiles":
        _check_tile_arrays(arrays, header["observation"]["size"], features["n_features"], path)


def _check_tile_arrays(arrays: dict[str, np.ndarray], n_inputs: int, n_features: int, path: Any) -> None:
    """Tile-coding index arrays: whole numbers, inputs in range, and every reachable feature inside the table."""
    inputs, resolution = arrays["tile_inputs"], arrays["tile_resolution"]
    strides, bases = arrays["tile_strides"], arrays["tile_bases"]
    for name in ("tile_inputs", "tile_resolution", "tile_strides", "tile_bases"):
        if not (np.floor(arrays[name]) == arrays[name]).all() or (arrays[name] < 0).any():
            raise _fail(path, f"array {name!r} must hold whole numbers >= 0")
    if (inputs >= n_inputs).any() or (resolution < 1).any():
        raise _fail(path, f"tile_inputs must be < {n_inputs} and tile_resolution >= 1")
    if (bases + (resolution * strides).sum(1)).max() >= n_features:
        raise _fail(path, f"the tile grids reach past the {n_features} features of the table")


def _fail(path: Any, why: str) -> ValueError:
    return ValueError(f"{path} is not a usable sb3-aac policy file: {why}")


def _count(value: Any) -> bool:
    """A whole number >= 0 (not a bool, not a float)."""
    return type(value) is int and value >= 0


def _positive_int(value: Any) -> bool:
    return _count(value) and value >= 1


def _check_features_and_head(approx: Any, action: dict[str, Any], d: int, version: int, path: Any) -> None:
    """The header's ``features`` and ``head`` sections (``KeyError``/``TypeError`` for a missing or mistyped field)."""
    features, head = approx["features"], approx["head"]
    if features["type"] == "rbf":
        if not _positive_int(features["n_rbf"]) or features["n_features"] != d * features["n_rbf"]:
            raise _fail(path, f"RBF features: n_rbf={features['n_rbf']!r}, n_features={features['n_features']!r}, {d} inputs")
        try:
            check_rbf_window(features["rbf_window"])  # None: dense
        except ValueError as error:
            raise _fail(path, str(error)) from None
    elif features["type"] == "scaled":
        if features["n_features"] != d:
            raise _fail(path, f"scaled features: n_features={features['n_features']!r} for {d} inputs")
    elif features["type"] == "tiles":
        sizes = ("n_codings", "group_size", "n_features")
        if not all(_positive_int(features[key]) for key in sizes) or head["type"] != "linear":
            why = f"tile features need positive {', '.join(sizes)} and a linear head, got {features!r}, head {head!r}"
            raise _fail(path, why)
    else:
        raise _fail(path, f"unknown feature type {features['type']!r} (known: 'rbf', 'scaled', 'tiles')")
    _check_head(approx, action, d, version, path)


def _check_head(approx: Any, action: dict[str, Any], d: int, version: int, path: Any) -> None:
    """The header's ``head`` section, given checked features (``KeyError``/``TypeError`` for a missing or mistyped
    field)."""
    features, head = approx["features"], approx["head"]
    if head["type"] == "tanh_mlp":
        if not _positive_int(head["hidden_units"]):
            raise _fail(path, f"hidden_units={head['hidden_units']!r}")
    elif head["type"] == "networks":
        if version < NETWORKS_VERSION or features["type"] != "scaled":
            why = f"a networks head needs version >= {NETWORKS_VERSION} and scaled features"
            raise _fail(path, f"{why}, got version {version}, features {features!r}")
        try:
            check_networks(head["networks"], d, approx["n_outputs"])
        except ValueError as error:
            raise _fail(path, str(error)) from None
    elif head["type"] == "pdqn":
        if version < PDQN_VERSION or features["type"] != "scaled":
            why = f"a pdqn head needs version >= {PDQN_VERSION} and scaled features"
            raise _fail(path, f"{why}, got version {version}, features {features!r}")
        try:
            check_pdqn_head(head, d, action["n_types"], action["n_params"])
        except ValueError as error:
            raise _fail(path, str(error)) from None
    elif head["type"] != "linear":
        raise _fail(path, f"unknown head type {head['type']!r} (known: 'linear', 'tanh_mlp', 'networks', 'pdqn')")


def _check_header(header: Any, path: Any) -> None:
    """Structure and consistency of a header of a supported version (everything but the arrays)."""
    try:
        obs, action, approx = header["observation"], header["action"], header["approximators"]
        d, shape = obs["size"], obs["shape"]
        shape_ok = isinstance(shape, list) and all(_positive_int(s) for s in shape) and math.prod(shape) == d
        if not (_positive_int(d) and shape_ok):
            raise _fail(path, f"observation size {d} and shape {shape} disagree")
        k, start, layout, types = action["n_types"], action["type_start"], action["layout"], action["types"]
        if layout not in LAYOUTS:
            raise _fail(path, f"unknown action layout {layout!r} (known: {list(LAYOUTS)})")
        if not (_positive_int(k) and type(start) is int and isinstance(types, list) and len(types) == k):
            raise _fail(path, f"action section: n_types={k!r}, type_start={start!r} must be whole numbers, with n_types types")
        offset = 0
        for j, t in enumerate(types):
            dim, tshape = t["dim"], t["shape"]
            if not (_count(dim) and isinstance(tshape, list) and all(_count(s) for s in tshape) and math.prod(tshape) == dim):
                raise _fail(path, f"action type {j}: dim {dim!r} and shape {tshape!r} disagree")
            if not _count(t["offset"]) or t["offset"] != offset:
                raise _fail(path, f"action type {j}: offset {t['offset']!r}, expected {offset}")
            if t["dtype"] not in PARAM_DTYPES:
                raise _fail(path, f"action type {j}: parameter dtype {t['dtype']!r} is not one of {list(PARAM_DTYPES)}")
            offset += dim
        if not _count(action["n_params"]) or action["n_params"] != offset:
            raise _fail(path, f"n_params is {action['n_params']!r} but the types' dims add up to {offset}")
        features = approx["features"]
        if not (_positive_int(features["n_features"]) and _positive_int(approx["n_outputs"])):
            sizes = f"n_features={features['n_features']!r}, n_outputs={approx['n_outputs']!r}"
            raise _fail(path, f"{sizes}: both must be whole numbers >= 1")
        _check_features_and_head(approx, action, d, header["version"], path)
        outputs = approx["outputs"]
        n_outputs, expected = output_layout(k, offset)
        if approx["n_outputs"] != n_outputs or outputs != expected:
            raise _fail(path, f"approximator outputs {outputs!r} (n_outputs={approx['n_outputs']!r}); expected {expected}")
        if not isinstance(header["arrays"], dict) or not _positive_int(header["blob_size"]):
            raise _fail(path, "the arrays table or blob_size is malformed")
    except (KeyError, TypeError) as error:
        raise _fail(path, f"the header lacks or mistypes a required field ({error!r})") from error


def policy_file_path(path: str | os.PathLike[str]) -> str:
    """The file :func:`sb3_aac.export_policy` writes for ``path`` and :meth:`RuntimePolicy.load` reads: ``.aacp``
    appended to a name without a suffix (as SB3 appends ``.zip``)."""
    text = os.fspath(path)
    base = os.path.basename(text)
    return text + DEFAULT_SUFFIX if base and os.path.splitext(base)[1] == "" else text


def encode_policy_file(header: dict[str, Any], arrays: dict[str, np.ndarray]) -> bytes:
    """
    Lay out a header and its arrays as file bytes: preamble, JSON header (space-padded to 8 bytes), blob, SHA-256.

    The header's ``arrays`` table and ``blob_size`` are filled in here.
    """
    table, chunks, offset = {}, [], 0
    for name, array in arrays.items():
        data = np.ascontiguousarray(array, dtype=ARRAY_DTYPE).tobytes()
        table[name] = {"dtype": ARRAY_DTYPE, "shape": list(array.shape), "offset": offset, "nbytes": len(data)}
        chunks.append(data)
        offset += len(data)  # float64 arrays keep every offset a multiple of 8
    header = {**header, "arrays": table, "blob_size": offset}
    text = json.dumps(header, indent=1, allow_nan=False).encode("utf-8")
    text += b" " * (-(PREAMBLE.size + len(text)) % ALIGNMENT)
    body = PREAMBLE.pack(MAGIC, len(text)) + text + b"".join(chunks)
    return body + hashlib.sha256(body).digest()


def _read_exactly(f: Any, n: int, path: Any, what: str) -> bytes:
    """``n`` bytes of ``f``, read in bounded chunks (a lying size cannot make us allocate it), or a ValueError."""
    chunks, remaining = [], n
    while remaining:
        chunk = f.read(min(remaining, 1 << 20))
        if not chunk:
            raise _fail(path, f"it ends inside the {what} ({n - remaining} of {n} bytes; truncated?)")
        chunks.append(chunk)
        remaining -= len(chunk)
    return b"".join(chunks)


def _parse_header(text: bytes, path: Any) -> dict[str, Any]:
    """The JSON header, checked (format, version, structure) before any array is read."""
    try:
        header = json.loads(text.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise _fail(path, f"the header is not UTF-8 JSON ({error}); the file is corrupted or was altered") from None
    except RecursionError:
        raise _fail(path, "the header nests too deeply to be a policy header") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT_NAME:
        found = header.get("format") if isinstance(header, dict) else None
        raise _fail(path, f"format is {found!r}, expected {FORMAT_NAME!r}")
    version = header.get("version")
    if version not in SUPPORTED_VERSIONS:
        raise _fail(
            path,
            f"unknown format version {version!r}; this reader supports versions {list(SUPPORTED_VERSIONS)} "
            "(a newer sb3-aac wrote it? upgrade sb3-aac, or export with this version)",
        )
    _check_header(header, path)
    return header


def read_policy_file(path: str | os.PathLike[str]) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """
    Read and verify a policy file (``path``, or ``path + ".aacp"`` for a name without a suffix, as written).

    The file is read in order and never further than its header declares: the magic bytes first, then the JSON
    header (at most ``MAX_HEADER_BYTES``), whose sizes bound the arrays' bytes; so a link to an endless or huge
    file is refused after a few bytes.

    :return: the JSON header and the arrays (read-only float64 views of one buffer)
    :raises ValueError: for a file that is not a complete, unaltered policy file of a supported version
    :raises FileNotFoundError: if there is no such file
    """
    if not os.path.exists(path):
        path = policy_file_path(path)
    if os.path.exists(path) and not os.path.isfile(path):
        raise _fail(path, "it is not a regular file (a directory, device or pipe)")
    with open(path, "rb") as f:
        preamble = f.read(PREAMBLE.size)
        if len(preamble) < PREAMBLE.size:
            raise _fail(path, f"only {len(preamble)} bytes (truncated?)")
        magic, header_len = PREAMBLE.unpack(preamble)
        if magic != MAGIC:
            why = f"it does not start with the magic bytes {MAGIC!r} (got {magic!r}); export one with sb3_aac.export_policy"
            raise _fail(path, why)
        if header_len > MAX_HEADER_BYTES or (PREAMBLE.size + header_len) % ALIGNMENT:
            raise _fail(path, f"header length {header_len}: at most {MAX_HEADER_BYTES} bytes, ending on a multiple of 8")
        head = preamble + _read_exactly(f, header_len, path, "header")
        try:
            header = _parse_header(head[PREAMBLE.size :], path)
        except ValueError as error:
            _raise_if_altered(f, head, path, error)
            raise
        blob_size = header["blob_size"]
        if blob_size > MAX_BLOB_BYTES:
            raise _fail(path, f"it announces {blob_size} bytes of arrays, more than this reader accepts ({MAX_BLOB_BYTES})")
        placements = _array_placements(header, path)
        rest = _read_exactly(f, blob_size + DIGEST_SIZE, path, "arrays and checksum")
        data = head + rest
        if hashlib.sha256(data[:-DIGEST_SIZE]).digest() != data[-DIGEST_SIZE:]:
            raise _fail(path, CHECKSUM_MISMATCH)
        if f.read(1):
            raise _fail(path, "bytes follow its SHA-256 checksum (trailing data: the file was altered); export it again")
    blob = memoryview(data)[len(head) : len(data) - DIGEST_SIZE]
    arrays = {
        name: np.frombuffer(blob, dtype=ARRAY_DTYPE, count=math.prod(shape), offset=offset).reshape(shape)
        for name, (offset, shape) in placements.items()
    }
    return header, arrays


def _array_placements(header: dict[str, Any], path: Any) -> dict[str, tuple[int, tuple[int, ...]]]:
    """Offset and shape of every array the header's sizes need, checked against its table and ``blob_size``."""
    table, blob_size = header["arrays"], header["blob_size"]
    placements = {}
    for name, shape in expected_array_shapes(header).items():
        entry = table.get(name)
        if not isinstance(entry, dict):
            raise _fail(path, f"missing array {name!r} (present: {sorted(table)})")
        try:
            offset, nbytes = entry["offset"], entry["nbytes"]
            dtype, stored_shape = entry["dtype"], entry["shape"]
        except (KeyError, TypeError) as error:
            raise _fail(path, f"array {name!r}: malformed entry {entry!r}") from error
        if dtype != ARRAY_DTYPE:
            raise _fail(path, f"array {name!r} has dtype {dtype!r}, the format stores every array as {ARRAY_DTYPE!r}")
        if not (isinstance(stored_shape, list) and all(_count(s) for s in stored_shape)) or tuple(stored_shape) != shape:
            raise _fail(path, f"array {name!r} has shape {stored_shape!r}, the header's sizes need {shape}")
        size = 8 * math.prod(shape)
        fits = _count(offset) and offset % ALIGNMENT == 0 and offset + size <= blob_size
        if not (fits and _count(nbytes) and nbytes == size):
            raise _fail(path, f"array {name!r}: offset {offset!r} / nbytes {nbytes!r} do not fit the {blob_size}-byte blob")
        placements[name] = (offset, shape)
    return placements


def _raise_if_altered(f: Any, head: bytes, path: Any, error: ValueError) -> None:
    """After a header error: if the file is a regular file of sane size whose checksum fails, say that instead (an
    altered byte is the likelier story than a crafted header)."""
    try:
        size = os.fstat(f.fileno()).st_size
    except OSError:
        return
    if not stat.S_ISREG(os.fstat(f.fileno()).st_mode) or not len(head) + DIGEST_SIZE <= size <= len(head) + MAX_BLOB_BYTES:
        return
    data = head + _read_exactly(f, size - len(head), path, "file")
    if hashlib.sha256(data[:-DIGEST_SIZE]).digest() != data[-DIGEST_SIZE:]:
        raise _fail(path, CHECKSUM_MISMATCH) from error
