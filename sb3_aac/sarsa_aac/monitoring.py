"""What SarsaAAC watches while it learns: the training statistics summed between log dumps and written by
:meth:`~TrainingMonitor.dump_logs` (the ``rollout/``, ``time/`` and ``train/`` keys of ``docs/sarsa_aac.md``), and
the divergence checks that restore the last finite weights and raise a ``FloatingPointError`` naming the
approximators."""

from __future__ import annotations

import sys
import time
from abc import abstractmethod
from typing import Any

import numpy as np
import torch as th
from stable_baselines3.common.type_aliases import Schedule
from stable_baselines3.common.utils import safe_mean

from sb3_aac.common.action_stats import ActionStats
from sb3_aac.common.divergence import divergence_error
from sb3_aac.common.episode_stats import EpisodeStatsMixin
from sb3_aac.sarsa_aac.policies import SarsaAACPolicy

# The training statistics summed between log dumps (the vector _train_stats, in this order): steps, TD error delta,
# |delta|, delta^2, the action-type actor's squared SARSA error, steps whose parameters moved (delta > 0).
TRAIN_STAT_FIELDS = ("n", "delta", "delta_abs", "delta_sq", "q_error_sq", "improved")


class TrainingMonitor(EpisodeStatsMixin):
    """SarsaAAC's statistics, logging and divergence checks (a base class of :class:`~sb3_aac.SarsaAAC`, which sets
    the attributes below)."""

    policy: SarsaAACPolicy
    learning_rate: float | Schedule
    q_learning_rate: float | Schedule
    param_learning_rate: float | Schedule
    q_lr_schedule: Schedule
    param_lr_schedule: Schedule
    exploration_rate: float
    param_noise: float
    # Per step since the last flush: delta, the SARSA error, the executed types and scaled parameters, V(s).
    _td_chunks: list[tuple[np.ndarray, ...]]
    _train_stats: np.ndarray
    _action_stats: ActionStats
    # The last finite weights (restored on divergence; None until first kept) and their timestep.
    _finite_weights: dict[str, th.Tensor] | None
    _finite_weights_timestep: int
    _pending: tuple[np.ndarray, np.ndarray, np.ndarray] | None
    _traces: Any
    _last_dump: tuple[int, int]
    _dumped_in_learn: bool
    exploration_episodes: int | None
    log_min_timesteps: int

    @abstractmethod
    def _update_exploration(self) -> None:
        """The exploration rate and parameter noise at the current progress (SarsaAAC's schedules)."""

    def _keep_finite_weights(self) -> None:
        """Check the weights and keep a copy of them as the last finite ones (restored on divergence)."""
        self._check_weights()
        self._finite_weights = {name: p.detach().clone() for name, p in self.policy.named_parameters()}
        self._finite_weights_timestep = self.num_timesteps

    def _on_non_finite_outputs(self, batch: np.ndarray) -> None:
        """Name what made the outputs non-finite, restore the last finite weights, and raise."""
        self._check_weights()
        if not np.isfinite(batch).all():
            raise ValueError(
                f"The env returned a non-finite (nan or inf) observation by timestep {self.num_timesteps}; "
                "SarsaAAC needs finite observations (the weights are unchanged)"
            )
        self._raise_divergence("the outputs (weights finite, but too large for the observations)")

    def _flush_td_chunks(self) -> None:
        """Fold the per-step TD errors into the running sums, and stop on divergence."""
        if not self._td_chunks:
            return
        delta, q_error, k, params, values = (np.concatenate(parts) for parts in zip(*self._td_chunks, strict=True))
        self._td_chunks.clear()
        sums = {
            "n": len(delta),
            "delta": delta.sum(),
            "delta_abs": np.abs(delta).sum(),
            "delta_sq": delta @ delta,
            "q_error_sq": q_error @ q_error,
            "improved": (delta > 0).sum(),
        }
        self._check_weights()  # names the approximators that diverged
        if not np.isfinite([sums["delta"], sums["delta_abs"], sums["delta_sq"]]).all():
            self._raise_divergence("the critic's TD error (delta)")
        if not np.isfinite(sums["q_error_sq"]):
            self._raise_divergence("the action-type actor's SARSA error")
        self._train_stats += [sums[name] for name in TRAIN_STAT_FIELDS]
        self._action_stats.add(k, params, values)

    def _check_weights(self) -> None:
        finite = self.policy.finite_outputs()
        if not finite.all():
            policy = self.policy
            names = []
            if not finite[policy.q_slice].all():
                names.append(f"the action-type actor (Q of types {np.flatnonzero(~finite[policy.q_slice]).tolist()})")
            if not finite[policy.param_slice].all():
                names.append(f"the parameter actor (parameters {np.flatnonzero(~finite[policy.param_slice]).tolist()})")
            if not finite[policy.value_index]:
                names.append("the critic")
            self._raise_divergence("the weights of " + " and ".join(names))

    def _raise_divergence(self, what: str) -> None:
        """Restore the last finite weights and raise a ``FloatingPointError`` saying so."""
        restored = "the weights were not restored (no finite copy)"
        if self._finite_weights is not None:
            with th.no_grad():
                for name, p in self.policy.named_parameters():
                    p.copy_(self._finite_weights[name])
            restored = (
                f"the weights were restored to those of timestep {self._finite_weights_timestep}, "
                "so save() keeps a usable model"
            )
        self._pending = None  # choose afresh with the restored weights
        self._traces = None
        remedy = (
            f"Lower the learning rates (learning_rate={self.learning_rate}, q_learning_rate={self.q_learning_rate}, "
            f"param_learning_rate={self.param_learning_rate}; normalised rates should be in [0, 1]), lower gamma, "
            "or rescale the rewards"
        )
        raise divergence_error(type(self).__name__, what, self.num_timesteps, remedy, restored)

    def _on_episodes_end(self, dones: np.ndarray, infos: list[dict[str, Any]], log_interval: int | None) -> None:
        for i in np.flatnonzero(dones):
            self._add_episode_keywords(infos[i])
        self._episode_num += int(dones.sum())
        if self.exploration_episodes is not None and self._episode_num <= self.exploration_episodes + len(dones):
            self._update_exploration()
        episodes, timesteps = self._last_dump
        if (
            log_interval is not None
            and self._episode_num - episodes >= log_interval
            and (self.num_timesteps - timesteps >= self.log_min_timesteps or not self._dumped_in_learn)
        ):
            self.dump_logs()

    def dump_logs(self) -> None:
        """Write log data (``rollout/``, ``time/`` and ``train/`` keys), then reset the ``train/`` statistics."""
        assert self.ep_info_buffer is not None
        assert self.ep_success_buffer is not None
        self._flush_td_chunks()
        time_elapsed = max((time.time_ns() - self.start_time) / 1e9, sys.float_info.epsilon)
        fps = int((self.num_timesteps - self._num_timesteps_at_start) / time_elapsed)
        record = self.logger.record
        record("time/episodes", self._episode_num, exclude="tensorboard")
        if len(self.ep_info_buffer) > 0 and len(self.ep_info_buffer[0]) > 0:
            record("rollout/ep_rew_mean", safe_mean([ep_info["r"] for ep_info in self.ep_info_buffer]))
            record("rollout/ep_len_mean", safe_mean([ep_info["l"] for ep_info in self.ep_info_buffer]))
        self._record_keyword_means()
        if len(self.ep_success_buffer) > 0:
            record("rollout/success_rate", safe_mean(self.ep_success_buffer))
        record("rollout/exploration_rate", self.exploration_rate)
        stats = dict(zip(TRAIN_STAT_FIELDS, self._train_stats, strict=True))
        n = stats["n"]
        self._action_stats.record(self.logger)
        if n > 0:
            record("train/td_error_mean", stats["delta"] / n)
            record("train/td_error_abs_mean", stats["delta_abs"] / n)
            record("train/critic_loss", stats["delta_sq"] / n)
            record("train/q_loss", stats["q_error_sq"] / n)
            record("train/param_update_fraction", stats["improved"] / n)
        progress = self._current_progress_remaining
        record("train/param_noise", self.param_noise)
        record("train/learning_rate", self.lr_schedule(progress))
        record("train/q_learning_rate", self.q_lr_schedule(progress))
        record("train/param_learning_rate", self.param_lr_schedule(progress))
        record("train/n_updates", self._n_updates, exclude="tensorboard")
        record("time/fps", fps)
        record("time/time_elapsed", int(time_elapsed), exclude="tensorboard")
        record("time/total_timesteps", self.num_timesteps, exclude="tensorboard")
        self.logger.dump(step=self.num_timesteps)
        self._last_dump = (self._episode_num, self.num_timesteps)
        self._dumped_in_learn = True
        self._train_stats[:] = 0
