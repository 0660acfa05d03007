"""
Sequential lane steps: the samples of one env step's lanes applied one after another, as if they had come in sequence.

Every approximator bank of SarsaAAC learns by normalised LMS (:mod:`sb3_aac.sarsa_aac.approximators`). For a batch of
``n`` lanes, sample ``i`` (features ``x_i``; approximator ``a``'s target ``y_ia = f_a(s_i) + err_ia``, with ``f_a(s_i)``
the output before the batch) is applied in lane order ``i = 0 .. n-1``: its error is recomputed on the weights lanes
``0 .. i-1`` left, ``e_ia = y_ia - f_a(s_i)``, and it takes the one-sample normalised step with rate ``lr_a``. So:

- one lane takes exactly the plain normalised LMS step (a rate of 1 lands a linear head's output on its target);
- ``n`` lanes take exactly the steps one lane would take on their ``n`` samples in lane order, the targets bootstrapped
  from the weights at the start of the env step (one lane bootstraps each sample from the weights its predecessor
  left): what one sample teaches does not depend on the number of lanes, so the learning curve per env step does not
  either, up to the order and the correlation of the samples;
- every step is a normalised step on one sample: a linear head's error on that sample shrinks by the factor
  ``1 - lr`` (no overshoot for any rate in ``(0, 1]``), whatever ``n``.

``err_ia == 0`` means "no target": approximator ``a`` skips sample ``i`` (SarsaAAC's Q of the types not taken, and the
parameter actor where CACLA does not update). The cost is ``O(n * active features * approximators with a target)``:
sparse tile heads pay only for their active features.
"""

from __future__ import annotations

import numba
import numpy as np

# The most lanes whose errors are measured on the same weights where every weight moves with every sample (DeepPolicy,
# whose steps of a chunk are summed, see sb3_aac.sarsa_aac.deep; the MLP heads): SarsaAAC updates more lanes in
# chunks of this many, one chunk after another, each chunk's targets, CACLA gates and next actions computed on the
# weights the earlier chunks left. Linear heads (tiles, RBFs) take all lanes at once.
LANE_CHUNK = 16


@numba.njit(cache=True, nogil=True)
def linear_steps(w, b, x, err, lr):  # type: ignore[no-untyped-def]
    """
    Linear heads ``f_a = w[a] . x + b[a]``, in place: each sample's step ``lr_a e_ia x_i / (1 + |x_i|^2)`` on the weights
    and ``lr_a e_ia / (1 + |x_i|^2)`` on the bias (module docstring).

    :param w: ``(A, F)`` weights; :param b: ``(A,)`` biases; :param x: ``(n, F)`` features
    :param err: ``(n, A)`` target minus output before the batch (0: no target); :param lr: ``(A,)`` rates
    """
    n, f_count = x.shape
    a_count = w.shape[0]
    targets = np.zeros((n, a_count))
    for i in range(n):
        for a in range(a_count):
            if err[i, a] != 0.0:
                out = b[a]
                for f in range(f_count):
                    out += w[a, f] * x[i, f]
                targets[i, a] = out + err[i, a]
    for i in range(n):
        energy = 1.0
        for f in range(f_count):
            energy += x[i, f] * x[i, f]
        for a in range(a_count):
            if err[i, a] == 0.0:
                continue
            out = b[a]
            for f in range(f_count):
                out += w[a, f] * x[i, f]
            step = lr[a] * (targets[i, a] - out) / energy
            for f in range(f_count):
                w[a, f] += step * x[i, f]
            b[a] += step


@numba.njit(cache=True, nogil=True)
def mlp_steps(w1, b1, w2, b2, x, err, lr, hidden_gain):  # type: ignore[no-untyped-def]
    """
    One-hidden-layer tanh heads ``f_a = w2[a] . tanh(w1[a] @ x + b1[a]) + b2[a]``, in place: each sample's gradient step
    on ``0.5 * e_ia**2``, each layer's divided by ``1 + |input of that layer|^2`` and the hidden layer's also multiplied
    by ``hidden_gain[a]`` (backpropagated through the output weights before they change).

    :param w1: ``(A, H, F)``; :param b1: ``(A, H)``; :param w2: ``(A, H)``; :param b2: ``(A,)``; :param x: ``(n, F)``
    :param err: ``(n, A)`` target minus output before the batch (0: no target); :param lr: ``(A,)`` rates
    :param hidden_gain: ``(A,)`` factor on the hidden layer's step
    """
    n, f_count = x.shape
    a_count, h_count = w2.shape
    hidden = np.empty(h_count)
    targets = np.zeros((n, a_count))
    for i in range(n):
        for a in range(a_count):
            if err[i, a] != 0.0:
                out = b2[a]
                for j in range(h_count):
                    pre = b1[a, j]
                    for f in range(f_count):
                        pre += w1[a, j, f] * x[i, f]
                    out += w2[a, j] * np.tanh(pre)
                targets[i, a] = out + err[i, a]
    for i in range(n):
        x_energy = 1.0
        for f in range(f_count):
            x_energy += x[i, f] * x[i, f]
        for a in range(a_count):
            if err[i, a] == 0.0:
                continue
            out = b2[a]
            h_energy = 1.0
            for j in range(h_count):
                pre = b1[a, j]
                for f in range(f_count):
                    pre += w1[a, j, f] * x[i, f]
                hidden[j] = np.tanh(pre)
                out += w2[a, j] * hidden[j]
                h_energy += hidden[j] * hidden[j]
            g = lr[a] * (targets[i, a] - out)
            for j in range(h_count):
                g_hidden = g * hidden_gain[a] * w2[a, j] * (1.0 - hidden[j] * hidden[j]) / x_energy
                w2[a, j] += g * hidden[j] / h_energy
                for f in range(f_count):
                    w1[a, j, f] += g_hidden * x[i, f]
                b1[a, j] += g_hidden
            b2[a] += g / h_energy


@numba.njit(cache=True, nogil=True)
def _tile_output(w, b, active, i, a):  # type: ignore[no-untyped-def]
    out = b[a]
    for c in range(active.shape[1]):
        out += w[active[i, c], a]
    return out


@numba.njit(cache=True, nogil=True)
def _tile_targets(w, b, active, err):  # type: ignore[no-untyped-def]
    n, a_count = err.shape
    targets = np.zeros((n, a_count))
    for i in range(n):
        for a in range(a_count):
            if err[i, a] != 0.0:
                targets[i, a] = _tile_output(w, b, active, i, a) + err[i, a]
    return targets


@numba.njit(cache=True, nogil=True)
def tile_steps(w, b, active, err, lr):  # type: ignore[no-untyped-def]
    """
    Linear heads on binary tile features, ``f_a = sum_c w[active_c, a] + b[a]``, in place: each sample's step
    ``lr_a e_ia / (1 + C)`` on its ``C`` active features and on the bias (module docstring).

    :param w: ``(n_features, A)`` weights; :param b: ``(A,)`` biases; :param active: ``(n, C)`` active features (distinct
        within a row); :param err: ``(n, A)`` target minus output before the batch (0: no target); :param lr: ``(A,)``
    """
    n, c_count = active.shape
    a_count = w.shape[1]
    targets = _tile_targets(w, b, active, err)
    for i in range(n):
        for a in range(a_count):
            if err[i, a] == 0.0:
                continue
            step = lr[a] * (targets[i, a] - _tile_output(w, b, active, i, a)) / (1.0 + c_count)
            for c in range(c_count):
                w[active[i, c], a] += step
            b[a] += step


@numba.njit(cache=True, nogil=True)
def traced_tile_steps(  # type: ignore[no-untyped-def]
    w, b, active, err, lr, trace_column, hit, decay, replacing, tolerance, trace, bias_trace, listed, live, n_live
):
    """
    :func:`tile_steps` with eligibility traces on some columns, in place. Per lane ``i`` in order: its traces decay by
    ``decay`` (features whose traces all fell below ``tolerance`` are dropped), then on its active features and on the
    bias column ``j``'s trace is set to (``replacing``) or increased by ``hit[i, j]``; then each column ``a`` with a
    target takes the step of :func:`tile_steps` with the error recomputed at ``s_i``, a traced column (``trace_column[a]
    = j >= 0``) on every feature and on the bias in proportion to their traces, the others on the active features and
    the bias.

    :param trace_column: ``(A,)`` each column's trace index, -1 for a column without traces
    :param hit: ``(n, T)``; :param trace: ``(lanes, n_features, T)``; :param bias_trace: ``(lanes, T)``;
        :param listed: ``(lanes, n_features)`` bool; :param live: ``(lanes, n_features)`` the features with a trace,
        the first ``n_live[i]`` of row ``i`` (see :class:`~sb3_aac.sarsa_aac.tile_coding.TileTraces`)
    """
    n, c_count = active.shape
    a_count = w.shape[1]
    t_count = hit.shape[1]
    targets = _tile_targets(w, b, active, err)
    for i in range(n):
        kept = 0
        for s in range(n_live[i]):
            f = live[i, s]
            alive = False
            for j in range(t_count):
                trace[i, f, j] *= decay
                alive |= abs(trace[i, f, j]) >= tolerance
            if alive:
                live[i, kept] = f
                kept += 1
            else:
                listed[i, f] = False
                for j in range(t_count):
                    trace[i, f, j] = 0.0
        for c in range(c_count):
            f = active[i, c]
            if not listed[i, f]:
                listed[i, f] = True
                live[i, kept] = f
                kept += 1
            for j in range(t_count):
                trace[i, f, j] = hit[i, j] if replacing else trace[i, f, j] + hit[i, j]
        n_live[i] = kept
        for j in range(t_count):
            bias_trace[i, j] = hit[i, j] if replacing else bias_trace[i, j] * decay + hit[i, j]
        for a in range(a_count):
            if err[i, a] == 0.0:
                continue
            step = lr[a] * (targets[i, a] - _tile_output(w, b, active, i, a)) / (1.0 + c_count)
            j = trace_column[a]
            if j < 0:
                for c in range(c_count):
                    w[active[i, c], a] += step
                b[a] += step
            else:
                for s in range(kept):
                    f = live[i, s]
                    w[f, a] += step * trace[i, f, j]
                b[a] += step * bias_trace[i, j]
