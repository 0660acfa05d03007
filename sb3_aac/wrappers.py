"""
Wrappers that let stock Stable-Baselines3 algorithms train on parameterized action spaces.

SB3 rejects ``Tuple`` and ``OneOf`` action spaces. These ``gymnasium.ActionWrapper`` s turn any parameterized
action space accepted by :class:`~sb3_aac.common.spaces.ParameterizedActionSpec` (K action types, type ``k`` with
``dims[k]`` real parameters, ``n_params = sum(dims)``) into a space SB3 accepts:

* :class:`FlattenParameterizedAction`: ``Box(-1, 1, (K + n_params,), float32)``, the formulation of PA-DDPG
  (Hausknecht & Stone, 2016). The first K entries are scores, one per action type; the rest are every type's
  parameters scaled to ``[-1, 1]``, type after type. The env runs ``k = argmax(scores)`` (ties go to the lowest
  index) with type ``k``'s parameters, clipped to ``[-1, 1]`` and mapped affinely to the Box bounds (``-1`` gives
  ``low``, ``1`` gives ``high``, exactly). For PPO, A2C, SAC, TD3 and DDPG.
* :class:`DiscretizeParameterizedAction`: ``Discrete(N)`` over action types times a grid of parameter values. Each
  parameter takes ``bins`` evenly spaced values over its bounds, both ends included, so type ``k`` contributes
  ``bins ** dims[k]`` actions (one if it has no parameters). For DQN and PPO.

Both keep the observation space, work inside SB3's ``DummyVecEnv`` and ``SubprocVecEnv`` (pass them to
``make_vec_env`` as ``wrapper_class``) and pass SB3's ``check_env``. In the ``"shared"`` layout each type owns its
own copy of the shared Box's parameters (see :mod:`sb3_aac.common.spaces`), even the coordinates the env ignores for
that type; give those a single bin (the middle of the range) with a per-parameter ``bins`` sequence.

The conversions themselves are batched functions on arrays (:func:`scores_to_action`, :func:`action_to_scores`,
:func:`make_grid`, :func:`grid_to_action`, :func:`action_to_grid`) that a ``VecEnvWrapper`` can share with the
wrappers here. Example::

    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    from sb3_aac import FlattenParameterizedAction
    from sb3_aac.common.envs import ParameterizedTargetEnv

    vec_env = make_vec_env(ParameterizedTargetEnv, n_envs=2, wrapper_class=FlattenParameterizedAction)
    model = PPO("MlpPolicy", vec_env, n_steps=64, batch_size=64, seed=0).learn(256)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from sb3_aac.common.spaces import ParameterizedActionSpec

MAX_DISCRETE_ACTIONS = 100_000

__all__ = [
    "MAX_DISCRETE_ACTIONS",
    "DiscretizeParameterizedAction",
    "FlattenParameterizedAction",
    "SelectObservation",
    "action_to_grid",
    "action_to_scores",
    "grid_size",
    "grid_to_action",
    "make_grid",
    "scores_to_action",
]


# ---------------------------------------------------------------------------------------------------------------------
# Batched conversion math (no env, no spec object: arrays and the spec's dims only)
# ---------------------------------------------------------------------------------------------------------------------


def scores_to_action(actions: np.ndarray, n_types: int) -> tuple[np.ndarray, np.ndarray]:
    """
    Decode flat actions ``[scores (K), parameters (n_params)]`` into action types and scaled parameters.

    :param actions: ``(n, K + n_params)`` flat actions
    :param n_types: Number of action types K
    :return: ``k`` of shape ``(n,)`` (int64, the highest score; ties go to the lowest index) and ``params_scaled``
        of shape ``(n, n_params)`` (float64, clipped to ``[-1, 1]``)
    :raises ValueError: for a wrong shape or a NaN anywhere in ``actions``
    """
    actions = np.asarray(actions)
    if actions.ndim != 2 or actions.shape[1] < n_types:
        raise ValueError(f"Expected flat actions of shape (n, {n_types} + n_params), got {actions.shape}")
    if np.isnan(actions).any():
        raise ValueError(f"Flat action contains NaN: {actions}")
    k = np.argmax(actions[:, :n_types], axis=1)  # first maximum: ties go to the lowest index
    params_scaled = np.minimum(np.maximum(actions[:, n_types:].astype(np.float64), -1.0), 1.0)
    return k.astype(np.int64), params_scaled


def action_to_scores(k: np.ndarray, params_scaled: np.ndarray, n_types: int) -> np.ndarray:
    """
    Inverse of :func:`scores_to_action`: score 1 for the chosen type, -1 for the others, parameters clipped.

    :param k: ``(n,)`` 0-based action types
    :param params_scaled: ``(n, n_params)`` parameters in ``[-1, 1]``
    :param n_types: Number of action types K
    :return: ``(n, K + n_params)`` float32 flat actions, inside ``Box(-1, 1)``
    """
    k = np.asarray(k)
    params_scaled = np.asarray(params_scaled)
    if k.ndim != 1 or params_scaled.ndim != 2 or len(params_scaled) != len(k):
        raise ValueError(
            f"Expected k of shape (n,) and params of shape (n, n_params), got {k.shape} and {params_scaled.shape}"
        )
    if np.any((k < 0) | (k >= n_types)):
        raise ValueError(f"Action types {k} out of range [0, {n_types})")
    scores = np.full((len(k), n_types), -1.0)
    scores[np.arange(len(k)), k] = 1.0
    return np.concatenate([scores, np.clip(params_scaled, -1.0, 1.0)], axis=1).astype(np.float32)


def _check_bins(bins: int | Sequence[int], n_params: int) -> tuple[int, ...]:
    """``bins`` as one int per parameter, each >= 1."""
    if isinstance(bins, (int, np.integer)):
        per_param = (bins,) * n_params
    elif isinstance(bins, (Sequence, np.ndarray)):
        per_param = tuple(bins)
    else:
        raise ValueError(f"bins must be an int or one int per parameter ({n_params}), got {bins!r}")
    if len(per_param) != n_params:
        raise ValueError(f"bins must be an int or one int per parameter ({n_params}), got {len(per_param)} values: {bins}")
    for b in per_param:
        if isinstance(b, bool) or not isinstance(b, (int, np.integer)) or b < 1:  # type: ignore[redundant-expr]
            raise ValueError(f"Every bin count must be an int >= 1, got {bins}")
    return tuple(int(b) for b in per_param)


def _type_sizes(dims: Sequence[int], bins: Sequence[int]) -> list[int]:
    offsets = np.concatenate([[0], np.cumsum(dims)]).astype(int)
    # math.prod on Python ints: no overflow however absurd the grid
    return [math.prod(bins[offsets[k] : offsets[k + 1]]) for k in range(len(dims))]


def grid_size(dims: Sequence[int], bins: int | Sequence[int]) -> int:
    """
    Number of discrete actions of :func:`make_grid`, computed without building it.

    :param dims: Number of parameters of each action type
    :param bins: Values per parameter: one int for all, or one per parameter (types concatenated)
    :return: ``sum_k prod(bins of type k's parameters)``
    """
    return sum(_type_sizes(dims, _check_bins(bins, int(sum(dims)))))


def _grid_values(b: int) -> np.ndarray:
    """``b`` evenly spaced scaled values with both ends ``-1`` and ``1`` included; one bin is the middle, 0."""
    return np.linspace(-1.0, 1.0, b) if b > 1 else np.zeros(1)


def _strides(dims: Sequence[int], bins: Sequence[int]) -> np.ndarray:
    """Per parameter: how far its grid index moves the action index (the last parameter of a type moves fastest)."""
    strides = np.ones(len(bins), dtype=np.int64)
    start = 0
    for d in dims:
        for j in range(start + d - 2, start - 1, -1):
            strides[j] = strides[j + 1] * bins[j + 1]
        start += d
    return strides


def make_grid(dims: Sequence[int], bins: int | Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    """
    Table of the discrete actions: every action type with every combination of its parameters' grid values.

    Actions are ordered by type, then in C order over the type's parameters (its last parameter varies fastest).
    Parameters of the other types are 0 (the middle of their range).

    :param dims: Number of parameters of each action type
    :param bins: Values per parameter: one int for all, or one per parameter (types concatenated)
    :return: ``types`` of shape ``(N,)`` (int64, 0-based) and ``params_scaled`` of shape ``(N, n_params)`` (float64)
    """
    n_params = int(sum(dims))
    bins = _check_bins(bins, n_params)
    sizes = _type_sizes(dims, bins)
    types = np.repeat(np.arange(len(dims), dtype=np.int64), sizes)
    params_scaled = np.zeros((sum(sizes), n_params))
    row, start = 0, 0
    for d, size in zip(dims, sizes, strict=True):
        if d > 0:
            axes = np.meshgrid(*(_grid_values(b) for b in bins[start : start + d]), indexing="ij")
            params_scaled[row : row + size, start : start + d] = np.stack([a.ravel() for a in axes], axis=1)
        row, start = row + size, start + d
    return types, params_scaled


def grid_to_action(index: np.ndarray, types: np.ndarray, params_scaled: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Look discrete actions up in a :func:`make_grid` table.

    :param index: ``(n,)`` discrete actions in ``[0, N)``
    :param types: ``(N,)`` table of action types
    :param params_scaled: ``(N, n_params)`` table of scaled parameters
    :return: ``k`` of shape ``(n,)`` and ``params_scaled`` of shape ``(n, n_params)`` (copies)
    """
    index = np.asarray(index)
    if index.ndim != 1 or not np.issubdtype(index.dtype, np.integer):
        raise ValueError(f"Expected an integer array of shape (n,), got {index.dtype} of shape {index.shape}")
    if np.any((index < 0) | (index >= len(types))):
        raise ValueError(f"Discrete actions {index} out of range [0, {len(types)})")
    return types[index], params_scaled[index]


def action_to_grid(k: np.ndarray, params_scaled: np.ndarray, dims: Sequence[int], bins: int | Sequence[int]) -> np.ndarray:
    """
    Inverse of :func:`grid_to_action`: the discrete action of type ``k`` nearest to ``params_scaled``.

    Each of type ``k``'s parameters is clipped to ``[-1, 1]`` and rounded to its nearest grid value; the other
    types' parameters are ignored.

    :param k: ``(n,)`` 0-based action types
    :param params_scaled: ``(n, n_params)`` scaled parameters
    :param dims: Number of parameters of each action type
    :param bins: Values per parameter, as given to :func:`make_grid`
    :return: ``(n,)`` int64 indices into the :func:`make_grid` table
    """
    bins = _check_bins(bins, int(sum(dims)))
    k = np.asarray(k)
    params_scaled = np.asarray(params_scaled, dtype=np.float64)
    if k.ndim != 1 or params_scaled.shape != (len(k), len(bins)):
        raise ValueError(
            f"Expected k of shape (n,) and params of shape (n, {len(bins)}), got {k.shape} and {params_scaled.shape}"
        )
    if np.any((k < 0) | (k >= len(dims))):
        raise ValueError(f"Action types {k} out of range [0, {len(dims)})")
    steps = np.array(bins) - 1
    position = (np.clip(params_scaled, -1.0, 1.0) + 1.0) / 2.0 * steps  # 0 .. bins - 1
    cell = np.minimum(np.rint(position), steps).astype(np.int64)
    own = np.repeat(np.arange(len(dims)), dims)[None, :] == k[:, None]  # the parameters type k owns
    first = np.concatenate([[0], np.cumsum(_type_sizes(dims, bins))])[:-1]
    index: np.ndarray = first[k] + (cell * _strides(dims, bins) * own).sum(axis=1)
    return index


# ---------------------------------------------------------------------------------------------------------------------
# Gymnasium wrappers
# ---------------------------------------------------------------------------------------------------------------------


class FlattenParameterizedAction(gym.ActionWrapper):
    """
    Present a parameterized action space as ``Box(-1, 1, (K + n_params,), float32)`` (PA-DDPG's formulation).

    An action is K scores followed by every type's parameters scaled to ``[-1, 1]``. The env runs the type with the
    highest score (ties: the lowest index) with that type's parameters clipped to ``[-1, 1]`` and mapped onto its
    Box bounds; the other types' parameters go to the env too in the nested and flat layouts (where it expects all
    of them), and are dropped in the shared and OneOf layouts.

    :param env: An env whose action space is one of the parameterized layouts of :mod:`sb3_aac.common.spaces`
    :raises ValueError: if it is not (the message says which spaces are supported)
    """

    def __init__(self, env: gym.Env):
        super().__init__(env)
        #: The parsed action space of the wrapped env (not ``spec``: that is the wrapper's ``EnvSpec``)
        self.action_spec = ParameterizedActionSpec.from_space(env.action_space)
        self.n_types = self.action_spec.n_types
        self.action_space = spaces.Box(-1.0, 1.0, (self.n_types + self.action_spec.n_params,), np.float32)

    def action(self, action: np.ndarray) -> Any:
        """
        Convert a flat action into the env's action.

        :param action: ``(K + n_params,)`` scores and scaled parameters
        :return: The env action (a tuple, see :mod:`sb3_aac.common.spaces`)
        """
        flat = np.asarray(action)
        if flat.shape != self.action_space.shape:
            raise ValueError(f"Expected a flat action of shape {self.action_space.shape}, got {flat.shape}")
        k, params_scaled = scores_to_action(flat[None], self.n_types)
        return self.action_spec.to_env_single(int(k[0]), params_scaled[0])

    def reverse_action(self, action: Any) -> np.ndarray:
        """
        Convert an env action into a flat action that :meth:`action` maps back to it.

        :param action: An element of the wrapped env's action space
        :return: ``(K + n_params,)`` float32: score 1 for the action's type and -1 for the others, then the scaled
            parameters (in the shared and OneOf layouts the other types' parameters are 0, the middle of their range)
        """
        k, params_scaled = self.action_spec.from_env([action])
        scores: np.ndarray = action_to_scores(k, params_scaled, self.n_types)[0]
        return scores


class DiscretizeParameterizedAction(gym.ActionWrapper):
    """
    Present a parameterized action space as ``Discrete(N)``: action types times a grid over their parameters.

    Each parameter takes ``bins`` evenly spaced values between its bounds, both bounds included (a single bin is
    the middle of the range). Type ``k`` contributes the product of its parameters' bins (one action if it has no
    parameters). The table is ordered by type, then by parameter values with the type's last parameter varying
    fastest; :attr:`types` and :attr:`params_scaled` hold it, :meth:`describe` prints one entry.

    :param env: An env whose action space is one of the parameterized layouts of :mod:`sb3_aac.common.spaces`
    :param bins: Values per parameter: one int for every parameter, or a sequence with one int per parameter in
        the spec's order (type after type; in the shared layout each type has its own copy of the shared Box)
    :param max_actions: Refuse grids with more discrete actions than this
    :raises ValueError: if the action space is not parameterized, ``bins`` is malformed, or the grid has more than
        ``max_actions`` actions
    """

    def __init__(self, env: gym.Env, bins: int | Sequence[int] = 3, max_actions: int = MAX_DISCRETE_ACTIONS):
        super().__init__(env)
        #: The parsed action space of the wrapped env (not ``spec``: that is the wrapper's ``EnvSpec``)
        self.action_spec = spec = ParameterizedActionSpec.from_space(env.action_space)
        #: Values per parameter, one int per parameter
        self.bins = _check_bins(bins, spec.n_params)
        #: Number of discrete actions of each type
        self.type_sizes = tuple(_type_sizes(spec.dims, self.bins))
        n_actions = sum(self.type_sizes)
        if n_actions > max_actions:
            per_type = ", ".join(
                f"type {k}: {' x '.join(str(b) for b in self.bins[spec.type_slice(k)]) or '1'}" for k in range(spec.n_types)
            )
            raise ValueError(
                f"DiscretizeParameterizedAction would have {n_actions} discrete actions ({per_type}), more than "
                f"max_actions={max_actions}. Use fewer bins, e.g. a per-parameter sequence with 1 bin for parameters "
                f"the env ignores, or raise max_actions."
            )
        self.types, self.params_scaled = make_grid(spec.dims, self.bins)
        self.types.flags.writeable = False
        self.params_scaled.flags.writeable = False
        self.action_space = spaces.Discrete(n_actions)

    def _index(self, action: Any) -> int:
        value = np.asarray(action)
        if value.size != 1 or not np.issubdtype(value.dtype, np.integer):
            raise ValueError(f"Expected one integer discrete action, got {action!r}")
        index = int(value.item())
        n_actions = len(self.types)
        if not 0 <= index < n_actions:
            raise ValueError(f"Discrete action {index} out of range [0, {n_actions})")
        return index

    def action(self, action: int | np.integer | np.ndarray) -> Any:
        """
        Convert a discrete action into the env's action.

        :param action: An index in ``[0, N)`` (an int, a numpy integer or a one-element integer array)
        :return: The env action (a tuple, see :mod:`sb3_aac.common.spaces`)
        """
        index = self._index(action)
        return self.action_spec.to_env_single(int(self.types[index]), self.params_scaled[index])

    def reverse_action(self, action: Any) -> int:
        """
        The discrete action nearest to an env action: same type, each parameter rounded to its nearest grid value.

        :param action: An element of the wrapped env's action space
        :return: An index in ``[0, N)``
        """
        k, params_scaled = self.action_spec.from_env([action])
        return int(action_to_grid(k, params_scaled, self.action_spec.dims, self.bins)[0])

    def describe(self, action: int) -> str:
        """
        Say which action type and parameter values a discrete action stands for.

        :param action: An index in ``[0, N)``
        :return: e.g. ``"action 7: type 1, parameters [0.5, 10]"``, with the env's type number (``Discrete.start``
            included) and the type's parameters in the env's units and Box shape
        """
        index = self._index(action)
        spec = self.action_spec
        k = int(self.types[index])
        values = spec.unscale(self.params_scaled[index])[spec.type_slice(k)].astype(spec.boxes[k].dtype)
        text = np.array2string(values.reshape(spec.boxes[k].shape), separator=", ", formatter={"float_kind": "{:.6g}".format})
        return f"action {index}: type {spec.start + k}, parameters {text}"


class SelectObservation(gym.ObservationWrapper):
    """
    Keep one part of a ``Tuple`` observation, a ``Box``, as the whole observation.

    Some parameterized-action envs observe a tuple, e.g. Platform-v0 (PyPI ``hybrid-platform``) gives
    ``(state Box(9), step counter Discrete(200))``; SB3 and sb3-aac algorithms take a Box. P-DQN's and MP-DQN's
    reference code keeps Platform's state part alone, as ``SelectObservation(env, 0)`` does.

    :param env: An env whose observation space is a ``Tuple``
    :param index: Which part to keep; it must be a ``Box``
    :raises ValueError: if the observation space is not a Tuple or its part ``index`` is not a Box
    """

    def __init__(self, env: gym.Env, index: int = 0):
        super().__init__(env)
        space = env.observation_space
        if not isinstance(space, spaces.Tuple):
            raise ValueError(f"SelectObservation needs a Tuple observation space, got {space}")
        if not 0 <= index < len(space.spaces) or not isinstance(space.spaces[index], spaces.Box):
            boxes = [i for i, part in enumerate(space.spaces) if isinstance(part, spaces.Box)]
            raise ValueError(f"index={index!r} must name a Box part of {space}; Box parts are at {boxes}")
        self.index = index
        self.observation_space = space.spaces[index]

    def observation(self, observation: tuple[Any, ...]) -> np.ndarray:
        """The kept part of ``observation``."""
        return np.asarray(observation[self.index], dtype=self.observation_space.dtype)
