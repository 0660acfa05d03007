"""
The approximators' forward pass, numpy only: :class:`BankForward` (scaled-input or RBF features, linear or one-tanh
-layer heads), :class:`TileForward` (tile coding), :class:`NetworkForward` (a ``networks`` head) and
:class:`PDQNForward` (a ``pdqn`` head). Training subclasses the first three
(:class:`sb3_aac.sarsa_aac.approximators.BankKernel`, :class:`sb3_aac.sarsa_aac.tile_coding.TileKernel`,
:class:`sb3_aac.sarsa_aac.deep.DeepKernel`), and
``model.predict`` and :class:`~sb3_aac.runtime.policy.RuntimePolicy` call them, so an exported policy decides
with the very code training ran.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

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
    implementation of these formulas (see :mod:`sb3_aac.sarsa_aac.approximators` for the model). Training subclasses
    it (:class:`~sb3_aac.sarsa_aac.approximators.BankKernel`), ``model.predict`` and :class:`RuntimePolicy` call it.

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
    it). Where every input's centres are evenly spaced with equal widths (:func:`~sb3_aac.sarsa_aac.approximators.rbf_layout`),
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
    of these formulas (training subclasses it, :class:`sb3_aac.sarsa_aac.tile_coding.TileKernel`).

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


LAYER_TYPES = ("linear", "layernorm", "activation")
ACTIVATIONS = ("tanh", "relu", "leaky_relu")


def network_array_shapes(networks: list[dict[str, Any]]) -> dict[str, tuple[int, ...]]:
    """
    The arrays a ``networks`` head holds (see :class:`NetworkForward`), by name, with their shapes: for layer ``j``
    of network ``i``, ``net{i}_{j}_weight`` and ``net{i}_{j}_bias``: ``(out, in)`` and ``(out,)`` for a linear
    layer, ``(size,)`` each for an affine layer norm; none for a plain layer norm or an activation.
    """
    shapes: dict[str, tuple[int, ...]] = {}
    for i, network in enumerate(networks):
        for j, layer in enumerate(network["layers"]):
            if layer["type"] == "linear":
                shapes[f"net{i}_{j}_weight"], shapes[f"net{i}_{j}_bias"] = (layer["out"], layer["in"]), (layer["out"],)
            elif layer["type"] == "layernorm" and layer["affine"]:
                shapes[f"net{i}_{j}_weight"] = shapes[f"net{i}_{j}_bias"] = (layer["size"],)
    return shapes


def check_networks(networks: Any, n_inputs: int, n_outputs: int) -> None:
    """
    A ``ValueError`` unless ``networks`` (a header's ``head.networks``) describes feed-forward networks that read
    ``n_inputs`` values and whose ``columns`` cover the ``n_outputs`` outputs exactly once; a ``KeyError`` or
    ``TypeError`` for a missing or mistyped field.
    """
    if not isinstance(networks, list) or not networks:
        raise ValueError(f"networks must be a non-empty list, got {networks!r}")
    covered = np.zeros(n_outputs, dtype=np.int64)
    for i, network in enumerate(networks):
        start, stop = _check_network(network, i, n_inputs, n_outputs)
        covered[start:stop] += 1
    if not (covered == 1).all():
        raise ValueError(
            f"the networks' columns must cover each of the {n_outputs} outputs exactly once, got {covered.tolist()}"
        )


def check_pdqn_head(head: Any, n_inputs: int, n_types: int, n_params: int) -> None:
    """
    A ``ValueError`` unless ``head`` (a header's ``approximators.head`` of type ``pdqn``) holds ``multi_pass`` (true or
    false) and two ``networks``: the parameter actor, reading the ``n_inputs`` scaled inputs and writing the
    ``n_params`` parameter columns ``[K, K + P]``, then the Q network, reading ``n_inputs + n_params`` values (the
    scaled inputs, then the actor's parameters) and writing the Q columns ``[0, K]``; a ``KeyError`` or ``TypeError``
    for a missing or mistyped field.
    """
    if type(head["multi_pass"]) is not bool:
        raise ValueError(f"a pdqn head's multi_pass must be true or false, got {head['multi_pass']!r}")
    networks = head["networks"]
    if not isinstance(networks, list) or len(networks) != 2:
        raise ValueError(f"a pdqn head holds two networks (the parameter actor, then the Q network), got {networks!r}")
    k, n_outputs = n_types, n_types + n_params + 1
    for i, (n_in, columns) in enumerate(((n_inputs, [k, k + n_params]), (n_inputs + n_params, [0, k]))):
        if _check_network(networks[i], i, n_in, n_outputs) != tuple(columns):
            raise ValueError(f"network {i} of a pdqn head writes the columns {columns}, got {networks[i]['columns']!r}")


def _check_network(network: dict[str, Any], i: int, n_inputs: int, n_outputs: int) -> tuple[int, int]:
    """Check network ``i`` reading ``n_inputs`` values; return its columns ``(start, stop)``."""
    start, stop = network["columns"]
    if not (type(start) is int and type(stop) is int and 0 <= start < stop <= n_outputs):
        raise ValueError(f"network {i}: columns {network['columns']!r} must be [start, stop) within [0, {n_outputs}]")
    size = n_inputs
    layers = network["layers"]
    if not isinstance(layers, list):
        raise ValueError(f"network {i}: layers must be a list, got {layers!r}")
    for j, layer in enumerate(layers):
        size = _check_layer(layer, size, f"network {i}, layer {j}")
    if size != stop - start:
        raise ValueError(f"network {i} ends with {size} values for its {stop - start} columns {network['columns']}")
    return start, stop


def _check_layer(layer: dict[str, Any], size: int, where: str) -> int:
    """Check one layer reading ``size`` values; return how many it writes."""
    kind = layer["type"]
    if kind == "linear":
        if not (type(layer["in"]) is int and type(layer["out"]) is int and layer["in"] == size and layer["out"] >= 1):
            raise ValueError(f"{where}: a linear layer on {size} values needs in={size} and out >= 1, got {layer!r}")
        return int(layer["out"])
    if kind == "layernorm":
        eps = layer["eps"]
        if layer["size"] != size or type(layer["affine"]) is not bool or not (isinstance(eps, float) and 0 < eps < math.inf):
            raise ValueError(
                f"{where}: a layer norm on {size} values needs size={size}, eps > 0 and affine true/false, got {layer!r}"
            )
        return size
    if kind == "activation":
        function = layer["function"]
        if function not in ACTIVATIONS:
            raise ValueError(f"{where}: unknown activation {function!r} (known: {list(ACTIVATIONS)})")
        if function == "leaky_relu" and not (isinstance(layer["slope"], float) and math.isfinite(layer["slope"])):
            raise ValueError(f"{where}: leaky_relu needs a finite slope, got {layer!r}")
        return size
    raise ValueError(f"{where}: unknown layer type {kind!r} (known: {list(LAYER_TYPES)})")


class ScaledNetworks:
    """
    Feed-forward networks over the scaled observation: the layers' formulas (the only implementation of them: the
    deep SarsaAAC policy trains on them, ``model.predict`` and :class:`~sb3_aac.runtime.policy.RuntimePolicy` call
    them). :class:`NetworkForward` and :class:`PDQNForward` say what the networks read and which outputs they write.

    The input is ``x = (s - obs_mid) / obs_half`` (``D`` values, computed as ``s * a - b``). Network ``i`` applies its
    layers in order to the values it is given. Layers:

    - ``linear``: ``y = W @ h + b`` with ``W = net{i}_{j}_weight`` ``(out, in)``, ``b = net{i}_{j}_bias`` ``(out,)``;
    - ``layernorm``: ``y = (h - mean(h)) / sqrt(var(h) + eps)`` over the layer's values (``var`` the mean squared
      deviation, as ``torch.nn.LayerNorm``), then ``* weight + bias`` if ``affine``;
    - ``activation``: ``tanh``, ``relu`` (``max(h, 0)``) or ``leaky_relu`` (``h`` if ``h > 0``, else ``slope * h``).

    :param obs_mid: ``(D,)`` input shift
    :param obs_half: ``(D,)`` input scale (> 0)
    :param networks: the header's ``head.networks`` (checked by the subclass)
    :param arrays: the layer arrays by name (:func:`network_array_shapes`); held as given (views), so in-place
        updates are seen by the next call
    """

    def __init__(
        self, obs_mid: np.ndarray, obs_half: np.ndarray, networks: list[dict[str, Any]], arrays: dict[str, np.ndarray]
    ):
        self.set_input_scaling(obs_mid, obs_half)
        self.networks = networks
        self.columns = [tuple(network["columns"]) for network in networks]
        # Per network, per layer: (type, weight or None, bias or None, eps or slope).
        self.layers: list[list[tuple[str, np.ndarray | None, np.ndarray | None, float]]] = []
        for i, network in enumerate(networks):
            layers = []
            for j, layer in enumerate(network["layers"]):
                weight, bias = arrays.get(f"net{i}_{j}_weight"), arrays.get(f"net{i}_{j}_bias")
                if layer["type"] == "activation":
                    kind = layer["function"]
                    constant = float(layer.get("slope", 0.0)) if kind == "leaky_relu" else 0.0
                else:
                    kind, constant = layer["type"], float(layer.get("eps", 0.0))
                layers.append((kind, weight, bias, constant))
            self.layers.append(layers)

    def set_input_scaling(self, obs_mid: np.ndarray, obs_half: np.ndarray) -> None:
        """Use new input scaling constants (e.g. updated observation statistics) from the next call on."""
        self.feature_a = 1.0 / np.asarray(obs_half, dtype=np.float64)
        self.feature_b = np.asarray(obs_mid, dtype=np.float64) * self.feature_a

    def features(self, obs: np.ndarray) -> np.ndarray:
        """Observations ``(n, D)`` -> scaled inputs ``(n, D)``."""
        x: np.ndarray = obs * self.feature_a - self.feature_b
        return x

    def network(self, i: int, x: np.ndarray, cache: list[tuple[np.ndarray, ...]] | None = None) -> np.ndarray:
        """
        Network ``i`` on its inputs ``(n, in)``: its outputs ``(n, stop - start)``. With ``cache``, one tuple per layer is
        appended to it: the layer's input, and for a layer norm also ``(h - mean) / sqrt(var + eps)`` (before any
        affine map) and ``1 / sqrt(var + eps)`` ``(n, 1)``: what a backward pass needs.
        """
        h = x
        for kind, weight, bias, constant in self.layers[i]:
            h_in = h
            if kind == "linear":
                h = h @ weight.T + bias  # type: ignore[union-attr]
            elif kind == "layernorm":
                # sum / size: ndarray.mean's Python-level overhead is most of the cost at these sizes.
                centred = h - h.sum(-1, keepdims=True) / h.shape[-1]
                inv_std = 1.0 / np.sqrt((centred * centred).sum(-1, keepdims=True) / h.shape[-1] + constant)
                h = centred * inv_std
                if cache is not None:
                    cache.append((h_in, h, inv_std))
                if weight is not None:
                    h = h * weight + bias
                continue
            elif kind == "tanh":
                h = np.tanh(h)
            elif kind == "relu":
                h = np.maximum(h, 0.0)
            else:  # leaky_relu
                h = np.where(h > 0.0, h, constant * h)
            if cache is not None:
                cache.append((h_in,))
        return h


class NetworkForward(ScaledNetworks):
    """
    The forward pass of a ``networks`` head: networks over the scaled observation (:class:`ScaledNetworks`), network
    ``i`` writing its last values to the outputs ``columns[0] .. columns[1] - 1``; together they write each of the
    ``A`` outputs once.

    :param n_outputs: ``A``; the other arguments are :class:`ScaledNetworks`', ``networks`` checked with
        :func:`check_networks`
    """

    def __init__(
        self,
        obs_mid: np.ndarray,
        obs_half: np.ndarray,
        networks: list[dict[str, Any]],
        arrays: dict[str, np.ndarray],
        n_outputs: int,
    ):
        check_networks(networks, len(obs_mid), n_outputs)
        self.n_outputs = n_outputs
        super().__init__(obs_mid, obs_half, networks, arrays)

    def outputs(self, x: np.ndarray) -> tuple[np.ndarray, None]:
        """Scaled inputs ``(n, D)`` -> every output ``(n, A)`` (and None, as :meth:`BankForward.outputs` for a linear head)."""
        out = np.empty((len(x), self.n_outputs))
        for i, (start, stop) in enumerate(self.columns):
            out[:, start:stop] = self.network(i, x)
        return out, None


class PDQNForward(ScaledNetworks):
    """
    The forward pass of a ``pdqn`` head: P-DQN's and MP-DQN's greedy decision (Xiong et al. 2018, Bester et al. 2019).

    Network 0, the parameter actor, maps the scaled inputs ``x`` to every type's scaled parameters ``p = x(s)``
    (``P`` values, not clipped). Network 1, the Q network, reads ``[x, p]`` (``D + P`` values) and writes the ``K``
    values ``Q_k``: in one pass (P-DQN), or (``multi_pass``, MP-DQN) in ``K`` passes, pass ``k`` reading ``p`` with
    every parameter not of type ``k`` set to 0 and giving ``Q_k`` alone. The outputs are ``Q`` (``K``), ``p``
    (``P``) and ``V = max_k Q_k``, the greedy value.

    :param head: the header's ``approximators.head`` (checked with :func:`check_pdqn_head`)
    :param offsets: the ``K + 1`` parameter offsets (type ``k`` owns parameters ``offsets[k] .. offsets[k + 1] - 1``)
    """

    def __init__(
        self,
        obs_mid: np.ndarray,
        obs_half: np.ndarray,
        head: dict[str, Any],
        arrays: dict[str, np.ndarray],
        offsets: Sequence[int],
    ):
        k, n_params = len(offsets) - 1, offsets[-1]
        check_pdqn_head(head, len(obs_mid), k, n_params)
        super().__init__(obs_mid, obs_half, head["networks"], arrays)
        self.n_types, self.n_params, self.multi_pass = k, n_params, head["multi_pass"]
        owner = np.zeros((k, n_params))
        for j in range(k):
            owner[j, offsets[j] : offsets[j + 1]] = 1.0
        self.owner = owner  # owner[k, j] = 1 if parameter j belongs to type k

    def outputs(self, x: np.ndarray) -> tuple[np.ndarray, None]:
        """Scaled inputs ``(n, D)`` -> ``Q``, ``p`` and ``V``, ``(n, K + P + 1)`` (and None, as :class:`NetworkForward`)."""
        n, k = len(x), self.n_types
        params = self.network(0, x)
        if self.multi_pass:  # pass j: rows j * n .. (j + 1) * n - 1
            masked = (params[None] * self.owner[:, None]).reshape(k * n, self.n_params)
            q_all = self.network(1, np.concatenate((np.tile(x, (k, 1)), masked), axis=1)).reshape(k, n, k)
            q = q_all.diagonal(axis1=0, axis2=2)  # (n, K): Q_j from pass j
        else:
            q = self.network(1, np.concatenate((x, params), axis=1))
        return np.concatenate((q, params, q.max(1, keepdims=True)), axis=1), None
