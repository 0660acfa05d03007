"""
The optional numba kernel behind :meth:`~sb3_aac.runtime.policy.RuntimePolicy.act`: one greedy decision for one
observation, the formulas of :class:`~sb3_aac.runtime.forward.BankForward` and
:func:`~sb3_aac.runtime.actions.unscale` written as loops and compiled. Without numba the runtime uses numpy alone.
"""

from __future__ import annotations

from typing import Any

import numpy as np


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
