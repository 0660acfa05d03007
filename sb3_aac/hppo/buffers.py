"""The rollout buffer of HybridPPO: SB3's ``RolloutBuffer`` (GAE, minibatches) over packed actions, with the
parameter log-probabilities stored beside the type log-probabilities, so each part gets its own PPO ratio."""

from __future__ import annotations

from collections.abc import Generator
from typing import Any, NamedTuple

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3.common.buffers import RolloutBuffer
from stable_baselines3.common.vec_env import VecNormalize

from sb3_aac.common.sizes import check_allocation


class HybridRolloutBufferSamples(NamedTuple):
    """A minibatch (``B`` rows) as tensors; actions are packed ``[k, x]`` rows (see :mod:`sb3_aac.hppo.distributions`)."""

    observations: th.Tensor
    actions: th.Tensor
    old_values: th.Tensor
    old_type_log_prob: th.Tensor
    """``(B,)``: ``log p(k|s)`` under the policy that collected the rollout."""
    advantages: th.Tensor
    returns: th.Tensor
    old_param_log_prob: th.Tensor
    """``(B,)``: ``log N(x_k; mu_k, sigma_k)`` under the policy that collected the rollout."""


def packed_action_space(n_params: int) -> spaces.Box:
    """The Box SB3's buffer sizes its action rows by: ``1 + n_params`` float32 columns, the type then the parameters."""
    return spaces.Box(-np.inf, np.inf, (1 + n_params,), np.float32)


class HybridRolloutBuffer(RolloutBuffer):
    """
    SB3's ``RolloutBuffer`` whose ``log_probs`` hold the type log-probabilities and ``param_log_probs`` the parameter
    log-probabilities of the same actions.

    :param buffer_size: Steps per env of a rollout
    :param observation_space: The observation space
    :param n_params: Scalar parameters over all types (actions are stored packed, ``1 + n_params`` columns)
    :param device: Device of the sampled tensors
    :param gae_lambda: GAE's lambda
    :param gamma: The discount factor
    :param n_envs: Number of parallel environments
    :raises ValueError: if the buffer would pass :data:`~sb3_aac.common.sizes.MAX_ALLOCATION_BYTES`
    """

    param_log_probs: np.ndarray

    def __init__(
        self,
        buffer_size: int,
        observation_space: spaces.Space[Any],
        n_params: int,
        device: th.device | str = "auto",
        gae_lambda: float = 1,
        gamma: float = 0.99,
        n_envs: int = 1,
    ):
        # float32 columns per step and env: the observation, the packed action, and reward, return, episode start,
        # value, advantage and the two log-probabilities
        columns = int(np.prod(observation_space.shape or ())) + 1 + n_params + 7
        check_allocation(
            f"HybridPPO's rollout buffer (n_steps={buffer_size:,} x {n_envs:,} envs)", buffer_size * n_envs * columns, 4
        )
        super().__init__(buffer_size, observation_space, packed_action_space(n_params), device, gae_lambda, gamma, n_envs)

    def reset(self) -> None:
        self.param_log_probs = np.zeros((self.buffer_size, self.n_envs), dtype=np.float32)
        super().reset()

    def add(  # type: ignore[override]
        self, obs: np.ndarray, action: np.ndarray, reward: np.ndarray, episode_start: np.ndarray
    ) -> None:
        """One step of every env (each argument ``(n_envs, ...)``), from arrays (no tensor copies); its value and
        log-probabilities come with :meth:`set_evaluations` for the whole rollout."""
        pos = self.pos
        self.observations[pos] = obs
        self.actions[pos] = np.reshape(action, (self.n_envs, self.action_dim))
        self.rewards[pos] = reward
        self.episode_starts[pos] = episode_start
        self.pos = pos + 1
        self.full = self.pos == self.buffer_size

    def set_evaluations(self, values: np.ndarray, type_log_prob: np.ndarray, param_log_prob: np.ndarray) -> None:
        """The values and the type and parameter log-probabilities of the steps added so far, each ``(pos * n_envs,)``
        in the order of the steps, then the envs."""
        shape = (self.pos, self.n_envs)
        self.values[: self.pos] = values.reshape(shape)
        self.log_probs[: self.pos] = type_log_prob.reshape(shape)
        self.param_log_probs[: self.pos] = param_log_prob.reshape(shape)

    def get(self, batch_size: int | None = None) -> Generator[HybridRolloutBufferSamples, None, None]:  # type: ignore[override]
        if not self.generator_ready:
            self.param_log_probs = self.swap_and_flatten(self.param_log_probs)
        yield from super().get(batch_size)  # type: ignore[misc]

    def _get_samples(  # type: ignore[override]
        self, batch_inds: np.ndarray, env: VecNormalize | None = None
    ) -> HybridRolloutBufferSamples:
        base = super()._get_samples(batch_inds, env)
        return HybridRolloutBufferSamples(*base, old_param_log_prob=self.to_torch(self.param_log_probs[batch_inds].flatten()))
