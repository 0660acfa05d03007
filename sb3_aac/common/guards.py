"""
What every algorithm of this package guards beyond Stable-Baselines3: ``learn``'s budget is checked, ``save`` cannot
lose the earlier file, ``load`` checks the file first, a learning rate must be a number or a schedule, an env must
have Box observations, and the env's observations and rewards are checked finite before anything learns from them.
"""

from __future__ import annotations

import io
import math
import os
import pathlib
import zipfile
from collections.abc import Iterable
from typing import Any, ClassVar, TypeVar

import numpy as np
import torch as th
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.type_aliases import GymEnv, MaybeCallback
from stable_baselines3.common.vec_env import VecEnv

from sb3_aac.common.model_files import check_model_file
from sb3_aac.common.observations import check_box_observation_space
from sb3_aac.common.output_files import replaced_atomically
from sb3_aac.common.sizes import is_whole

SelfGuarded = TypeVar("SelfGuarded", bound="GuardedAlgorithmMixin")


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


def check_schedule(name: str, value: Any, allow_none: bool = False) -> None:
    """
    Check a hyperparameter that is a number or a schedule (SB3's: a callable of the progress remaining).

    :raises ValueError: saying what is allowed, for anything else (``"abc"``; SB3 would fail later with an assertion
        about the learning rate whatever the name)
    """
    if (value is None and allow_none) or callable(value):
        return
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or not math.isfinite(value):
        allowed = "a finite number or a schedule (a callable of the progress remaining, 1 to 0)"
        raise ValueError(f"{name} must be {allowed}{', or None' if allow_none else ''}, got {value!r}")


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

    - An env whose observations are not a ``Box`` is refused first, with what to do (SB3 would point a Dict to a
      ``MultiInputPolicy``, which this package does not have).
    - :meth:`load` checks the file first (:func:`~sb3_aac.common.model_files.check_model_file`: damage, a missing
      member or field, NaN or inf weights) and turns SB3's failures on a file that passes into one ``ValueError``.

    The algorithm calls :func:`check_finite_step` after each env step.
    """

    load_device: ClassVar[str] = "auto"  # where load puts the model unless told (SB3's default: a GPU if there is one)

    @classmethod
    def load(
        cls: type[SelfGuarded],
        path: Any,
        env: GymEnv | None = None,
        device: th.device | str | None = None,
        custom_objects: dict[str, Any] | None = None,
        print_system_info: bool = False,
        force_reset: bool = True,
        **kwargs: Any,
    ) -> SelfGuarded:
        """
        Load the model from a zip-file (see :meth:`BaseAlgorithm.load`), onto ``device`` (None: :attr:`load_device`).

        :raises ValueError: if the file is not a complete, usable model of this algorithm (corrupted, truncated, NaN
            or inf weights, or another algorithm's), if a hyperparameter of ``custom_objects`` is refused, or if
            ``env`` does not match the model's spaces
        """
        check_model_file(path)  # one ValueError naming the file for any damage, before SB3 unpickles anything
        try:
            return super().load(path, env, device or cls.load_device, custom_objects, print_system_info, force_reset, **kwargs)
        except (zipfile.BadZipFile, EOFError, AssertionError, KeyError, RuntimeError, OSError) as e:
            if isinstance(e, FileNotFoundError):
                raise
            raise ValueError(
                f"{path} is not a complete {cls.__name__} model (corrupted, truncated, or saved by another algorithm): {e!r}"
            ) from e

    @staticmethod
    def _wrap_env(env: GymEnv, verbose: int = 0, monitor_wrapper: bool = True) -> VecEnv:
        # Before SB3's own check, which points Dict observations to a MultiInputPolicy this package does not have.
        check_box_observation_space(env.observation_space, "sb3-aac's policies")
        return BaseAlgorithm._wrap_env(env, verbose, monitor_wrapper)

    def _setup_lr_schedule(self) -> None:
        check_schedule("learning_rate", self.learning_rate)
        super()._setup_lr_schedule()

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
