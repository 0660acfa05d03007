"""
Greedy SarsaAAC decisions from an exported policy file, with numpy alone.

:func:`sb3_aac.export_policy` writes a trained policy as plain arrays and a JSON description (format
``sb3-aac-policy`` version 2, see ``docs/export-format.md``); :class:`RuntimePolicy` reads it back and acts::

    from sb3_aac.runtime import RuntimePolicy

    policy = RuntimePolicy.load("dribbler.aacp")
    action_type, params = policy.act(observation)  # params of that type, in the env's units

This module imports only the standard library and numpy (no torch, no Stable-Baselines3), so it can be copied
into an agent on its own. Loading never executes anything from the file: it checks the magic bytes, a SHA-256
over the whole file, the format version, and the name, dtype, shape and placement of every array, and raises a
:class:`ValueError` saying what is wrong rather than ever returning an action from a damaged file.

The approximators' forward pass, :class:`BankForward`, lives here and nowhere else: training
(:class:`sb3_aac.common.approximators.BankKernel`) and ``model.predict`` call this same code, so the decisions are
those of ``model.predict(obs, deterministic=True)``. The optional numba kernel behind :meth:`RuntimePolicy.act` is
the same formulas compiled for one observation.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import stat
import struct
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

FORMAT_NAME = "sb3-aac-policy"
FORMAT_VERSION = 2  # 2: RBF features may name a window (features.rbf_window)
SUPPORTED_VERSIONS = (1, 2)
MAGIC = b"SB3AACP\x00"  # 8 bytes
PREAMBLE = struct.Struct("<8sQ")  # magic, header length (bytes)
DIGEST_SIZE = 32  # the file ends with the SHA-256 of everything before it
ALIGNMENT = 8  # the blob and every array start at a multiple of 8 bytes
LAYOUTS = ("nested", "flat", "shared", "oneof")
BACKENDS = ("auto", "numpy", "numba")  # how act() computes: numba if importable, or numpy only
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

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "LAYOUTS",
    "MAGIC",
    "BankForward",
    "RuntimePolicy",
    "TileForward",
    "env_action",
    "expected_array_shapes",
    "policy_file_path",
    "read_policy_file",
    "unscale",
]


def unscale(low: np.ndarray, high: np.ndarray, params_scaled: np.ndarray) -> np.ndarray:
    """
    Map parameters from ``[-1, 1]`` to ``[low, high]`` and clip them inside the bounds (float64, ``(..., n_params)``).

    ``-1`` and ``1`` give ``low`` and ``high`` exactly, whatever the dtype: ``mid + half * p`` can miss a float64
    bound by one ulp, so the interpolation weights both bounds instead. Training
    (:meth:`sb3_aac.common.spaces.ParameterizedActionSpec.unscale`) and :meth:`RuntimePolicy.unscale` call this.
    """
    weight = 0.5 * np.asarray(params_scaled, dtype=np.float64)
    value = low * (0.5 - weight) + high * (0.5 + weight)
    # minimum/maximum: np.clip costs several times more on small arrays.
    clipped: np.ndarray = np.minimum(np.maximum(value, low), high)
    return clipped


def env_action(
    layout: str, start: int, k: int, n_types: int, box: Callable[[int, np.ndarray], np.ndarray], params: np.ndarray
) -> tuple[Any, ...]:
    """
    One env action of 0-based type ``k`` in action ``layout`` (see ``LAYOUTS``), as ``model.predict`` returns it.

    :param start: the ``Discrete``'s start, added to ``k`` (a ``"oneof"`` action numbers its types from 0)
    :param box: ``box(j, params)`` is type ``j``'s part of the parameter vector ``params`` in its Box's shape and dtype
    """
    if layout == "oneof":
        return (k, box(k, params))
    if layout == "shared":
        return (start + k, box(k, params))
    values = tuple(box(j, params) for j in range(n_types))
    return (start + k, values) if layout == "nested" else (start + k, *values)


# Batches of at least this many observations gather the RBF window (fancy indexing); smaller ones, where its fixed
# cost dominates, compute every RBF and then zero those outside the window. The values are the same.
WINDOW_MIN_ROWS = 32
# ... and only where the window holds at most half of an input's centres (measured at 256 rows: the gather and scatter
# cost about as much as the dense centres they save at 30 RBFs per input, 1.7x less at 50).
WINDOW_MIN_SHARE = 2


def check_rbf_window(rbf_window: Any) -> None:
    """A ``ValueError`` unless ``rbf_window`` is None or a finite number of standard deviations > 0."""
    if rbf_window is not None and not (
        isinstance(rbf_window, (int, float)) and not isinstance(rbf_window, bool) and 0 < rbf_window < math.inf
    ):
        raise ValueError(f"rbf_window must be a finite number of standard deviations > 0, or None; got {rbf_window!r}")


class BankForward:
    """
    The forward pass of a bank of ``A`` independent function approximators of one observation: the only
    implementation of these formulas (see :mod:`sb3_aac.common.approximators` for the model). Training subclasses
    it (:class:`~sb3_aac.common.approximators.BankKernel`), ``model.predict`` and :class:`RuntimePolicy` call it.

    - features ``phi`` (``F``): the inputs scaled from ``[low, high]`` to ``[-1, 1]``, ``(s - mid) / half``; or per
      input ``m`` Gaussian RBFs on the scaled input, ``exp(-0.5 * ((s~_i - c_ij) / w_ij)**2)``. Both are computed
      as ``s * a - b`` (then ``exp(-z**2)`` for RBFs) with the constants ``a``, ``b`` folded once here;
    - head of approximator ``a``: linear, ``weight[a] . phi + bias[a]``; or one tanh layer,
      ``weight2[a] . tanh(weight1[a] @ phi + bias1[a]) + bias2[a]``.

    The arguments are the arrays of the export format (names in ``BANK_ARRAYS``): ``obs_mid``, ``obs_half`` ``(D,)``;
    ``rbf_centers``, ``rbf_widths`` ``(D, m)`` or None; ``weight`` ``(A, F)`` and ``bias`` ``(A,)``, or ``weight1``
    ``(A, H, F)``, ``bias1`` ``(A, H)``, ``weight2`` ``(A, H)``, ``bias2`` ``(A,)``. The weights are held as given
    (views, no copies), so in-place updates of them are seen by the next call.

    ``rbf_window`` ``r`` (RBF features only; None: dense) keeps only the Gaussians within ``r`` standard deviations of
    the input, ``|s~_i - c_ij| <= r * w_ij`` (decided on ``z = s * a - b`` as ``z * z <= r**2 / 2``, the same
    operations in every implementation), and sets every other feature to exactly 0. Each dropped feature is below
    ``exp(-r**2 / 2)`` (r = 5: 3.7e-6), so an output differs from the dense one by less than ``exp(-r**2 / 2)`` times
    the sum of the absolute weights on the dropped features (before the tanh for an MLP head, which does not enlarge
    it). Where every input's centres are evenly spaced with equal widths (:func:`~sb3_aac.common.approximators.rbf_layout`),
    batches of ``WINDOW_MIN_ROWS`` or more evaluate only a window of ``window_size`` centres per input (where that
    is at most half of them).
    """

    def __init__(
        self,
        obs_mid: np.ndarray,
        obs_half: np.ndarray,
        rbf_centers: np.ndarray | None = None,
        rbf_widths: np.ndarray | None = None,
        weight: np.ndarray | None = None,
        bias: np.ndarray | None = None,
        weight1: np.ndarray | None = None,
        bias1: np.ndarray | None = None,
        weight2: np.ndarray | None = None,
        bias2: np.ndarray | None = None,
        rbf_window: float | None = None,
    ):
        scale = 1.0 / obs_half
        shift = obs_mid * scale
        self.rbf = rbf_centers is not None
        if (rbf_centers is None) != (rbf_widths is None):
            raise ValueError("RBF features need both rbf_centers and rbf_widths (or neither, for scaled inputs)")
        self.window_z2 = math.inf  # features with z * z above this are 0
        self.window_size: int | None = None  # centres evaluated per input (None: all)
        if rbf_centers is not None:
            # exp(-0.5 * ((obs * scale - shift - c) / w)**2) = exp(-(obs * a - b)**2)
            inv_w = np.sqrt(0.5) / rbf_widths
            self.feature_a, self.feature_b = scale[:, None] * inv_w, (shift[:, None] + rbf_centers) * inv_w
            if rbf_window is not None:
                self._set_window(rbf_window)
        else:
            self.feature_a, self.feature_b = scale, shift
        self.mlp = weight1 is not None
        if weight1 is not None:
            if bias1 is None or weight2 is None or bias2 is None:
                raise ValueError("An MLP head needs weight1, bias1, weight2 and bias2")
            self.w1, self.b1, self.w2, self.b2 = weight1, bias1, weight2, bias2
            self.w1_flat, self.b1_flat = weight1.reshape(-1, weight1.shape[-1]), bias1.reshape(-1)
            self.head_w, self.head_b = self.w1_flat, self.b1_flat
        else:
            if weight is None or bias is None:
                raise ValueError("A linear head needs weight and bias")
            self.w, self.b = self.head_w, self.head_b = weight, bias

    def _set_window(self, rbf_window: float) -> None:
        check_rbf_window(rbf_window)
        self.window_z2 = 0.5 * float(rbf_window) ** 2
        m = self.feature_a.shape[1]
        step = self.feature_b[:, 1:] - self.feature_b[:, :-1] if m > 1 else np.ones((len(self.feature_b), 1))
        uniform = bool(
            m > 1
            and (self.feature_a == self.feature_a[:, :1]).all()
            and (step > 0).all()
            and np.allclose(step, step[:, :1], rtol=1e-9, atol=0.0)
        )
        if not uniform:
            return  # dense evaluation, then the mask
        # In z units centre j of input i sits at b_i0 + j * step_i (a_i common): the window |z| <= sqrt(window_z2)
        # spans at most 2 * sqrt(window_z2) / step + 1 centres; a margin of one on each side absorbs rounding.
        self._first_b, self._b_step = self.feature_b[:, 0].copy(), step[:, 0].copy()
        size = int(np.floor(2 * math.sqrt(self.window_z2) / self._b_step.min())) + 3
        if WINDOW_MIN_SHARE * size <= m:
            self.window_size = size
            self._input_index = np.arange(len(self.feature_b))
            # Row s + i * (m - size + 1): the feature_b values of input i's window starting at centre s.
            self._window_b = sliding_window_view(self.feature_b, size, axis=1).reshape(-1, size)
            self._window_rows = self._input_index * (m - size + 1)

    def features(self, obs: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """
        Observations ``(..., D)`` -> features ``(..., F)`` (float64).

        :param out: a float64 buffer of shape ``(..., *feature_a.shape)`` to compute in (saves allocations)
        """
        if self.window_size is not None and obs.size >= WINDOW_MIN_ROWS * len(self.feature_b):
            return self._window_features(obs, out, self.window_size)
        z: np.ndarray = np.multiply(obs[..., None] if self.rbf else obs, self.feature_a, out=out)
        np.subtract(z, self.feature_b, out=z)
        if not self.rbf:
            return z
        np.multiply(z, z, out=z)
        inside = z <= self.window_z2 if self.window_z2 < math.inf else None
        np.negative(z, out=z)
        np.exp(z, out=z)
        if inside is not None:
            np.multiply(z, inside, out=z)  # exactly 0 outside the window (a mask costs less than skipping exps)
        return z.reshape(*obs.shape[:-1], -1)

    def _window_features(self, obs: np.ndarray, out: np.ndarray | None, size: int) -> np.ndarray:
        """:meth:`features` evaluating only ``size`` evenly spaced centres per input (same values)."""
        a = self.feature_a[:, 0]
        d, m = self.feature_a.shape
        rows = obs.reshape(-1, d)
        first = np.floor((rows * a - self._first_b - math.sqrt(self.window_z2)) / self._b_step) - 1.0
        np.clip(first, 0, m - size, out=first)
        start = first.astype(np.int64)  # (n, D): each input's first evaluated centre
        b = self._window_b.take(start + self._window_rows, axis=0)  # (n, D, size)
        z = rows[..., None] * a[:, None] - b  # the dense formula's operations, on the window only
        np.multiply(z, z, out=z)
        inside = z <= self.window_z2
        np.negative(z, out=z)
        np.exp(z, out=z)
        np.multiply(z, inside, out=z)
        phi = np.zeros((len(rows) * d, m)) if out is None else out.reshape(len(rows) * d, m)
        if out is not None:
            phi.fill(0.0)
        windows = sliding_window_view(phi, size, axis=1, writeable=True)  # (n * D, m - size + 1, size)
        windows[np.arange(len(phi)), start.reshape(-1)] = z.reshape(-1, size)
        return phi.reshape(*obs.shape[:-1], d * m)

    def outputs(self, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """Features ``(..., F)`` -> every output ``(..., A)``, and the tanh activations ``(..., A, H)`` (None if linear)."""
        pre = phi @ self.head_w.T + self.head_b
        if not self.mlp:
            return pre, None
        hidden = np.tanh(pre, out=pre).reshape(*phi.shape[:-1], *self.w2.shape)
        return (hidden * self.w2).sum(-1) + self.b2, hidden


class TileForward:
    """
    The forward pass of a bank of ``A`` linear approximators on tile-coding features: the only implementation
    of these formulas (training subclasses it, :class:`sb3_aac.common.tile_coding.TileKernel`).

    ``C`` codings (one per group of inputs and tiling) each activate exactly one binary feature. Coding ``c``
    reads the inputs ``tile_inputs[c]`` (``k`` per coding; a padded slot has stride 0), scales each to
    ``[-1, 1]`` with ``obs_mid`` / ``obs_half``, and takes the tile coordinate
    ``clip(floor((s~ + 1) / 2 * tile_resolution + tile_offsets), 0, tile_resolution)`` per input; its active feature
    is ``tile_bases[c] + sum_j coordinate_j * tile_strides[c, j]``. The output of approximator ``a`` is
    ``sum_c tile_weight[active_c, a] + bias[a]``, so one evaluation costs ``O(C * A)`` whatever the table size.

    The arguments are the arrays of the export format: ``obs_mid``, ``obs_half`` ``(D,)``; ``tile_inputs``,
    ``tile_offsets``, ``tile_resolution``, ``tile_strides`` ``(C, k)``; ``tile_bases`` ``(C,)``; ``tile_weight``
    ``(F, A)``; ``bias`` ``(A,)``. Index arrays may be given as float64 (as files store them). The weights are held
    as given (views), so in-place updates are seen by the next call.
    """

    def __init__(
        self,
        obs_mid: np.ndarray,
        obs_half: np.ndarray,
        tile_inputs: np.ndarray,
        tile_offsets: np.ndarray,
        tile_resolution: np.ndarray,
        tile_strides: np.ndarray,
        tile_bases: np.ndarray,
        tile_weight: np.ndarray,
        bias: np.ndarray,
    ):
        self.inputs = np.asarray(tile_inputs).astype(np.int64)
        half = np.asarray(obs_half, dtype=np.float64)[self.inputs]
        mid = np.asarray(obs_mid, dtype=np.float64)[self.inputs]
        resolution = np.asarray(tile_resolution, dtype=np.float64)
        # (s - mid) / half * res / 2 + res / 2 + offset = s * a - b
        self.tile_a = resolution / (2 * half)
        self.tile_b = mid * self.tile_a - resolution / 2 - np.asarray(tile_offsets, dtype=np.float64)
        self.limit = resolution
        self.strides = np.asarray(tile_strides).astype(np.int64)
        self.bases = np.asarray(tile_bases).astype(np.int64)
        self.w, self.b = tile_weight, bias

    def features(self, obs: np.ndarray) -> np.ndarray:
        """Observations ``(n, D)`` -> the active feature of every coding, ``(n, C)`` int64."""
        position = obs[:, self.inputs] * self.tile_a - self.tile_b  # (n, C, k)
        np.floor(position, out=position)
        np.clip(position, 0.0, self.limit, out=position)
        active: np.ndarray = np.einsum("nck,ck->nc", position.astype(np.int64), self.strides) + self.bases
        return active

    def outputs(self, active: np.ndarray) -> tuple[np.ndarray, None]:
        """Active features ``(n, C)`` -> every output ``(n, A)`` (and None: there is no hidden layer)."""
        return self.w[active].sum(1) + self.b, None


def expected_array_shapes(header: dict[str, Any]) -> dict[str, tuple[int, ...]]:
    """The arrays a version-1 or -2 file must hold, with their shapes, given its (checked) header."""
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
    elif approx["head"]["type"] == "linear":
        shapes.update(weight=(a, f), bias=(a,))
    else:
        h = approx["head"]["hidden_units"]
        shapes.update(weight1=(a, h, f), bias1=(a, h), weight2=(a, h), bias2=(a,))
    return shapes


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


def _check_features_and_head(features: Any, head: Any, d: int, path: Any) -> None:
    """The header's ``features`` and ``head`` sections (``KeyError``/``TypeError`` for a missing or mistyped field)."""
    if features["type"] == "rbf":
        if not _positive_int(features["n_rbf"]) or features["n_features"] != d * features["n_rbf"]:
            raise _fail(path, f"RBF features: n_rbf={features['n_rbf']!r}, n_features={features['n_features']!r}, {d} inputs")
        try:  # version 1 has no window: dense
            check_rbf_window(features.get("rbf_window"))
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
    if head["type"] == "tanh_mlp":
        if not _positive_int(head["hidden_units"]):
            raise _fail(path, f"hidden_units={head['hidden_units']!r}")
    elif head["type"] != "linear":
        raise _fail(path, f"unknown head type {head['type']!r} (known: 'linear', 'tanh_mlp')")


def _check_header(header: Any, path: Any) -> None:
    """Structure and consistency of a version-1 or -2 header (everything but the arrays)."""
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
        features, head = approx["features"], approx["head"]
        if not (_positive_int(features["n_features"]) and _positive_int(approx["n_outputs"])):
            sizes = f"n_features={features['n_features']!r}, n_outputs={approx['n_outputs']!r}"
            raise _fail(path, f"{sizes}: both must be whole numbers >= 1")
        _check_features_and_head(features, head, d, path)
        outputs = approx["outputs"]
        expected = {"q": [0, k], "params": [k, k + offset], "value": k + offset}
        if approx["n_outputs"] != k + offset + 1 or outputs != expected:
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
            f"unknown format version {version!r}; this reader supports {list(SUPPORTED_VERSIONS)} "
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
            raise _fail(path, f"array {name!r} has dtype {dtype!r}, versions 1 and 2 store every array as {ARRAY_DTYPE!r}")
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


def _compile_act_kernel() -> Any:  # noqa: C901 (a compiled kernel: its loops and branches are the point)
    """
    A numba-compiled ``act`` for one observation, or None without numba: :meth:`BankForward.features` and
    :meth:`BankForward.outputs` (on :class:`BankForward`'s folded constants and weights), the argmax and
    :meth:`RuntimePolicy.unscale`, the same formulas written as loops and compiled.

    Optional, and only a speed-up: the runtime needs only numpy; numba (a dependency of sb3-aac) removes numpy's
    per-call overhead, a microsecond or more for each of the dozen array operations of a decision, which a single
    decision cannot amortise (numpy alone does not reach 10 us). Sums run in a different order than numpy's BLAS,
    so outputs can differ from the numpy path in the last bit; the decisions are the same except for exact ties of
    that size (tested on every policy and layout).
    """
    try:
        import numba
    except ImportError:
        return None

    # reassoc lets LLVM vectorise the dot products (their order differs from numpy's BLAS anyway); no nnan/ninf,
    # so the finiteness check stays valid.
    # Untyped for mypy: numba infers the argument types from the arrays it is called with.
    @numba.njit(cache=True, nogil=True, fastmath={"reassoc"})
    def act_kernel(x, pack, meta, phi, active, params):  # type: ignore[no-untyped-def]  # noqa: C901  # pragma: no cover
        # Few arguments: numba's dispatch costs about as much per argument as a small loop iteration does.
        # meta: d, m (RBFs per input, 0: scaled inputs), F, H (0: linear head), K, 8 segment starts in pack,
        # then the K + 1 parameter offsets. pack: BankForward's feature_a, feature_b, head_w, head_b, w2, b2
        # (MLP head); parameter low, high; window_z2. phi[:n_active] holds the features that are not 0 (outside
        # the RBF window), active[:n_active] their indices.
        d, m, n_features, h, n_types = meta[0], meta[1], meta[2], meta[3], meta[4]
        fa, fb, pw, pb, pw2, pb2, plow, pwin = meta[5], meta[6], meta[7], meta[8], meta[9], meta[10], meta[11], meta[12]
        total = 0.0
        for i in range(d):
            total += x[i] * x[i]
        if not np.isfinite(total):
            return -1, 0
        n_active = 0
        if m > 0:
            window_z2 = pack[pwin]
            for i in range(d):
                for j in range(m):
                    z = x[i] * pack[fa + i * m + j] - pack[fb + i * m + j]
                    if z * z <= window_z2:
                        phi[n_active] = np.exp(-(z * z))
                        active[n_active] = i * m + j
                        n_active += 1
        else:
            for i in range(d):
                phi[i] = x[i] * pack[fa + i] - pack[fb + i]
                active[i] = i
            n_active = d

        def output(a: int) -> float:  # numba ignores the annotations
            if h > 0:
                acc = 0.0
                for u in range(h):
                    row = a * h + u
                    s = 0.0
                    for f in range(n_active):
                        s += pack[pw + row * n_features + active[f]] * phi[f]
                    acc += np.tanh(s + pack[pb + row]) * pack[pw2 + row]
                return acc + pack[pb2 + a]  # type: ignore[no-any-return]  # numba: pack's elements are untyped
            s = 0.0
            for f in range(n_active):
                s += pack[pw + a * n_features + active[f]] * phi[f]
            return s + pack[pb + a]  # type: ignore[no-any-return]  # numba: pack's elements are untyped

        k, best = 0, output(0)
        for a in range(1, n_types):
            q = output(a)
            if q > best:
                k, best = a, q
        start, dim = meta[13 + k], meta[14 + k] - meta[13 + k]
        n_params = meta[13 + n_types]
        for j in range(dim):
            weight = 0.5 * output(n_types + start + j)
            lo, hi = pack[plow + start + j], pack[plow + n_params + start + j]
            params[j] = min(max(lo * (0.5 - weight) + hi * (0.5 + weight), lo), hi)
        return k, dim

    return act_kernel


_ACT_KERNEL: Any = False  # compiled on first use


def _act_kernel() -> Any:
    global _ACT_KERNEL
    if _ACT_KERNEL is False:
        _ACT_KERNEL = _compile_act_kernel()
    return _ACT_KERNEL


class RuntimePolicy:
    """
    A SarsaAAC policy read from an exported file: greedy decisions with numpy only.

    ``act`` follows the paper's decision procedure (Uc-Cetina 2013, Sec. 4.3): the K action-type values, their
    maximum, then the parameters of the chosen type only, so one decision costs ``O(n)`` in the number of
    features. Use :meth:`load` to build one.

    :ivar n_types: number of action types K
    :ivar type_start: the env's number for type 0 (``Discrete.start``; 0 for ``OneOf``)
    :ivar obs_shape: the observation shape the policy was trained on
    :ivar header: the file's JSON header (a dict)
    """

    def __init__(self, header: dict[str, Any], arrays: dict[str, np.ndarray], path: Any = "<memory>", backend: str = "auto"):
        if backend not in BACKENDS:
            raise ValueError(f"Unknown backend {backend!r}, choose one of {list(BACKENDS)}")
        self.header, self.path = header, path
        obs, action, approx = header["observation"], header["action"], header["approximators"]
        self.obs_shape = tuple(obs["shape"])
        self.obs_size = obs["size"]
        self.layout, self.n_types, self.type_start = action["layout"], action["n_types"], action["type_start"]
        types = action["types"]
        self.dims = tuple(t["dim"] for t in types)
        self.offsets = (*(t["offset"] for t in types), action["n_params"])
        self.param_shapes = tuple(tuple(t["shape"]) for t in types)
        self.param_dtypes = tuple(np.dtype(t["dtype"]) for t in types)
        self.n_params = action["n_params"]
        self.obs_low, self.obs_high = arrays["obs_low"], arrays["obs_high"]
        self.param_low, self.param_high = arrays["param_low"], arrays["param_high"]
        for name, values in arrays.items():
            if name in ("obs_low", "obs_high"):
                if np.isnan(values).any():
                    raise _fail(path, f"array {name!r} holds NaN")
            elif not np.isfinite(values).all():
                raise _fail(path, f"array {name!r} holds NaN or inf values")
        if not (arrays["obs_half"] > 0).all():
            raise _fail(path, "obs_half must be > 0 everywhere")
        if not (self.param_low <= self.param_high).all():
            raise _fail(path, "param_low must be <= param_high everywhere")

        if "rbf_widths" in arrays and not (arrays["rbf_widths"] > 0).all():
            raise _fail(path, "rbf_widths must be > 0 everywhere")
        self.tiles = approx["features"]["type"] == "tiles"
        self.hidden_units = approx["head"].get("hidden_units")
        k = self.n_types
        self._p_slice = slice(k, k + self.n_params)
        # Per type: its parameter bounds as Python floats.
        slices = [self.type_slice(j) for j in range(k)]
        self._bounds_lists = [(self.param_low[s].tolist(), self.param_high[s].tolist()) for s in slices]
        self._kernel_args: tuple[np.ndarray, ...] | None = None
        if self.tiles:
            _check_tile_arrays(arrays, self.obs_size, approx["features"]["n_features"], path)
            if backend == "numba":
                raise ValueError("backend='numba' computes dense features only; tile-coding policies run with numpy ('auto')")
            self._bank: BankForward | TileForward = TileForward(**{name: arrays[name] for name in TILE_ARRAYS})
            self.rbf = self.mlp = False
            self.backend = "numpy"
            return
        window = approx["features"].get("rbf_window")
        self._bank = bank = BankForward(**{name: arrays[name] for name in BANK_ARRAYS if name in arrays}, rbf_window=window)
        self.rbf, self.mlp = bank.rbf, bank.mlp
        self._feature_buffer = np.empty(bank.feature_a.shape)  # (D,) or (D, m), reused by act()
        if backend != "numpy":
            kernel = _act_kernel()
            if kernel is None and backend == "numba":
                raise ValueError("backend='numba' needs numba (pip install numba); use backend='numpy' or 'auto'")
            if kernel is not None:
                head2 = [bank.w2, bank.b2] if self.mlp else [np.zeros(0), np.zeros(0)]
                segments = [bank.feature_a, bank.feature_b, bank.head_w, bank.head_b, *head2, self.param_low, self.param_high]
                segments.append(np.array([bank.window_z2]))
                segment_starts = np.cumsum([0] + [seg.size for seg in segments])[:-1]
                # param_low's start also locates param_high
                starts = [*segment_starts[:6], segment_starts[6], segment_starts[8]]
                m = bank.feature_a.shape[1] if self.rbf else 0
                sizes = [self.obs_size, m, approx["features"]["n_features"], self.hidden_units or 0, k]
                meta = np.array([*sizes, *starts, *self.offsets], dtype=np.int64)
                pack = np.concatenate([seg.ravel() for seg in segments])
                self._kernel = kernel
                active = np.empty(self._feature_buffer.size, dtype=np.int64)
                self._kernel_args = (pack, meta, self._feature_buffer.reshape(-1), active, np.empty(max(self.dims)))
        self.backend = "numpy" if self._kernel_args is None else "numba"

    # ------------------------------------------------------------------ loading

    @classmethod
    def load(cls, path: str | os.PathLike[str], backend: str = "auto") -> RuntimePolicy:
        """
        Read a policy file written by :func:`sb3_aac.export_policy`.

        :param path: the file, or the name given to ``export_policy`` (``.aacp`` is appended to a name without a
            suffix when no such file exists, as ``export_policy`` appends it)

        :param backend: how :meth:`act` computes: ``"numpy"`` (:class:`BankForward`, the code training runs),
            ``"numba"`` (compiled, several times faster on one observation), or ``"auto"`` (numba when it can be
            imported). Batched methods always use numpy.

        :raises ValueError: naming what is wrong, for a truncated, corrupted, altered or unsupported file
        :raises FileNotFoundError: if there is no such file
        """
        header, arrays = read_policy_file(path)
        return cls(header, arrays, path, backend)

    def __repr__(self) -> str:
        approx = self.header["approximators"]
        return (
            f"RuntimePolicy({self.path!s}: {self.header.get('policy_class')}, {self.obs_size} inputs, "
            f"{approx['features']['n_features']} features, head {approx['head']}, {self.n_types} action types, "
            f"dims {list(self.dims)}, layout {self.layout!r})"
        )

    def type_slice(self, k: int) -> slice:
        """Columns of 0-based type ``k``'s parameters in the concatenated parameter vector."""
        return slice(self.offsets[k], self.offsets[k + 1])

    # ------------------------------------------------------------------ one observation

    def _observation(self, obs: Any) -> np.ndarray:
        x = np.asarray(obs, dtype=np.float64)
        if x.shape != self.obs_shape and x.shape != (self.obs_size,):
            raise ValueError(
                f"Expected one observation of shape {self.obs_shape} ({self.obs_size} values), got shape {x.shape}; "
                "use act_batch for a batch"
            )
        x = x.reshape(-1)
        if not math.isfinite(np.dot(x, x)):  # one reduction: NaN and inf (and absurd magnitudes) reach the sum
            raise ValueError(f"The observation holds NaN or inf values: {x}")
        return x

    def act(self, obs: Any) -> tuple[int, np.ndarray]:
        """
        The greedy decision for one observation.

        Not thread-safe (it reuses internal buffers): give each thread its own ``RuntimePolicy``.

        :param obs: one observation, of the trained shape or flat
        :return: the action type as the env numbers it (``type_start + k``) and that type's parameters in the
            env's units, clipped to its bounds: a flat array of ``dims[k]`` values in its Box's dtype
        :raises ValueError: for a wrong observation size or non-finite values
        """
        if self._kernel_args is not None:
            x = np.asarray(obs, dtype=np.float64)
            if x.shape != self.obs_shape and x.shape != (self.obs_size,):
                self._observation(x)  # raises the shape error
            k, dim = self._kernel(x.reshape(-1), *self._kernel_args)
            if k < 0:
                raise ValueError(f"The observation holds NaN or inf values: {x}")
            return self.type_start + k, self._kernel_args[-1][:dim].astype(self.param_dtypes[k])
        if isinstance(self._bank, TileForward):  # self.tiles
            out = self._bank.outputs(self._bank.features(self._observation(obs)[None]))[0][0].tolist()
        else:
            phi = self._bank.features(self._observation(obs), out=self._feature_buffer)
            # Every output at once: with numpy, one matrix-vector product costs less than separate calls for Q and
            # for the chosen type's parameters (a C++ runtime would compute only those, see docs/export-format.md).
            out = self._bank.outputs(phi)[0].tolist()
        q = out[: self.n_types]
        k = q.index(max(q))  # the first maximum, like numpy's argmax
        # Unscale in Python floats: the same IEEE operations as unscale(), cheaper on a few values.
        values = []
        start = self.n_types + self.offsets[k]
        for scaled, low, high in zip(out[start : start + self.dims[k]], *self._bounds_lists[k], strict=True):
            weight = 0.5 * scaled
            values.append(min(max(low * (0.5 - weight) + high * (0.5 + weight), low), high))
        return self.type_start + k, np.array(values, dtype=self.param_dtypes[k])

    def __call__(self, obs: Any) -> tuple[int, np.ndarray]:
        return self.act(obs)

    # ------------------------------------------------------------------ batches

    def _batch(self, obs: Any) -> np.ndarray:
        x = np.asarray(obs, dtype=np.float64)
        if x.ndim < 1 or (x.shape[1:] != self.obs_shape and x.shape[1:] != (self.obs_size,)):
            raise ValueError(
                f"Expected a batch of observations of shape (n, {', '.join(map(str, self.obs_shape))}) "
                f"or (n, {self.obs_size}), got shape {x.shape}"
            )
        x = x.reshape(len(x), -1)
        if not np.isfinite(x).all():
            rows = np.flatnonzero(~np.isfinite(x).all(1))
            raise ValueError(f"Observation(s) {rows[:10].tolist()} of the batch hold NaN or inf values")
        return x

    def outputs(self, obs: Any) -> np.ndarray:
        """
        Every approximator's output for a batch ``(n, D)``: ``(n, A)`` columns Q (K), scaled parameters
        (n_params), value V (1).
        """
        outputs: np.ndarray = self._bank.outputs(self._bank.features(self._batch(obs)))[0]
        return outputs

    def unscale(self, params_scaled: np.ndarray) -> np.ndarray:
        """Scaled parameters ``(..., n_params)`` in ``[-1, 1]`` -> env units, clipped to the bounds (float64)."""
        return unscale(self.param_low, self.param_high, params_scaled)

    def act_batch(self, obs: Any) -> tuple[np.ndarray, np.ndarray]:
        """
        Greedy decisions for a batch of observations.

        :return: action types ``(n,)`` (int64, numbered as the env numbers them) and the parameters ``(n, n_params)``
            (float64, env units, clipped) of *every* type; observation ``i``'s chosen parameters are
            ``params[i, policy.type_slice(types[i] - policy.type_start)]``
        """
        out = self.outputs(obs)
        k = out[:, : self.n_types].argmax(1)
        return k + self.type_start, self.unscale(out[:, self._p_slice])

    def value(self, obs: Any) -> np.ndarray:
        """The critic's state values ``V(s)`` for a batch ``(n,)``."""
        return self.outputs(obs)[:, -1]

    # ------------------------------------------------------------------ SB3-style predict

    def _env_action(self, k: int, params: np.ndarray) -> tuple[Any, ...]:
        """One env action in the file's layout, as ``model.predict`` builds it (0-based ``k``)."""
        return env_action(self.layout, self.type_start, k, self.n_types, self._box_value, params)

    def _box_value(self, j: int, params: np.ndarray) -> np.ndarray:
        """Type ``j``'s part of the parameter vector ``params`` in its Box's shape and dtype."""
        return params[self.type_slice(j)].astype(self.param_dtypes[j]).reshape(self.param_shapes[j])

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[Any, Any]:
        """
        The SB3 ``predict`` interface (greedy; ``deterministic`` is ignored), so evaluation code written for a
        model takes a ``RuntimePolicy`` too.

        :return: one env action (a tuple in the action space's layout) for one observation, or an object array of
            them for a batch; and ``state``
        """
        x = np.asarray(observation, dtype=np.float64)
        single = x.shape == self.obs_shape
        types, params = self.act_batch(x[None] if single else x)
        types = types - self.type_start
        if single:
            return self._env_action(int(types[0]), params[0]), state
        actions = np.empty(len(types), dtype=object)
        for i in range(len(types)):
            actions[i] = self._env_action(int(types[i]), params[i])
        return actions, state
