"""
:class:`RuntimePolicy`: greedy decisions (SarsaAAC, HybridPPO's mode, P-DQN / MP-DQN) from an exported ``.aacp`` file,
with numpy alone (and numba, when importable, for one observation at a time).
"""

from __future__ import annotations

import math
import os
import threading
from typing import Any

import numpy as np

from .actions import env_action, unscale, unscale_value
from .format import BANK_ARRAYS, TILE_ARRAYS, check_array_values, read_policy_file
from .forward import BankForward, NetworkForward, PDQNForward, TileForward
from .kernel import act_kernel, kernel_arguments, network_kernel, network_kernel_arguments, pdqn_kernel

BACKENDS = ("auto", "numpy", "numba")  # how act() computes: numba if importable, or numpy only


def unusable_observation(x: np.ndarray) -> ValueError:
    """The error for an observation whose sum of squares is not finite: NaN or inf values, or finite values too large
    to compute with (their squares overflow float64, beyond about 1.3e154)."""
    if not np.isfinite(x).all():
        return ValueError(f"The observation holds NaN or inf values: {x}")
    return ValueError(
        f"The observation holds values too large to compute with (largest magnitude {np.abs(x).max():.3g}; their squares "
        f"overflow float64): {x}"
    )


class RuntimePolicy:
    """
    A policy read from an exported file: greedy decisions with numpy only.

    ``act`` follows the paper's decision procedure (Uc-Cetina 2013, Sec. 4.3): the K action-type values, their
    maximum, then the parameters of the chosen type only, so one decision costs ``O(n)`` in the number of
    features. A P-DQN / MP-DQN file (``pdqn`` head) computes every type's parameters first, since its Q values read
    them. Use :meth:`load` to build one.

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
        check_array_values(header, arrays, path)
        self.tiles = approx["features"]["type"] == "tiles"
        self.hidden_units = approx["head"].get("hidden_units")
        k = self.n_types
        self._p_slice = slice(k, k + self.n_params)
        # Per type: its parameter bounds as Python floats.
        slices = [self.type_slice(j) for j in range(k)]
        self._bounds_lists = [(self.param_low[s].tolist(), self.param_high[s].tolist()) for s in slices]
        self._kernel_args: tuple[np.ndarray, ...] | None = None
        self._lock = threading.Lock()  # act() reuses the buffers below
        if approx["head"]["type"] in ("networks", "pdqn"):
            self._init_networks(approx, arrays, backend)
            return
        if self.tiles:
            if backend == "numba":
                raise ValueError("backend='numba' computes dense features only; tile-coding policies run with numpy ('auto')")
            self._bank: BankForward | TileForward | NetworkForward | PDQNForward = TileForward(
                **{name: arrays[name] for name in TILE_ARRAYS}
            )
            self.rbf = self.mlp = False
            self.backend = "numpy"
            return
        window = approx["features"].get("rbf_window")
        self._bank = bank = BankForward(**{name: arrays[name] for name in BANK_ARRAYS if name in arrays}, rbf_window=window)
        self.rbf, self.mlp = bank.rbf, bank.mlp
        self._feature_buffer = np.empty(bank.feature_a.shape)  # (D,) or (D, m), reused by act()
        if backend != "numpy":
            kernel = act_kernel()
            if kernel is None and backend == "numba":
                raise ValueError("backend='numba' needs numba (pip install numba); use backend='numpy' or 'auto'")
            if kernel is not None:
                pack, meta = kernel_arguments(bank, self.param_low, self.param_high, self.offsets)
                self._kernel = kernel
                active = np.empty(self._feature_buffer.size, dtype=np.int64)
                self._params_buffer = np.empty(max(self.dims))  # the chosen type's parameters, written by the kernel
                self._kernel_args = (pack, meta, self._feature_buffer.reshape(-1), active, self._params_buffer)
        self.backend = "numpy" if self._kernel_args is None else "numba"

    def _init_networks(self, approx: dict[str, Any], arrays: dict[str, np.ndarray], backend: str) -> None:
        """Set up a ``networks`` or ``pdqn`` head: :class:`NetworkForward` or :class:`PDQNForward`, and the numba kernel
        unless ``backend="numpy"``."""
        head = approx["head"]
        net: NetworkForward | PDQNForward
        if head["type"] == "pdqn":
            net = PDQNForward(arrays["obs_mid"], arrays["obs_half"], head, arrays, self.offsets)
        else:
            net = NetworkForward(arrays["obs_mid"], arrays["obs_half"], head["networks"], arrays, approx["n_outputs"])
        self._bank = net
        self.rbf = self.mlp = False
        if backend != "numpy":
            kernel = pdqn_kernel() if head["type"] == "pdqn" else network_kernel()
            if kernel is None and backend == "numba":
                raise ValueError("backend='numba' needs numba (pip install numba); use backend='numpy' or 'auto'")
            if kernel is not None:
                pack, meta, width = network_kernel_arguments(net, self.param_low, self.param_high, self.offsets)
                self._kernel = kernel
                self._params_buffer = np.empty(max(self.dims))
                self._kernel_args = (pack, meta, np.empty((3, width)), np.empty(approx["n_outputs"]), self._params_buffer)
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
            raise unusable_observation(x)
        return x

    def act(self, obs: Any) -> tuple[int, np.ndarray]:
        """
        The greedy decision for one observation.

        Thread-safe: the decision reuses internal buffers, so calls from several threads take turns (a lock); for
        decisions in parallel give each thread its own ``RuntimePolicy``.

        :param obs: one observation, of the trained shape or flat
        :return: the action type as the env numbers it (``type_start + k``) and that type's parameters in the
            env's units, clipped to its bounds: a flat array of ``dims[k]`` values in its Box's dtype
        :raises ValueError: for a wrong observation size or non-finite values
        """
        with self._lock:
            return self._act(obs)

    def _act(self, obs: Any) -> tuple[int, np.ndarray]:
        """:meth:`act` without the lock."""
        if self._kernel_args is not None:
            x = np.asarray(obs, dtype=np.float64)
            if x.shape != self.obs_shape and x.shape != (self.obs_size,):
                self._observation(x)  # raises the shape error
            k, dim = self._kernel(x.reshape(-1), *self._kernel_args)
            if k < 0:
                raise unusable_observation(x)
            return self.type_start + k, self._params_buffer[:dim].astype(self.param_dtypes[k])
        if isinstance(self._bank, (TileForward, NetworkForward, PDQNForward)):
            out = self._bank.outputs(self._bank.features(self._observation(obs)[None]))[0][0].tolist()
        else:
            phi = self._bank.features(self._observation(obs), out=self._feature_buffer)
            # Every output at once: with numpy, one matrix-vector product costs less than separate calls for Q and
            # for the chosen type's parameters (a C++ runtime would compute only those, see docs/export-format.md).
            out = self._bank.outputs(phi)[0].tolist()
        q = out[: self.n_types]
        k = q.index(max(q))  # the first maximum, like numpy's argmax
        start = self.n_types + self.offsets[k]
        scaled = out[start : start + self.dims[k]]
        values = list(map(unscale_value, scaled, *self._bounds_lists[k]))
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
        if len(x) == 0:
            raise ValueError(f"Got an empty batch of shape {x.shape}: a decision needs at least one observation")
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
        """The critic's state values ``V(s)`` for a batch ``(n,)`` (P-DQN / MP-DQN: ``max_k Q_k``, the greedy value)."""
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
