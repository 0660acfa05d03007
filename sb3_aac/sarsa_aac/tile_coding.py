"""
Tile coding over groups of inputs: sparse binary features that combine inputs, with a linear head per approximator.

Per-input features (the paper's RBF arrays) are additive, ``f(s) = sum_i f_i(s_i)``, so they cannot represent a value
that depends on, say, a heading *relative to* a target direction. Tile coding (Sutton & Barto, *Reinforcement
Learning*, 2nd ed., Sec. 9.5.4) over *groups* of inputs can: each group of ``k`` inputs is covered by ``n_tilings``
grids of ``(tiles_per_input + 1)**k`` tiles, offset from each other asymmetrically (tiling ``t`` shifts input
``j`` of its group by ``t * (2j + 1) / n_tilings`` of a tile, modulo one tile), and each grid activates the one tile
the observation falls in. The default groups are every single input and every pair of inputs, so interactions
between any two inputs are representable without choosing them; users who know their inputs pass their own groups.

Every feature has its own weight (no hashing: the table holds every tile of every grid), and an observation
activates exactly ``C = n_groups * n_tilings`` features, so evaluation and training cost ``O(C)`` per approximator,
whatever the table size. The forward pass is :class:`sb3_aac.runtime.forward.TileForward` (shared with the exported
runtime); :class:`TileKernel` adds the update, the dense banks' normalised step on the sparse features
(:mod:`sb3_aac.sarsa_aac.lane_steps`): a sample's step is ``lr * err / (1 + C)`` on each of its ``C`` active features
and on the bias, the lanes' samples applied one after another, each error recomputed on its predecessors' weights.
For one sample a rate of 1 lands the output on its target; ``n`` lanes take the steps one lane would take on their
samples.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import NamedTuple

import numba
import numpy as np
import torch as th
from torch import nn

from sb3_aac.common.sizes import check_allocation
from sb3_aac.sarsa_aac.approximators import NumpyBank
from sb3_aac.sarsa_aac.lane_steps import tile_steps, traced_tile_steps
from sb3_aac.runtime.forward import TileForward


def default_tile_groups(n_inputs: int) -> list[tuple[int, ...]]:
    """Every single input, then every pair of inputs: ``D + D * (D - 1) / 2`` groups."""
    return [(i,) for i in range(n_inputs)] + list(itertools.combinations(range(n_inputs), 2))


def check_tile_groups(groups: object, n_inputs: int) -> list[tuple[int, ...]]:
    """``groups`` as tuples of input indices, each non-empty, in range and without repeats (else ValueError).

    ``groups`` is user input checked at run time, hence typed ``object``: a sequence of index sequences (a bare
    index stands for a group of one).
    """
    if isinstance(groups, str) or not isinstance(groups, Sequence) or len(groups) == 0:
        raise ValueError(f"tile_groups must be a non-empty list of tuples of input indices, got {groups!r}")
    checked = []
    for entry in groups:
        group = (entry,) if isinstance(entry, (int, np.integer)) else tuple(entry)
        valid = all(isinstance(i, (int, np.integer)) and not isinstance(i, bool) for i in group)
        if not group or not valid or len(set(group)) != len(group) or not all(0 <= i < n_inputs for i in group):
            raise ValueError(f"Each tile group must be a tuple of distinct input indices in [0, {n_inputs}), got {group!r}")
        checked.append(tuple(int(i) for i in group))
    return checked


class TileLayout(NamedTuple):
    """The grids of a tile coding: per coding ``c`` (group x tiling), ``k`` = the largest group size."""

    inputs: np.ndarray  # (C, k) input index per slot (padded slots repeat the group's first input)
    offsets: np.ndarray  # (C, k) offset in tiles
    resolution: np.ndarray  # (C, k) tiles per input (the coordinate runs 0..resolution)
    strides: np.ndarray  # (C, k) index stride per slot (0 for padded slots)
    bases: np.ndarray  # (C,) first feature of the coding's grid
    n_features: int


def tile_layout(groups: Sequence[tuple[int, ...]], tiles_per_input: int, n_tilings: int, n_outputs: int = 1) -> TileLayout:
    """The grids of ``n_tilings`` asymmetrically offset tilings of every group (see the module docstring).

    :raises ValueError: for sizes that are not whole numbers >= 1, or whose weight table (features x ``n_outputs``)
        would pass :data:`~sb3_aac.common.sizes.MAX_ALLOCATION_BYTES` (checked before anything is built)
    """
    # Run-time checks of user input that the annotations cannot guarantee.
    if not (isinstance(tiles_per_input, (int, np.integer)) and tiles_per_input >= 1):  # type: ignore[redundant-expr]
        raise ValueError(f"tiles_per_input must be an int >= 1, got {tiles_per_input!r}")
    if not (isinstance(n_tilings, (int, np.integer)) and n_tilings >= 1):  # type: ignore[redundant-expr]
        raise ValueError(f"n_tilings must be an int >= 1, got {n_tilings!r}")
    k = max(len(g) for g in groups)
    side = tiles_per_input + 1
    n_features = n_tilings * sum(side ** len(group) for group in groups)
    check_allocation(
        f"TilePolicy's weight table (tiles_per_input={tiles_per_input}, n_tilings={n_tilings}: {n_features:,} features x "
        f"{n_outputs} outputs)",
        n_features * n_outputs,
    )
    rows = []
    base = 0
    for group in groups:
        for t in range(n_tilings):
            inputs = [*group, *[group[0]] * (k - len(group))]
            offsets = [(t * (2 * j + 1) / n_tilings) % 1.0 if j < len(group) else 0.0 for j in range(k)]
            strides = [side**j if j < len(group) else 0 for j in range(k)]
            rows.append((inputs, offsets, strides, base))
            base += side ** len(group)
    inputs, offsets, strides, bases = zip(*rows, strict=True)
    return TileLayout(
        np.array(inputs, dtype=np.int64),
        np.array(offsets),
        np.full((len(rows), k), float(tiles_per_input)),
        np.array(strides, dtype=np.int64),
        np.array(bases, dtype=np.int64),
        base,
    )


class TileBank(NumpyBank):
    """
    ``n_outputs`` independent linear approximators on tile-coding features (see the module docstring).

    :param low: ``(D,)`` lower bounds of the observation (finite), where the grids start
    :param high: ``(D,)`` upper bounds (finite), where they end; values outside fall in the edge tiles
    :param n_outputs: Number of approximators ``A``
    :param groups: Groups of input indices, each tiled jointly; None for every input and every pair
    :param tiles_per_input: Tiles across each input's range per tiling
    :param n_tilings: Offset tilings per group
    """

    def __init__(
        self,
        low: np.ndarray,
        high: np.ndarray,
        n_outputs: int,
        groups: Sequence[Sequence[int]] | None = None,
        tiles_per_input: int = 8,
        n_tilings: int = 8,
    ):
        super().__init__()
        low, high = np.asarray(low, dtype=np.float64).ravel(), np.asarray(high, dtype=np.float64).ravel()
        if low.shape != high.shape or not np.all(low < high) or not np.isfinite(low).all() or not np.isfinite(high).all():
            raise ValueError(f"Tile coding needs finite low < high elementwise with equal shapes, got low={low}, high={high}")
        self.n_inputs, self.n_outputs = len(low), n_outputs
        self.groups = default_tile_groups(self.n_inputs) if groups is None else check_tile_groups(groups, self.n_inputs)
        layout = tile_layout(self.groups, tiles_per_input, n_tilings, n_outputs)
        self.tiles_per_input, self.n_tilings, self.n_features = tiles_per_input, n_tilings, layout.n_features
        self.n_active = len(layout.bases)
        self.register_buffer("obs_mid", th.as_tensor((high + low) / 2))
        self.register_buffer("obs_half", th.as_tensor((high - low) / 2))
        for name in ("inputs", "offsets", "resolution", "strides", "bases"):
            self.register_buffer(f"tile_{name}", th.as_tensor(getattr(layout, name)))
        # Tile weights start at 0: random ones would stay as noise in rarely visited tiles (measured: on the toy env
        # the greedy return after 20k steps was 4.2 with random tile weights, 9.5 with zeros). Random biases.
        self.tile_weight = nn.Parameter(th.zeros((layout.n_features, n_outputs), dtype=th.float64), requires_grad=False)
        self.bias = self._uniform((n_outputs,), 1 / math.sqrt(self.n_active))

    def _make_kernel(self) -> TileKernel:
        return TileKernel(self)

    def _forward_pass(self) -> TileForward:
        return TileForward(**self.arrays())

    def _output_weights(self) -> tuple[th.Tensor, th.Tensor, int]:
        return self.tile_weight, self.bias, 1


class TileCache(NamedTuple):
    """What :meth:`TileKernel.forward` computed and :meth:`TileKernel.update` needs. ``n`` rows."""

    x: np.ndarray  # (n, C) active features
    hidden: None


@numba.njit(cache=True, nogil=True)
def _active_features(obs, inputs, tile_a, tile_b, limit, strides, bases):  # type: ignore[no-untyped-def]
    """:meth:`TileForward.features` as loops (the same float operations, so the same tiles)."""
    n, (c_count, k) = len(obs), inputs.shape
    active = np.empty((n, c_count), dtype=np.int64)
    for i in range(n):
        for c in range(c_count):
            index = bases[c]
            for j in range(k):
                position = obs[i, inputs[c, j]] * tile_a[c, j] - tile_b[c, j]
                position = min(max(math.floor(position), 0.0), limit[c, j])
                index += np.int64(position) * strides[c, j]
            active[i, c] = index
    return active


@numba.njit(cache=True, nogil=True)
def _outputs(active, w, b):  # type: ignore[no-untyped-def]
    """:meth:`TileForward.outputs` as loops (summed in the same order as numpy's ``w[active].sum(1) + b``)."""
    n, c_count = active.shape
    a_count = w.shape[1]
    out = np.zeros((n, a_count))
    for i in range(n):
        for c in range(c_count):
            row = active[i, c]
            for a in range(a_count):
                out[i, a] += w[row, a]
        for a in range(a_count):
            out[i, a] += b[a]
    return out


class TileKernel(TileForward):
    """
    The tile forward pass on views of a :class:`TileBank`'s CPU parameters, with the closed-form update.

    Training runs :class:`~sb3_aac.runtime.forward.TileForward`'s formulas compiled with numba (the same float operations
    and summation order, so the same outputs; tested against the numpy forward pass).
    """

    def __init__(self, bank: TileBank):
        if bank.obs_mid.device.type != "cpu":
            raise ValueError(f"The numpy kernel needs CPU tensors, the bank is on {bank.obs_mid.device}")
        super().__init__(**bank.arrays())
        self.n_features = bank.n_features

    def features(self, obs: np.ndarray) -> np.ndarray:
        obs = np.ascontiguousarray(obs, dtype=np.float64)
        active: np.ndarray = _active_features(obs, self.inputs, self.tile_a, self.tile_b, self.limit, self.strides, self.bases)
        return active

    def outputs(self, active: np.ndarray) -> tuple[np.ndarray, None]:
        return _outputs(active, self.w, self.b), None

    def forward(self, obs: np.ndarray) -> tuple[np.ndarray, TileCache]:
        """``obs``: ``(n, D)`` -> outputs ``(n, A)`` and the cache for :meth:`update`."""
        active = self.features(obs)
        return self.outputs(active)[0], TileCache(active, None)

    def update(self, cache: TileCache, err: np.ndarray, lr: np.ndarray, hidden_gain: np.ndarray | None = None) -> None:
        """
        The normalised step on ``0.5 * err**2`` for each sample in turn (module docstring), in place. ``hidden_gain``
        is accepted for the dense banks' interface and unused (there is no hidden layer).
        """
        tile_steps(self.w, self.b, cache.x[: len(err)], np.ascontiguousarray(err, dtype=np.float64), lr)

    def update_traced(self, cache: TileCache, err: np.ndarray, lr: np.ndarray, hit: np.ndarray, traces: TileTraces) -> None:
        """
        :meth:`update` with eligibility traces on ``traces.columns``: per sample in turn, their step (the same
        normalised step, its error recomputed on the weights the earlier samples left) goes to every feature (and
        the bias) in proportion to its trace after folding in this sample's features with ``hit`` ``(n, T)`` (see
        :class:`TileTraces`); the other columns take :meth:`update`'s step. With ``decay == 0`` and replacing traces
        this is :meth:`update` exactly.
        """
        trace_column = np.full(self.w.shape[1], -1, dtype=np.int64)
        trace_column[traces.columns] = np.arange(len(traces.columns))
        traced_tile_steps(
            self.w,
            self.b,
            cache.x[: len(err)],
            np.ascontiguousarray(err, dtype=np.float64),
            lr,
            trace_column,
            hit,
            traces.decay,
            traces.replacing,
            traces.tolerance,
            traces.trace,
            traces.bias_trace,
            traces.listed,
            traces.live,
            traces.n_live,
        )


@numba.njit(cache=True, nogil=True)
def _clear_lanes(lanes, trace, listed, live, n_live):  # type: ignore[no-untyped-def]
    """Zero the traces of ``lanes``."""
    for i in lanes:
        for s in range(n_live[i]):
            f = live[i, s]
            listed[i, f] = False
            trace[i, f, :] = 0.0
        n_live[i] = 0


class TileTraces:
    """
    Eligibility traces (Sutton & Barto, 2nd ed., Sec. 12.2 and 12.7) of some output columns of a :class:`TileBank`,
    one trace per lane, for :meth:`TileKernel.update_traced`.

    At each step, lane ``i``'s traces decay by ``decay`` (``gamma * lambda``), then on the features active in its
    current observation (and on the bias, always active) column ``j``'s trace is set to ``hit[i, j]``
    (replacing traces; ``hit`` is 0 or 1, so a 0 clears another action's trace there, as Singh & Sutton 1996
    recommend) or has ``hit[i, j]`` added (accumulating traces). A feature whose traces all fall below
    ``tolerance`` is dropped (set to 0), so each step costs ``O(features with a trace)``: at most about
    ``C * log(tolerance) / log(decay)``.

    :param n_lanes: Number of lanes (environments)
    :param n_features: The bank's number of tile features
    :param columns: ``(T,)`` output columns that learn with traces
    :param decay: ``gamma * lambda``, in ``[0, 1]``
    :param replacing: Replacing (True) or accumulating (False) traces
    :param tolerance: Traces below this are dropped
    """

    def __init__(
        self, n_lanes: int, n_features: int, columns: np.ndarray, decay: float, replacing: bool, tolerance: float = 1e-3
    ):
        self.columns = np.asarray(columns, dtype=np.int64)
        self.decay, self.replacing, self.tolerance = float(decay), bool(replacing), float(tolerance)
        t_count = len(self.columns)
        self.trace = np.zeros((n_lanes, n_features, t_count))
        self.bias_trace = np.zeros((n_lanes, t_count))
        self.listed = np.zeros((n_lanes, n_features), dtype=np.bool_)
        self.live = np.zeros((n_lanes, n_features), dtype=np.int64)
        self.n_live = np.zeros(n_lanes, dtype=np.int64)

    def clear(self, lanes: np.ndarray) -> None:
        """Zero the traces of ``lanes`` (e.g. where an episode ended)."""
        _clear_lanes(np.asarray(lanes, dtype=np.int64), self.trace, self.listed, self.live, self.n_live)
        self.bias_trace[lanes] = 0.0
