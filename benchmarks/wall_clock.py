"""The equal wall-clock budget: a cell with ``seconds > 0`` trains until that many seconds of training have passed
(its greedy evaluations excluded, so every learner gets the same training time whatever its evaluation costs), or
until its env-step horizon, whichever comes first; :class:`TrainingTimeLimit` ends ``learn`` at the limit.

The horizon (``Cell.budget``) is what the learner steps in those seconds at its usual rate
(:data:`benchmarks.presets.STEPS_PER_SECOND`), because schedules (exploration, learning rates) run over the
horizon: a learner trained for 120 s ends its schedules at about 120 s. The cell file records which limit ended
training (``stopped_by``).
"""

from __future__ import annotations

import time

from stable_baselines3.common.callbacks import BaseCallback

from benchmarks.evaluation import EvalCallback


class TrainingTimeLimit(BaseCallback):
    """Stop training (``learn`` returns) once ``seconds`` of training have passed since training started, the time
    ``evaluation`` spent on its greedy evaluations excluded.

    :param seconds: the training-time budget (> 0)
    :param evaluation: the cell's learning-curve callback (its ``eval_seconds`` are not training time); place this
        callback after it in the ``CallbackList``
    """

    def __init__(self, seconds: float, evaluation: EvalCallback):
        super().__init__()
        if not seconds > 0:
            raise ValueError(f"a wall-clock budget must be > 0 seconds, got {seconds}")
        self.seconds, self.evaluation = float(seconds), evaluation
        self.reached = False  # whether the time limit (not the env-step horizon) ended training
        self._start = 0.0
        self._eval_before = 0.0  # evaluation seconds spent before training started (the curve's first point)

    def _on_training_start(self) -> None:
        self._start = time.perf_counter()
        self._eval_before = self.evaluation.eval_seconds

    def training_seconds(self) -> float:
        """Seconds of training so far (evaluations excluded)."""
        return time.perf_counter() - self._start - (self.evaluation.eval_seconds - self._eval_before)

    def _on_step(self) -> bool:
        self.reached = self.training_seconds() >= self.seconds
        return not self.reached
