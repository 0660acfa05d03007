"""Greedy evaluation at checkpoints of training: a callback that scores the model every ``every`` env steps."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from stable_baselines3.common.callbacks import BaseCallback


class GreedyCheckpoints(BaseCallback):
    """
    Every ``every`` env steps of ``learn`` (``num_timesteps``, summed over lanes): ``score(model)``, appended to
    :attr:`curve` as ``(num_timesteps, score)`` and passed to :meth:`on_checkpoint`, whose answer says whether
    training goes on. A checkpoint is taken at the first step at or past ``every``, ``2 * every``, ... (one per step).

    :param every: env steps between checkpoints (>= 1)
    :param score: the model's greedy score (the caller fixes the evaluation episodes)
    """

    def __init__(self, every: int, score: Callable[[Any], float]):
        super().__init__()
        if every < 1:
            raise ValueError(f"every must be >= 1 env step, got {every}")
        self.every, self.score = every, score
        self.curve: list[tuple[int, float]] = []
        self._next_checkpoint = every

    def _on_step(self) -> bool:
        if self.num_timesteps < self._next_checkpoint:
            return True
        self._next_checkpoint += self.every
        value = self.score(self.model)
        self.curve.append((int(self.num_timesteps), value))
        return self.on_checkpoint(value)

    def on_checkpoint(self, score: float) -> bool:
        """Called with each checkpoint's score; False stops training. This one goes on."""
        return True
