"""
The optional numba kernels behind :meth:`~sb3_aac.runtime.policy.RuntimePolicy.act`: one greedy decision for one
observation, the formulas of :class:`~sb3_aac.runtime.forward.BankForward` (and further down of the ``networks`` and
``pdqn`` heads) and
:func:`~sb3_aac.runtime.actions.unscale_value` written as loops and compiled. Without numba the runtime uses numpy
alone.

The kernel takes its numbers in two flat vectors, built by :func:`kernel_arguments`: ``pack`` (float64), the arrays
named by :data:`PACK_FIELDS` one after the other, and ``meta`` (int64), laid out as :data:`META_FIELDS` (the sizes,
then where each array of ``pack`` starts) followed by the K + 1 parameter offsets. Every index into ``meta`` is a
constant looked up by name in :data:`META_FIELDS`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .actions import unscale_value
from .forward import BankForward, NetworkForward, PDQNForward

# n_rbf: RBFs per input (0: scaled inputs); hidden_units: tanh units per approximator (0: linear head).
SIZE_FIELDS = ("n_inputs", "n_rbf", "n_features", "hidden_units", "n_types")
# BankForward's folded feature constants and head weights (w2, b2 empty for a linear head), the parameter bounds,
# and the RBF window (one value).
PACK_FIELDS = ("feature_a", "feature_b", "head_w", "head_b", "w2", "b2", "param_low", "param_high", "window_z2")
META_FIELDS = (*SIZE_FIELDS, *PACK_FIELDS)  # a PACK_FIELDS name in meta: where that array starts in pack
M_INPUTS, M_RBF, M_FEATURES, M_HIDDEN, M_TYPES = (META_FIELDS.index(f) for f in SIZE_FIELDS)
M_FEATURE_A, M_FEATURE_B, M_HEAD_W, M_HEAD_B, M_W2, M_B2, M_PARAM_LOW, M_PARAM_HIGH, M_WINDOW = (
    META_FIELDS.index(f) for f in PACK_FIELDS
)
M_OFFSETS = len(META_FIELDS)  # type k's parameters are offsets k to k + 1 of the parameter vector


def kernel_arguments(
    bank: BankForward, param_low: np.ndarray, param_high: np.ndarray, offsets: Sequence[int]
) -> tuple[np.ndarray, np.ndarray]:
    """
    ``pack`` and ``meta`` for the kernel (see the module docstring) of ``bank``'s dense features and head, with the
    parameter bounds ``param_low``, ``param_high`` ``(n_params,)`` and the K + 1 parameter ``offsets``.
    """
    w2, b2 = (bank.w2, bank.b2) if bank.mlp else (np.zeros(0), np.zeros(0))
    arrays = {
        "feature_a": bank.feature_a,
        "feature_b": bank.feature_b,
        "head_w": bank.head_w,
        "head_b": bank.head_b,
        "w2": w2,
        "b2": b2,
        "param_low": param_low,
        "param_high": param_high,
        "window_z2": np.array([bank.window_z2]),
    }
    segments = [np.ravel(arrays[name]) for name in PACK_FIELDS]
    starts = np.cumsum([0] + [segment.size for segment in segments])[:-1]
    sizes = {
        "n_inputs": len(bank.feature_a),
        "n_rbf": bank.feature_a.shape[1] if bank.rbf else 0,
        "n_features": bank.head_w.shape[-1],
        "hidden_units": w2.shape[-1] if bank.mlp else 0,
        "n_types": len(offsets) - 1,
    }
    meta = np.array([*(sizes[name] for name in SIZE_FIELDS), *starts, *offsets], dtype=np.int64)
    return np.concatenate(segments), meta


def _compile_act_kernel() -> Any:  # noqa: C901 (a compiled kernel: its loops and branches are the point)
    """
    A numba-compiled ``act`` for one observation, or None without numba: :meth:`BankForward.features` and
    :meth:`BankForward.outputs` (on :class:`BankForward`'s folded constants and weights), the argmax and
    :func:`~sb3_aac.runtime.actions.unscale_value`, the same formulas written as loops and compiled.

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

    unscale_one = numba.njit(inline="always")(unscale_value)

    # reassoc lets LLVM vectorise the dot products (their order differs from numpy's BLAS anyway); no nnan/ninf,
    # so the finiteness check stays valid.
    # Untyped for mypy: numba infers the argument types from the arrays it is called with.
    @numba.njit(cache=True, nogil=True, fastmath={"reassoc"})
    def act_kernel(x, pack, meta, phi, active, params):  # type: ignore[no-untyped-def]  # noqa: C901  # pragma: no cover
        # Few arguments: numba's dispatch costs about as much per argument as a small loop iteration does.
        # pack and meta: see the module docstring. phi[:n_active] holds the features that are not 0 (outside the RBF
        # window), active[:n_active] their indices.
        d, m, n_features, h = meta[M_INPUTS], meta[M_RBF], meta[M_FEATURES], meta[M_HIDDEN]
        n_types, fa, fb, pw, pb = meta[M_TYPES], meta[M_FEATURE_A], meta[M_FEATURE_B], meta[M_HEAD_W], meta[M_HEAD_B]
        pw2, pb2, plow, phigh, pwin = meta[M_W2], meta[M_B2], meta[M_PARAM_LOW], meta[M_PARAM_HIGH], meta[M_WINDOW]
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
        start, dim = meta[M_OFFSETS + k], meta[M_OFFSETS + k + 1] - meta[M_OFFSETS + k]
        for j in range(dim):
            params[j] = unscale_one(output(n_types + start + j), pack[plow + start + j], pack[phigh + start + j])
        return k, dim

    return act_kernel


_ACT_KERNEL: Any = False  # compiled on first use


def act_kernel() -> Any:
    """The compiled kernel (compiled on the first call), or None without numba. Call it as
    ``act_kernel()(x, pack, meta, phi, active, params) -> (k, dim)``: the chosen 0-based type ``k`` (-1 for an
    observation with NaN or inf) and its parameters in ``params[:dim]``; ``phi`` and ``active`` are scratch buffers
    of ``n_features`` float64 and int64 values."""
    global _ACT_KERNEL
    if _ACT_KERNEL is False:
        _ACT_KERNEL = _compile_act_kernel()
    return _ACT_KERNEL


# The numba kernels of a "networks" head (NetworkForward) and of a "pdqn" head (PDQNForward). Their meta (int64) starts
# with NETWORK_FIELDS (sizes, then where each array of its pack starts), then the K + 1 parameter offsets, then
# NETWORK_RECORD values per network, then LAYER_RECORD values per layer; their pack (float64) holds the input scaling,
# the parameter bounds and every layer's arrays and constant.
NETWORK_FIELDS = ("n_inputs", "n_types", "n_networks", "multi_pass", "feature_a", "feature_b", "param_low", "param_high")
N_INPUTS, N_TYPES, N_NETWORKS, N_MULTI_PASS, N_FEATURE_A, N_FEATURE_B, N_PARAM_LOW, N_PARAM_HIGH = range(len(NETWORK_FIELDS))
# Per network: its first output column, one past its last, whether act() needs it (it writes Q or parameters), its
# first layer record, its number of layers and its number of inputs.
NETWORK_RECORD = ("start", "stop", "needed", "first_layer", "n_layers", "n_in")
# Per layer: its code (LAYER_CODES), its number of inputs and outputs, where its weight, bias (-1: none) and
# constant (eps or slope) start in pack.
LAYER_RECORD = ("code", "n_in", "n_out", "weight", "bias", "constant")
LAYER_CODES = ("linear", "layernorm", "tanh", "relu", "leaky_relu")


def network_kernel_arguments(
    net: NetworkForward | PDQNForward, param_low: np.ndarray, param_high: np.ndarray, offsets: Sequence[int]
) -> tuple[np.ndarray, np.ndarray, int]:
    """``pack``, ``meta`` (see the comments above :data:`NETWORK_FIELDS`) and the widest layer or input of ``net``."""
    segments: list[np.ndarray] = []
    position = 0

    def put(values: np.ndarray | None) -> int:
        nonlocal position
        if values is None:
            return -1
        segments.append(np.ravel(values).astype(np.float64))
        start, position = position, position + segments[-1].size
        return start

    d, n_types = len(net.feature_a), len(offsets) - 1
    value_column = n_types + offsets[-1]
    pdqn = isinstance(net, PDQNForward)
    inputs = (d, d + offsets[-1]) if pdqn else (d,) * len(net.columns)  # PDQNForward: the Q network reads [x, p]
    starts = [put(net.feature_a), put(net.feature_b), put(param_low), put(param_high)]
    network_records: list[int] = []
    layer_records: list[int] = []
    width = max(inputs)
    for (start, stop), layers, n_in in zip(net.columns, net.layers, inputs, strict=True):
        first = len(layer_records) // len(LAYER_RECORD)
        network_records += [start, stop, int(start < value_column), first, len(layers), n_in]
        size = n_in
        for kind, weight, bias, constant in layers:
            n_out = len(weight) if kind == "linear" and weight is not None else size
            layer_records += [LAYER_CODES.index(kind), size, n_out, put(weight), put(bias), put(np.array([constant]))]
            size, width = n_out, max(width, n_out)
    multi_pass = int(isinstance(net, PDQNForward) and net.multi_pass)
    fields = [d, n_types, len(net.columns), multi_pass, *starts]
    meta = np.array([*fields, *offsets, *network_records, *layer_records], dtype=np.int64)
    return np.concatenate(segments), meta, width


def _compile_network_kernels() -> tuple[Any, Any] | None:  # noqa: C901 (compiled kernels: their loops are the point)
    """
    The numba-compiled ``act`` for one observation of a ``networks`` head and of a ``pdqn`` head, or None without
    numba: the formulas of :class:`~sb3_aac.runtime.forward.NetworkForward` (skipping the networks that write only
    the value) and :class:`~sb3_aac.runtime.forward.PDQNForward`, the argmax and
    :func:`~sb3_aac.runtime.actions.unscale_value`, written as loops. Sums run in another order than numpy's, so
    outputs can differ in the last bits; the decisions are the same except at ties of that size.
    """
    try:
        import numba
    except ImportError:
        return None

    unscale_one = numba.njit(inline="always")(unscale_value)
    n_fields, n_net, n_layer = len(NETWORK_FIELDS), len(NETWORK_RECORD), len(LAYER_RECORD)

    @numba.njit(cache=True, nogil=True, fastmath={"reassoc"})
    def run_network(pack, meta, net, scratch):  # type: ignore[no-untyped-def]  # pragma: no cover
        # Network net on scratch[0, :n_in]; its values end in one of rows 1 and 2 (returned), which it uses in turn.
        n_types, n_networks = meta[N_TYPES], meta[N_NETWORKS]
        r = n_fields + n_types + 1 + net * n_net
        layer_base = n_fields + n_types + 1 + n_networks * n_net
        src, size = 0, meta[r + 5]
        for layer in range(meta[r + 3], meta[r + 3] + meta[r + 4]):
            q = layer_base + layer * n_layer
            code, n_out, pw, pb, pc = meta[q], meta[q + 2], meta[q + 3], meta[q + 4], meta[q + 5]
            dst = 1 if src != 1 else 2
            h, y = scratch[src], scratch[dst]  # 1-D views: contiguous loops that LLVM vectorises
            if code == 0:  # linear
                weight = pack[pw : pw + n_out * size]
                for o in range(n_out):
                    row = weight[o * size : (o + 1) * size]
                    acc = 0.0
                    for i in range(size):
                        acc += row[i] * h[i]
                    y[o] = acc + pack[pb + o]
                src, size = dst, n_out
                continue
            if code == 1:  # layernorm
                mean = 0.0
                for i in range(size):
                    mean += h[i]
                mean /= size
                var = 0.0
                for i in range(size):
                    c = h[i] - mean
                    var += c * c
                inv_std = 1.0 / np.sqrt(var / size + pack[pc])
                for i in range(size):
                    v = (h[i] - mean) * inv_std
                    y[i] = v * pack[pw + i] + pack[pb + i] if pw >= 0 else v
            elif code == 2:
                for i in range(size):
                    y[i] = np.tanh(h[i])
            elif code == 3:
                for i in range(size):
                    y[i] = max(h[i], 0.0)
            else:
                slope = pack[pc]
                for i in range(size):
                    v = h[i]
                    y[i] = v if v > 0.0 else slope * v
            src = dst
        return src

    @numba.njit(cache=True, nogil=True, fastmath={"reassoc"})
    def scaled_input(x, pack, meta, scratch):  # type: ignore[no-untyped-def]  # pragma: no cover
        # The scaled inputs into scratch[0, :d]; False for an observation with NaN or inf.
        d, fa, fb = meta[N_INPUTS], meta[N_FEATURE_A], meta[N_FEATURE_B]
        total = 0.0
        for i in range(d):
            total += x[i] * x[i]
        if not np.isfinite(total):
            return False
        for i in range(d):
            scratch[0, i] = x[i] * pack[fa + i] - pack[fb + i]
        return True

    @numba.njit(cache=True, nogil=True, fastmath={"reassoc"})
    def decide(pack, meta, out, params):  # type: ignore[no-untyped-def]  # pragma: no cover
        # The first maximum of out[:K], and its type's parameters unscaled into params.
        n_types, plow, phigh = meta[N_TYPES], meta[N_PARAM_LOW], meta[N_PARAM_HIGH]
        k, best = 0, out[0]
        for a in range(1, n_types):
            if out[a] > best:
                k, best = a, out[a]
        start, dim = meta[n_fields + k], meta[n_fields + k + 1] - meta[n_fields + k]
        for j in range(dim):
            params[j] = unscale_one(out[n_types + start + j], pack[plow + start + j], pack[phigh + start + j])
        return k, dim

    @numba.njit(cache=True, nogil=True, fastmath={"reassoc"})
    def act_network_kernel(x, pack, meta, scratch, out, params):  # type: ignore[no-untyped-def]  # pragma: no cover
        # scratch: (3, width) float64; row 0 holds the scaled input, rows 1 and 2 a network's layers in turn.
        if not scaled_input(x, pack, meta, scratch):
            return -1, 0
        records = n_fields + meta[N_TYPES] + 1
        for net in range(meta[N_NETWORKS]):
            r = records + net * n_net
            if meta[r + 2] == 0:
                continue
            src = run_network(pack, meta, net, scratch)
            for j in range(meta[r + 1] - meta[r]):
                out[meta[r] + j] = scratch[src, j]
        return decide(pack, meta, out, params)

    @numba.njit(cache=True, nogil=True, fastmath={"reassoc"})
    def act_pdqn_kernel(x, pack, meta, scratch, out, params):  # type: ignore[no-untyped-def]  # pragma: no cover
        # scratch: (3, width) float64; row 0 holds [x, p], the Q network's input, rows 1 and 2 a network's layers.
        if not scaled_input(x, pack, meta, scratch):
            return -1, 0
        d, n_types = meta[N_INPUTS], meta[N_TYPES]
        offsets = n_fields
        n_params = meta[offsets + n_types]
        src = run_network(pack, meta, 0, scratch)  # the parameter actor
        for j in range(n_params):
            out[n_types + j] = scratch[src, j]
            scratch[0, d + j] = scratch[src, j]
        if meta[N_MULTI_PASS] == 0:
            src = run_network(pack, meta, 1, scratch)
            for a in range(n_types):
                out[a] = scratch[src, a]
        else:  # pass a: only type a's parameters
            for a in range(n_types):
                for j in range(n_params):
                    owned = meta[offsets + a] <= j < meta[offsets + a + 1]
                    scratch[0, d + j] = out[n_types + j] if owned else 0.0
                src = run_network(pack, meta, 1, scratch)
                out[a] = scratch[src, a]
        return decide(pack, meta, out, params)

    return act_network_kernel, act_pdqn_kernel


_NETWORK_KERNELS: Any = False  # compiled on first use


def _network_kernels() -> tuple[Any, Any] | None:
    global _NETWORK_KERNELS
    if _NETWORK_KERNELS is False:
        _NETWORK_KERNELS = _compile_network_kernels()
    return _NETWORK_KERNELS  # type: ignore[no-any-return]


def network_kernel() -> Any:
    """The compiled kernel of a ``networks`` head (compiled on the first call), or None without numba. Call it as
    ``network_kernel()(x, pack, meta, scratch, out, params) -> (k, dim)`` with the arguments of
    :func:`network_kernel_arguments`, ``scratch`` ``(3, width)`` and ``out`` ``(A,)`` float64 buffers: the chosen
    0-based type ``k`` (-1 for an observation with NaN or inf) and its parameters in ``params[:dim]``."""
    kernels = _network_kernels()
    return None if kernels is None else kernels[0]


def pdqn_kernel() -> Any:
    """The compiled kernel of a ``pdqn`` head, or None without numba; called as :func:`network_kernel`'s (with the
    :func:`network_kernel_arguments` of a :class:`~sb3_aac.runtime.forward.PDQNForward`)."""
    kernels = _network_kernels()
    return None if kernels is None else kernels[1]
