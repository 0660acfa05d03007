"""
What a dashboard compares across algorithms: the share of each action type, the mean and standard deviation of each
type's executed parameters (in the env's units), and statistics of the critic's values, accumulated between log
dumps by :class:`ActionStats`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from sb3_aac.common.spaces import ParameterizedActionSpec

VALUE_NAMES = ("value", "q")  # V(s) and Q(s, k, x_k): see ActionStats


class ActionStats:
    """
    Sums over the executed actions since the last :meth:`record`:

    - ``rollout/type_freq_{k}``: the share of steps that chose type ``k``;
    - ``rollout/param_mean_{k}_{i}`` and ``rollout/param_std_{k}_{i}``: mean and standard deviation of parameter ``i``
      of type ``k`` (its ``i``-th scalar, flattened) over the steps that chose type ``k``, in the env's units (the
      scaled ``[-1, 1]`` values mapped affinely onto the parameter's bounds); nothing for a type no step chose;
    - ``train/{value_name}_mean``, ``_std``, ``_min``, ``_max``: of the critic values given to :meth:`add` or
      :meth:`add_values`.

    The value name says which critic output the statistics are of, so that one key means one quantity in every
    algorithm: ``"value"`` for the state value ``V(s)`` at the steps acted from (SarsaAAC's and HybridPPO's critics),
    ``"q"`` for the action value ``Q(s, k, x_k)`` of a training batch's actions (P-DQN, which has no ``V``).

    :param spec: the parsed parameterized action space
    :param value_name: ``"value"`` or ``"q"``, as above
    """

    def __init__(self, spec: ParameterizedActionSpec, value_name: str) -> None:
        if value_name not in VALUE_NAMES:
            raise ValueError(f"value_name must be one of {VALUE_NAMES}, got {value_name!r}")
        self.spec, self.value_name = spec, value_name
        self._owned = spec.param_type[None, :] == np.arange(spec.n_types)[:, None]  # (K, P) type k owns param j
        self._half = (spec.high - spec.low) / 2
        self.reset()

    def reset(self) -> None:
        """Forget everything added since the last :meth:`record`."""
        k, p = self.spec.n_types, self.spec.n_params
        self._counts = np.zeros(k, dtype=np.int64)
        self._param_sums = np.zeros(p)
        self._param_squares = np.zeros(p)
        self._values = np.zeros(2)  # sum, sum of squares
        self._n_values = 0
        self._value_range = [math.inf, -math.inf]

    def add(self, types: np.ndarray, scaled_params: np.ndarray, values: np.ndarray | None = None) -> None:
        """
        Add ``n`` executed actions: ``types`` ``(n,)`` 0-based, ``scaled_params`` ``(n, n_params)`` in ``[-1, 1]``
        (only the chosen type's parameters count), and optionally the critic's values ``(n,)`` at those steps.
        """
        types = np.asarray(types, dtype=np.int64)
        self._counts += np.bincount(types, minlength=self.spec.n_types)
        mask = self._owned[types]  # (n, P): the parameters of each row's chosen type
        chosen = np.where(mask, scaled_params, 0.0)
        self._param_sums += chosen.sum(0)
        self._param_squares += (chosen * chosen).sum(0)
        if values is not None:
            self.add_values(values)

    def add_values(self, values: np.ndarray) -> None:
        """Add critic values ``(n,)`` (e.g. the Q values of a training batch)."""
        values = np.asarray(values, dtype=np.float64).ravel()
        if len(values):
            self._values += (values.sum(), values @ values)
            self._n_values += len(values)
            low, high = self._value_range
            self._value_range = [min(low, float(values.min())), max(high, float(values.max()))]

    def record(self, logger: Any) -> None:
        """Record the keys above on ``logger`` (an SB3 ``Logger``), then :meth:`reset`."""
        total = int(self._counts.sum())
        if total:
            spec = self.spec
            per_param = np.maximum(self._counts[spec.param_type], 1)  # steps that chose each parameter's type
            means = self._param_sums / per_param
            stds = np.sqrt(np.maximum(self._param_squares / per_param - means * means, 0.0)) * self._half
            means = spec.unscale(means)
            for k, count in enumerate(self._counts):
                logger.record(f"rollout/type_freq_{k}", count / total)
                for i in range(spec.dims[k] if count else 0):
                    logger.record(f"rollout/param_mean_{k}_{i}", float(means[spec.offsets[k] + i]))
                    logger.record(f"rollout/param_std_{k}_{i}", float(stds[spec.offsets[k] + i]))
        if self._n_values:
            mean = self._values[0] / self._n_values
            name = f"train/{self.value_name}"
            logger.record(f"{name}_mean", mean)
            logger.record(f"{name}_std", math.sqrt(max(self._values[1] / self._n_values - mean * mean, 0.0)))
            logger.record(f"{name}_min", self._value_range[0])
            logger.record(f"{name}_max", self._value_range[1])
        self.reset()
