"""
What every algorithm of this package guards beyond Stable-Baselines3: ``learn``'s budget is checked, ``save`` cannot
lose the earlier file, and the env's observations and rewards are checked finite before anything learns from them.
"""

from __future__ import annotations

import io
import math
import os
import pathlib
from collections.abc import Iterable
from typing import Any

import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.type_aliases import MaybeCallback

from sb3_aac.common.output_files import replaced_atomically
from sb3_aac.common.sizes import is_whole


def check_total_timesteps(total_timesteps: Any) -> int:
    """
    ``learn``'s budget as an int.

    :raises ValueError: unless it is a whole number >= 1 (``learn(-5)``, ``learn(nan)`` and ``learn("100")`` would
        otherwise return at once or fail deep inside SB3)
    """
    whole = is_whole(total_timesteps) or (isinstance(total_timesteps, float) and total_timesteps.is_integer())
    if not whole or total_timesteps < 1:
        raise ValueError(f"total_timesteps must be a whole number of env steps >= 1, got {total_timesteps!r}")
    return int(total_timesteps)


def check_finite_step(observations: np.ndarray, rewards: np.ndarray, num_timesteps: int) -> None:
    """
    Check one env step's observations ``(n, ...)`` and rewards ``(n,)`` of all lanes (one reduction when they are
    finite, as they almost always are).

    :raises ValueError: naming the lanes and the timestep of the first non-finite (NaN or inf) value
    """
    if math.isfinite(float(np.sum(rewards)) + float(np.sum(observations))):
        return
    n = len(rewards)
    bad_obs = np.flatnonzero(~np.isfinite(np.asarray(observations, dtype=np.float64).reshape(n, -1)).all(1))
    bad_rewards = np.flatnonzero(~np.isfinite(np.asarray(rewards, dtype=np.float64)))
    what = [f"observations of lanes {bad_obs.tolist()}"] * bool(len(bad_obs)) + [
        f"rewards of lanes {bad_rewards.tolist()}"
    ] * bool(len(bad_rewards))
    if what:  # else finite values whose sum overflowed
        raise ValueError(
            f"The env returned non-finite (NaN or inf) {' and '.join(what)} at timestep {num_timesteps}; the algorithms "
            "need finite observations and rewards (nothing has learnt from this step)"
        )


class GuardedAlgorithmMixin(BaseAlgorithm):
    """
    For any ``BaseAlgorithm`` subclass (list it first among the bases); it defines no ``__init__``.

    - ``learn`` (through ``_setup_learn``) refuses a budget that is not a whole number >= 1 (:func:`check_total_timesteps`).
    - :meth:`save` to a path writes a temporary beside the target and renames it into place once complete (flushed
      to disk), so a reader during a save sees the old file or the new one, and a failed save (a full disk, a kill)
      leaves the earlier file intact. A file object is written as SB3 writes it.

    The algorithm calls :func:`check_finite_step` after each env step.
    """

    def _setup_learn(
        self,
        total_timesteps: int,
        callback: MaybeCallback = None,
        reset_num_timesteps: bool = True,
        tb_log_name: str = "run",
        progress_bar: bool = False,
    ) -> tuple[int, BaseCallback]:
        total_timesteps = check_total_timesteps(total_timesteps)
        return super()._setup_learn(total_timesteps, callback, reset_num_timesteps, tb_log_name, progress_bar)

    def save(
        self,
        path: str | pathlib.Path | io.BufferedIOBase,
        exclude: Iterable[str] | None = None,
        include: Iterable[str] | None = None,
    ) -> None:
        """
        Save all the attributes of the object and the model parameters in a zip-file, as SB3's ``save`` does, but
        atomically (see the class docstring). As SB3, a path without a suffix gets ``.zip``.
        """
        if not isinstance(path, (str, os.PathLike)):
            super().save(path, exclude, include)
            return
        target = pathlib.Path(path)
        if target.suffix == "":
            target = target.with_name(target.name + ".zip")
        with replaced_atomically(target, suffix=".zip") as tmp:
            super().save(tmp, exclude, include)
