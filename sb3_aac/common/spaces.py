"""
Parameterized action spaces: pick one of K action types, then a real-valued parameter vector for it.

Gymnasium has no dedicated space for this, so environments declare it in one of four ways. All of them are
accepted and parsed once into a :class:`ParameterizedActionSpec`:

============  ==========================================================  ========================================
layout        action space                                                env action (one environment)
============  ==========================================================  ========================================
``"nested"``  ``Tuple(Discrete(K), Tuple(Box_1, ..., Box_K))`` (canonical)  ``(k, (p_1, ..., p_K))``
``"flat"``    ``Tuple(Discrete(K), Box_1, ..., Box_K)``                   ``(k, p_1, ..., p_K)``
``"shared"``  ``Tuple(Discrete(K), Box(P))``                              ``(k, p)``
``"oneof"``   ``OneOf((Box_1, ..., Box_K))``                              ``(k, p_k)``
============  ==========================================================  ========================================

``k`` is a Python ``int`` (offset by ``Discrete.start``); each ``p`` is an ndarray with its Box's shape and dtype.
In the nested and flat layouts the env receives *every* type's parameters and reads those of type ``k``.

Inside an algorithm every layout looks the same: type ``k`` (0-based, ``0 <= k < K``) owns ``dims[k]`` scalar
parameters, and all parameters are concatenated into one vector of length ``n_params = sum(dims)``, type after type,
each Box flattened in C order and scaled affinely from ``[low, high]`` to ``[-1, 1]``. In the ``"shared"`` layout
each type owns its *own copy* of the shared Box's ``P`` parameters (so ``n_params = K * P``): what type ``k`` should
send is generally different from what type ``j`` should send, even when the env reads them from the same Box.

A ``Tuple(Discrete(1), Box)`` is read as ``"shared"``; with one type it behaves exactly like ``"flat"``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from gymnasium import spaces

from sb3_aac.runtime.actions import env_action, unscale

_SUPPORTED = (
    "Tuple(Discrete(K), Tuple(Box_1, ..., Box_K)) (nested), Tuple(Discrete(K), Box_1, ..., Box_K) (flat), "
    "Tuple(Discrete(K), Box(P)) (shared) or OneOf((Box_1, ..., Box_K)), every Box with finite bounds and a "
    "floating-point dtype"
)


def _unsupported(space: spaces.Space[Any], why: str) -> ValueError:
    return ValueError(f"Unsupported parameterized action space {space}: {why}. Supported: {_SUPPORTED}.")


def _check_box(space: spaces.Space[Any], box: Any, what: str) -> spaces.Box:
    if not isinstance(box, spaces.Box):
        raise _unsupported(space, f"{what} is {box}, not a Box")
    if not np.issubdtype(box.dtype, np.floating):
        raise _unsupported(space, f"{what} {box} has dtype {box.dtype}")
    if not (np.all(np.isfinite(box.low)) and np.all(np.isfinite(box.high))):
        raise _unsupported(space, f"{what} {box} has infinite bounds (parameters are scaled to [-1, 1] internally)")
    return box


@dataclass(frozen=True, eq=False)
class ParameterizedActionSpec:
    """
    Structure of a parameterized action space, parsed once by :meth:`from_space`.

    Batched conversions between the algorithm's view ``(k, p_scaled)`` and env actions:
    ``k`` has shape ``(n,)`` with 0-based type indices, ``p_scaled`` has shape ``(n, n_params)`` in ``[-1, 1]``.

    :param space: The action space this spec was parsed from
    :param layout: One of ``"nested"``, ``"flat"``, ``"shared"``, ``"oneof"`` (see the module docstring)
    :param n_types: Number of action types K
    :param start: ``Discrete.start`` of the type space (0 for ``OneOf``); env type = ``start + k``
    :param boxes: The Box each type's parameters come from, one per type (the same Box K times for ``"shared"``)
    :param dims: Number of scalar parameters of each type (``boxes[k]`` flattened)
    :param offsets: Start of each type's parameters in the concatenated vector; ``offsets[K] == n_params``
    :param low: ``(n_params,)`` lower bounds, float64
    :param high: ``(n_params,)`` upper bounds, float64
    :param param_type: ``(n_params,)`` int array: the type that owns each scalar parameter
    """

    space: spaces.Space[Any]
    layout: str
    n_types: int
    start: int
    boxes: tuple[spaces.Box, ...]
    dims: tuple[int, ...]
    offsets: tuple[int, ...]
    low: np.ndarray
    high: np.ndarray
    param_type: np.ndarray

    @classmethod
    def from_space(cls, space: spaces.Space[Any]) -> ParameterizedActionSpec:
        """
        Parse and validate a parameterized action space.

        :param space: The action space
        :return: Its spec
        :raises ValueError: naming the space and what is supported, if it is not one of the four layouts,
            a Box has infinite bounds or a non-floating dtype, or the number of Boxes does not match K.
        """
        start = 0
        if isinstance(space, spaces.OneOf):
            layout = "oneof"
            boxes = tuple(_check_box(space, box, f"option {i}") for i, box in enumerate(space.spaces))
        elif isinstance(space, spaces.Tuple):
            if len(space.spaces) < 2 or not isinstance(space.spaces[0], spaces.Discrete):
                raise _unsupported(space, "a Tuple must start with a Discrete space of action types followed by parameters")
            discrete = space.spaces[0]
            n_types, start = int(discrete.n), int(discrete.start)
            rest = space.spaces[1:]
            if len(rest) == 1 and isinstance(rest[0], spaces.Tuple):
                layout = "nested"
                boxes = tuple(_check_box(space, box, f"parameter space {i}") for i, box in enumerate(rest[0].spaces))
            elif len(rest) == 1:
                layout = "shared"
                boxes = (_check_box(space, rest[0], "the shared parameter space"),) * n_types
            else:
                layout = "flat"
                boxes = tuple(_check_box(space, box, f"parameter space {i}") for i, box in enumerate(rest))
            if len(boxes) != n_types:
                raise _unsupported(space, f"Discrete({n_types}) declares {n_types} action types but {len(boxes)} Boxes follow")
        else:
            raise _unsupported(space, f"{type(space).__name__} is not a parameterized action space")
        if len(boxes) == 0:
            raise _unsupported(space, "there are no action types")

        dims = tuple(int(np.prod(box.shape)) for box in boxes)
        offsets = tuple(int(x) for x in np.concatenate([[0], np.cumsum(dims)]))
        low = np.concatenate([box.low.astype(np.float64).ravel() for box in boxes])
        high = np.concatenate([box.high.astype(np.float64).ravel() for box in boxes])
        param_type = np.repeat(np.arange(len(boxes)), dims)
        return cls(space, layout, len(boxes), start, boxes, dims, offsets, low, high, param_type)

    # Derived quantities, cached so the dataclass fields hold only what was parsed.
    @property
    def n_params(self) -> int:
        """Total number of scalar parameters over all types."""
        return self.offsets[-1]

    @cached_property
    def _mid(self) -> np.ndarray:
        mid: np.ndarray = (self.high + self.low) / 2
        return mid

    @cached_property
    def _half(self) -> np.ndarray:
        half: np.ndarray = (self.high - self.low) / 2
        return half

    @cached_property
    def _dtype(self) -> np.dtype | None:
        """The parameters' dtype if every Box has the same one (then one cast serves all types)."""
        dtypes = {box.dtype for box in self.boxes}
        return dtypes.pop() if len(dtypes) == 1 else None

    @cached_property
    def _box_views(self) -> tuple[tuple[slice, tuple[int, ...] | None], ...]:
        """Per type: its slice of the parameter vector, and the Box shape to reshape to (None if already 1-D)."""
        return tuple((self.type_slice(k), None if len(box.shape) == 1 else box.shape) for k, box in enumerate(self.boxes))

    def type_slice(self, k: int) -> slice:
        """Slice of type ``k``'s parameters (0-based ``k``) in the concatenated vector."""
        return slice(self.offsets[k], self.offsets[k + 1])

    def scale(self, params: np.ndarray) -> np.ndarray:
        """Map parameters from ``[low, high]`` to ``[-1, 1]``. ``params``: ``(..., n_params)``; degenerate bounds give 0."""
        half = self._half
        centred = np.asarray(params, dtype=np.float64) - self._mid
        scaled: np.ndarray = np.divide(centred, half, out=np.zeros(centred.shape), where=half > 0)
        return scaled

    def unscale(self, params_scaled: np.ndarray) -> np.ndarray:
        """
        Map parameters from ``[-1, 1]`` to ``[low, high]`` and clip them inside the bounds. Shape ``(..., n_params)``.

        The formula is :func:`sb3_aac.runtime.actions.unscale`, which the exported policy's runtime uses as well.
        """
        return unscale(self.low, self.high, params_scaled)

    def _env_params(self, params_scaled: np.ndarray) -> np.ndarray:
        params = self.unscale(params_scaled)
        return params if self._dtype is None else params.astype(self._dtype)

    def to_env(self, k: np.ndarray, params_scaled: np.ndarray) -> np.ndarray:
        """
        Build env actions from a batch.

        :param k: ``(n,)`` 0-based action types
        :param params_scaled: ``(n, n_params)`` parameters in ``[-1, 1]`` (values outside are clipped to the bounds)
        :return: object ndarray of shape ``(n,)`` whose items are env actions (Python tuples, see module docstring)
        """
        k = np.asarray(k)
        params_scaled = np.asarray(params_scaled)
        if k.ndim != 1 or params_scaled.shape != (len(k), self.n_params):
            raise ValueError(
                f"Expected k of shape (n,) and params of shape (n, {self.n_params}), got {k.shape} and {params_scaled.shape}"
            )
        params = self._env_params(params_scaled)
        out = np.empty(len(k), dtype=object)  # never np.array(list_of_tuples): numpy would try to stack them
        for i in range(len(k)):
            out[i] = self._action(int(k[i]), params[i])
        return out

    def to_env_predicted(self, k: np.ndarray, params_scaled: np.ndarray, vectorized: bool) -> Any:
        """``predict``'s answer: :meth:`to_env` for a batch (``vectorized``), else the first row as one env action."""
        if vectorized:
            return self.to_env(k, params_scaled)
        return self.to_env_single(int(k[0]), params_scaled[0])

    def to_env_single(self, k: int, params_scaled: np.ndarray) -> tuple[Any, ...]:
        """Like :meth:`to_env` for one action: ``k`` an int, ``params_scaled`` of shape ``(n_params,)``."""
        return self._action(int(k), self._env_params(np.asarray(params_scaled)))

    def _action(self, k: int, params: np.ndarray) -> tuple[Any, ...]:
        # params: (n_params,) unscaled, clipped (and cast if all Boxes share a dtype); a fresh array per call
        if not 0 <= k < self.n_types:
            raise ValueError(f"Action type {k} out of range [0, {self.n_types})")
        return env_action(self.layout, self.start, k, self.n_types, self._box_value, params)

    def _box_value(self, k: int, params: np.ndarray) -> np.ndarray:
        part, shape = self._box_views[k]
        value = params[part]
        if self._dtype is None:
            value = value.astype(self.boxes[k].dtype)
        return value if shape is None else value.reshape(shape)

    def from_env(self, actions: Any) -> tuple[np.ndarray, np.ndarray]:
        """
        Inverse of :meth:`to_env`.

        :param actions: a sequence (list or object ndarray) of env actions
        :return: ``k`` of shape ``(n,)`` (0-based) and ``params_scaled`` of shape ``(n, n_params)``. In the
            ``"shared"`` and ``"oneof"`` layouts an env action carries only the chosen type's parameters; the other
            types' entries are set to 0 (the middle of their range).
        """
        n = len(actions)
        k = np.empty(n, dtype=np.int64)
        params = np.tile(self._mid, (n, 1))
        for i, action in enumerate(actions):
            if not isinstance(action, tuple) or not self.space.contains(action):
                raise ValueError(f"{action!r} is not an element of {self.space}")
            k[i] = int(action[0]) - (0 if self.layout == "oneof" else self.start)
            if self.layout in ("oneof", "shared"):
                params[i, self.type_slice(k[i])] = np.ravel(action[1])
            else:
                values = action[1] if self.layout == "nested" else action[1:]
                params[i] = np.concatenate([np.ravel(v) for v in values])
        return k, self.scale(params)
