"""The array path: a batched parameterized-action env stepped with arrays instead of N Python tuples.

SB3's ``VecEnv.step`` takes one Gymnasium action per lane and returns one ``info`` dict per lane. For a
parameterized action that means N Python tuples built by the algorithm and parsed back into arrays by the
env, and N dicts built by the env and read back by the algorithm: at hundreds of lanes this costs more than
the physics. A batched env that also offers :meth:`ArrayVecEnv.step_arrays` lets algorithms skip both.

The protocol (duck-typed: the env needs no import from this package):

- ``step_arrays(action_types, params) -> ArrayStep``, with ``action_types`` an ``(N,)`` integer array of
  0-based types and ``params`` an ``(N, n_params)`` float64 array holding every type's parameters in the
  env's own units, concatenated in type order (the flat layout of
  :class:`sb3_aac.common.spaces.ParameterizedActionSpec`, i.e. what ``spec.unscale`` returns). Out-of-range
  values are clipped as the tuple ``step`` clips them; a wrong shape or type index raises ``ValueError``.
- The env auto-resets like an SB3 ``VecEnv``: ``observations`` rows of lanes whose episode ended hold the
  first observation of their next episode, and ``terminal_observations`` holds the last one.
- ``step`` (the SB3 form, tuples in, info dicts out) stays available and gives the same transitions.

:func:`step_as_vec_env` steps an array env and returns what SB3's ``VecEnv.step`` would, which is what every
algorithm here hands its callbacks (``locals()["infos"]``, ``["dones"]``, ``["rewards"]``, ``["new_obs"]``) whichever
path it stepped; ``locals()["actions"]`` is the env's actions (a sequence of Gymnasium actions) on the SB3 path and
the pair ``(action_types, scaled_params)`` of ``(N,)`` 0-based types and ``(N, n_params)`` parameters in ``[-1, 1]``
on the array path.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple, Protocol, runtime_checkable

import numpy as np


class ArrayStep(NamedTuple):
    """One step of all N lanes. Rows marked "where ended" are meaningful only where ``terminated | truncated``."""

    observations: np.ndarray
    """``(N, *obs_shape)``: the next observations (a fresh episode's first one where ended)."""
    rewards: np.ndarray
    """``(N,)`` float: this step's rewards."""
    terminated: np.ndarray
    """``(N,)`` bool: the episode ended in a terminal state (no bootstrapping)."""
    truncated: np.ndarray
    """``(N,)`` bool: the episode was cut by a time limit and not terminated (bootstrap from the terminal observation)."""
    terminal_observations: np.ndarray
    """``(N, *obs_shape)``: the last observation of the episode, where ended."""
    episode_returns: np.ndarray
    """``(N,)`` float: the undiscounted return of the episode, where ended."""
    episode_lengths: np.ndarray
    """``(N,)`` int: the number of steps of the episode, where ended."""
    episode_info: Mapping[str, np.ndarray]
    """``(N,)`` arrays, one per episode statistic the env reports (e.g. ``"distance"``), where ended."""


@runtime_checkable
class ArrayVecEnv(Protocol):
    """A batched env offering the array path (see the module docstring)."""

    num_envs: int

    def step_arrays(self, action_types: np.ndarray, params: np.ndarray) -> ArrayStep: ...


def array_path(env: Any) -> ArrayVecEnv | None:
    """``env`` itself if its class offers ``step_arrays``, else None.

    The class is asked, not the instance: SB3's ``VecEnvWrapper`` forwards unknown attributes to the env it wraps,
    so a ``VecNormalize`` around an array env would otherwise be bypassed.
    """
    return env if callable(getattr(type(env), "step_arrays", None)) else None


def step_as_vec_env(
    env: ArrayVecEnv, action_types: np.ndarray, params: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
    """
    One :meth:`~ArrayVecEnv.step_arrays` call, returned as SB3's ``VecEnv.step`` would: ``(observations, rewards,
    dones, infos)``. ``infos`` is a list of N dicts: empty where the episode goes on; where it ended, the episode's
    statistics (``episode_info``), ``"episode"`` ``{"r", "l"}`` (as SB3's ``Monitor``), ``"terminal_observation"`` and
    ``"TimeLimit.truncated"``.
    """
    step = env.step_arrays(action_types, params)
    dones = step.terminated | step.truncated
    infos: list[dict[str, Any]] = [{} for _ in range(len(dones))]
    for i in np.flatnonzero(dones):
        info = infos[i]
        info.update((key, values[i]) for key, values in step.episode_info.items())
        info["episode"] = {"r": float(step.episode_returns[i]), "l": int(step.episode_lengths[i])}
        info["terminal_observation"] = step.terminal_observations[i]
        info["TimeLimit.truncated"] = bool(step.truncated[i])
    return step.observations, step.rewards, dones, infos
