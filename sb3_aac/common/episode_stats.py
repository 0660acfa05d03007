"""
The episode statistics every algorithm of this package keeps beyond SB3's: ``info`` values of finished episodes,
logged as means, and a public episode count; and the same ``info`` means for any SB3 algorithm, as a callback.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.logger import Logger
from stable_baselines3.common.type_aliases import MaybeCallback
from stable_baselines3.common.utils import safe_mean


def check_info_keywords(info_keywords: Sequence[str]) -> tuple[str, ...]:
    """``info_keywords`` as a tuple; a ``ValueError`` unless it is a tuple or list of strings."""
    # A run-time check of user input that the annotation cannot guarantee.
    if not isinstance(info_keywords, tuple | list) or not all(isinstance(key, str) for key in info_keywords):
        hint = f"; for one key write ({info_keywords!r},)" if isinstance(info_keywords, str) else ""
        raise ValueError(f"info_keywords must be a tuple of info keys (str), got {info_keywords!r}{hint}")
    return tuple(info_keywords)


class EpisodeKeywordBuffers:
    """
    Per key of ``info_keywords``, the values (floats) the last ``window_size`` finished episodes that reported the key
    gave at their last step, like SB3's ``ep_info_buffer``; ``buffers[key]`` is that key's ``deque``.

    :param info_keywords: the ``info`` keys (see :func:`check_info_keywords`)
    :param window_size: episodes per window (the algorithm's ``stats_window_size``)
    """

    def __init__(self, info_keywords: Sequence[str], window_size: int):
        self.info_keywords = check_info_keywords(info_keywords)
        self._buffers: dict[str, deque[float]] = {key: deque(maxlen=window_size) for key in self.info_keywords}

    def __getitem__(self, key: str) -> deque[float]:
        return self._buffers[key]

    def add(self, info: Mapping[str, Any]) -> None:
        """Append the values ``info`` holds (one finished episode's) to their keys' windows."""
        for key, buffer in self._buffers.items():
            if key in info:
                buffer.append(float(info[key]))

    def record(self, logger: Logger) -> None:
        """Record ``rollout/ep_<key>_mean``, the mean of the window, for every key with values in its window."""
        for key, buffer in self._buffers.items():
            if buffer:
                logger.record(f"rollout/ep_{key}_mean", safe_mean(list(buffer)))


class EpisodeStatsMixin(BaseAlgorithm):
    """
    ``info_keywords`` windows and the episode count, for any ``BaseAlgorithm`` subclass: list the mixin before the SB3
    base class (``class MyAlgo(EpisodeStatsMixin, OffPolicyAlgorithm)``); it defines no ``__init__``.

    - ``info_keywords`` (set by :meth:`_set_info_keywords` in the constructor): keys of ``info`` read at the step
      where an episode ends. Their values are kept in ``_ep_keyword_buffers`` (an :class:`EpisodeKeywordBuffers` of
      ``stats_window_size`` episodes), and :meth:`_record_keyword_means` logs their means as ``rollout/ep_<key>_mean``
      (nothing for a key no episode reported yet).
    - The windows are emptied by :meth:`_reset_keyword_buffers` (call it in ``_setup_model``) and whenever ``learn``
      resets the timestep count (as SB3 empties ``ep_info_buffer``); they are not saved with the model.
    - :attr:`episode_num`: the episodes finished since the model was created, over all envs (the algorithm counts
      them in SB3's ``_episode_num``; saved with the model).

    The algorithm calls :meth:`_add_episode_keywords` once per finished episode. SB3's own algorithms get the same
    ``rollout/ep_<key>_mean`` from :class:`EpisodeKeywordsCallback`.
    """

    info_keywords: tuple[str, ...]
    _ep_keyword_buffers: EpisodeKeywordBuffers

    @property
    def episode_num(self) -> int:
        """The number of episodes finished since the model was created, counted over all envs."""
        return int(self._episode_num)

    def _set_info_keywords(self, info_keywords: tuple[str, ...]) -> None:
        """Check and keep ``info_keywords`` (a ``ValueError`` unless it is a tuple of strings)."""
        self.info_keywords = check_info_keywords(info_keywords)

    def _reset_keyword_buffers(self) -> None:
        """Empty windows of the ``info_keywords`` values of finished episodes (like ``ep_info_buffer``)."""
        self._ep_keyword_buffers = EpisodeKeywordBuffers(self.info_keywords, self._stats_window_size)

    def _add_episode_keywords(self, info: Mapping[str, Any]) -> None:
        """Append the ``info_keywords`` values ``info`` holds (one finished episode's) to their windows."""
        self._ep_keyword_buffers.add(info)

    def _record_keyword_means(self) -> None:
        """Record ``rollout/ep_<key>_mean`` for every key with values in its window."""
        self._ep_keyword_buffers.record(self.logger)

    def _setup_learn(
        self,
        total_timesteps: int,
        callback: MaybeCallback = None,
        reset_num_timesteps: bool = True,
        tb_log_name: str = "run",
        progress_bar: bool = False,
    ) -> tuple[int, BaseCallback]:
        if reset_num_timesteps:  # like ep_info_buffer in BaseAlgorithm._setup_learn
            self._reset_keyword_buffers()
        return super()._setup_learn(total_timesteps, callback, reset_num_timesteps, tb_log_name, progress_bar)

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "_ep_keyword_buffers"]


class EpisodeKeywordsCallback(BaseCallback):
    """
    ``rollout/ep_<key>_mean`` for any SB3 algorithm on any ``VecEnv``, with the meaning this package's algorithms
    give it (:class:`EpisodeStatsMixin`): per key of ``info_keywords``, the mean of the values the last
    ``stats_window_size`` (the model's) finished episodes that reported the key gave in ``info`` at their last step.
    For SB3's PPO, TD3, DQN, ... trained through :class:`~sb3_aac.FlattenParameterizedAction` or
    :class:`~sb3_aac.DiscretizeParameterizedAction`, which log only ``ep_rew_mean`` and ``ep_len_mean``::

        model.learn(100_000, callback=EpisodeKeywordsCallback(("distance", "ball_lost")))

    The means are recorded at every step where an episode ends and at the end of every rollout, so each of SB3's
    dumps (off-policy: at an episode end; on-policy: after a rollout) carries them beside ``ep_rew_mean``, from the
    same episodes. The windows are emptied when ``learn`` resets the timestep count (as SB3 empties
    ``ep_info_buffer``) or the callback is given another model. It reads the ``dones`` and ``infos`` SB3 passes to
    callbacks, so it works on every ``VecEnv`` (``DummyVecEnv``, ``SubprocVecEnv``, ``DribbleVecEnv``, ...).

    :param info_keywords: the ``info`` keys (a tuple of strings: a ``ValueError`` otherwise)
    :param verbose: SB3's callback verbosity (nothing is printed)
    """

    def __init__(self, info_keywords: tuple[str, ...], verbose: int = 0):
        super().__init__(verbose)
        self.info_keywords = check_info_keywords(info_keywords)
        self.buffers: EpisodeKeywordBuffers | None = None
        self._buffers_model: BaseAlgorithm | None = None

    def _init_callback(self) -> None:
        if self.buffers is None or self._buffers_model is not self.model or self.model.num_timesteps == 0:
            self.buffers = EpisodeKeywordBuffers(self.info_keywords, self.model._stats_window_size)
            self._buffers_model = self.model

    def _on_step(self) -> bool:
        assert self.buffers is not None, "the callback runs only inside learn()"
        ended = np.flatnonzero(self.locals["dones"])
        if ended.size:
            infos = self.locals["infos"]
            for i in ended:
                self.buffers.add(infos[i])
            self.buffers.record(self.logger)
        return True

    def _on_rollout_end(self) -> None:
        assert self.buffers is not None, "the callback runs only inside learn()"
        self.buffers.record(self.logger)
