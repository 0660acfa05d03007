"""
The episode statistics every algorithm of this package keeps beyond SB3's: ``info`` values of finished episodes,
logged as means, and a public episode count.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from typing import Any

from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.type_aliases import MaybeCallback
from stable_baselines3.common.utils import safe_mean


class EpisodeStatsMixin(BaseAlgorithm):
    """
    ``info_keywords`` windows and the episode count, for any ``BaseAlgorithm`` subclass: list the mixin before the SB3
    base class (``class MyAlgo(EpisodeStatsMixin, OffPolicyAlgorithm)``); it defines no ``__init__``.

    - ``info_keywords`` (set by :meth:`_set_info_keywords` in the constructor): keys of ``info`` read at the step
      where an episode ends. Per key, the values of the last ``stats_window_size`` episodes that reported it are kept
      in ``_ep_keyword_buffers`` (floats, like ``ep_info_buffer``), and :meth:`_record_keyword_means` logs their mean
      as ``rollout/ep_<key>_mean`` (nothing for a key no episode reported yet).
    - The windows are emptied by :meth:`_reset_keyword_buffers` (call it in ``_setup_model``) and whenever ``learn``
      resets the timestep count (as SB3 empties ``ep_info_buffer``); they are not saved with the model.
    - :attr:`episode_num`: the episodes finished since the model was created, over all envs (the algorithm counts
      them in SB3's ``_episode_num``; saved with the model).

    The algorithm calls :meth:`_add_episode_keywords` once per finished episode.
    """

    info_keywords: tuple[str, ...]
    _ep_keyword_buffers: dict[str, deque[float]]

    @property
    def episode_num(self) -> int:
        """The number of episodes finished since the model was created, counted over all envs."""
        return int(self._episode_num)

    def _set_info_keywords(self, info_keywords: tuple[str, ...]) -> None:
        """Check and keep ``info_keywords`` (a ``ValueError`` unless it is a tuple of strings)."""
        # A run-time check of user input that the annotation cannot guarantee.
        if isinstance(info_keywords, str) or not all(isinstance(key, str) for key in info_keywords):  # type: ignore[redundant-expr, unreachable]
            raise ValueError(
                f"info_keywords must be a tuple of info keys (str), got {info_keywords!r}; "
                f"for one key write ({info_keywords!r},)"
            )
        self.info_keywords = tuple(info_keywords)

    def _reset_keyword_buffers(self) -> None:
        """Empty windows of the ``info_keywords`` values of finished episodes (like ``ep_info_buffer``)."""
        self._ep_keyword_buffers = {key: deque(maxlen=self._stats_window_size) for key in self.info_keywords}

    def _add_episode_keywords(self, info: Mapping[str, Any]) -> None:
        """Append the ``info_keywords`` values ``info`` holds (one finished episode's) to their windows."""
        for key, buffer in self._ep_keyword_buffers.items():
            if key in info:
                buffer.append(float(info[key]))

    def _record_keyword_means(self) -> None:
        """Record ``rollout/ep_<key>_mean`` for every key with values in its window."""
        for key, buffer in self._ep_keyword_buffers.items():
            if buffer:
                self.logger.record(f"rollout/ep_{key}_mean", safe_mean(list(buffer)))

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
