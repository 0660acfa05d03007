"""Replay buffer for parameterized actions (SB3's buffers store one numpy action array and reject Tuple spaces)."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import torch as th
from gymnasium import spaces

from sb3_aac.common.sizes import check_allocation, is_whole
from sb3_aac.common.spaces import ParameterizedActionSpec


class ParameterizedReplayBufferSamples(NamedTuple):
    """A minibatch of transitions as tensors on the buffer's device (``B`` = batch size)."""

    observations: th.Tensor
    """``(B, *obs_shape)`` float32."""
    action_types: th.Tensor
    """``(B,)`` int64, 0-based action types."""
    params: th.Tensor
    """``(B, n_params)`` float32: every type's parameters, scaled to ``[-1, 1]``, as executed."""
    next_observations: th.Tensor
    """``(B, *obs_shape)`` float32 (the terminal observation where an episode ended)."""
    dones: th.Tensor
    """``(B,)`` float32: 1 where the episode terminated (no bootstrapping); time-limit truncations count as 0 when
    ``handle_timeout_termination`` is set."""
    rewards: th.Tensor
    """``(B,)`` float32."""


class ParameterizedReplayBuffer:
    """
    Circular replay buffer of ``(s, k, x, r, s', done)`` transitions from ``n_envs`` environments.

    It stores the chosen type ``k`` and the *full* scaled parameter vector ``x`` (all types' parameters, in the
    layout of :class:`~sb3_aac.common.spaces.ParameterizedActionSpec`), as P-DQN's Q network takes all of them.
    Each :meth:`add` writes one row per environment; capacity is ``buffer_size`` rows of ``n_envs`` transitions
    (at least one row), as in SB3's ``ReplayBuffer``.

    :param buffer_size: Maximum number of transitions stored (over all environments)
    :param observation_space: A ``Box`` observation space
    :param action_space: A parameterized action space (see :mod:`sb3_aac.common.spaces`)
    :param device: Device of the sampled tensors
    :param n_envs: Number of parallel environments
    :param optimize_memory_usage: Store each observation once: the next observation of row ``i`` is the
        observation of row ``i + 1`` (SB3's memory-efficient variant, about half the memory). The oldest row cannot
        be sampled once the buffer is full, and the terminal observation of a finished episode is not kept, so it
        cannot be combined with ``handle_timeout_termination``.
    :param handle_timeout_termination: Treat time-limit truncations as non-terminal (bootstrap from the terminal
        observation), as SB3 does
    """

    def __init__(
        self,
        buffer_size: int,
        observation_space: spaces.Space[Any],
        action_space: spaces.Space[Any],
        device: th.device | str = "auto",
        n_envs: int = 1,
        optimize_memory_usage: bool = False,
        handle_timeout_termination: bool = True,
    ):
        if not isinstance(observation_space, spaces.Box):
            raise ValueError(f"ParameterizedReplayBuffer stores Box observations, got {observation_space}")
        if not (is_whole(buffer_size) and is_whole(n_envs)) or buffer_size < 1 or n_envs < 1:
            raise ValueError(f"buffer_size and n_envs must be whole numbers >= 1, got {buffer_size!r} and {n_envs!r}")
        obs_size = int(np.prod(observation_space.shape))
        n_params = ParameterizedActionSpec.from_space(action_space).n_params
        per_transition = obs_size * (1 if optimize_memory_usage else 2) + n_params + 4  # float32 / int64 fields
        check_allocation(f"The replay buffer (buffer_size={buffer_size:,})", max(buffer_size, n_envs) * per_transition, 4)
        if optimize_memory_usage and handle_timeout_termination:
            raise ValueError(
                "optimize_memory_usage=True and handle_timeout_termination=True cannot be combined: the memory-efficient "
                "buffer does not keep the terminal observation a truncated episode bootstraps from. Pass "
                "replay_buffer_kwargs=dict(handle_timeout_termination=False) or optimize_memory_usage=False"
            )
        self.spec = ParameterizedActionSpec.from_space(action_space)
        self.observation_space, self.action_space = observation_space, action_space
        self.n_envs = n_envs
        self.buffer_size = max(buffer_size // n_envs, 1)
        self.optimize_memory_usage = optimize_memory_usage
        self.handle_timeout_termination = handle_timeout_termination
        self.device = th.device(
            "cuda" if device == "auto" and th.cuda.is_available() else "cpu" if device == "auto" else device
        )
        self.pos, self.full = 0, False
        obs_shape, rows = observation_space.shape, (self.buffer_size, n_envs)
        self.observations = np.zeros((*rows, *obs_shape), dtype=np.float32)
        self.next_observations = None if optimize_memory_usage else np.zeros((*rows, *obs_shape), dtype=np.float32)
        self.action_types = np.zeros(rows, dtype=np.int64)
        self.params = np.zeros((*rows, self.spec.n_params), dtype=np.float32)
        self.rewards = np.zeros(rows, dtype=np.float32)
        self.dones = np.zeros(rows, dtype=np.float32)
        self.timeouts = np.zeros(rows, dtype=np.float32)

    def size(self) -> int:
        """Number of rows stored (each holds ``n_envs`` transitions)."""
        return self.buffer_size if self.full else self.pos

    def add(
        self,
        obs: np.ndarray,
        next_obs: np.ndarray,
        action_types: np.ndarray,
        params: np.ndarray,
        rewards: np.ndarray,
        dones: np.ndarray,
        truncated: np.ndarray,
    ) -> None:
        """
        Store one transition per environment.

        :param obs: ``(n_envs, *obs_shape)``
        :param next_obs: ``(n_envs, *obs_shape)``: the observation after the step (the terminal one where an episode
            ended, not the first of the next episode)
        :param action_types: ``(n_envs,)`` 0-based types
        :param params: ``(n_envs, n_params)`` scaled parameters as executed
        :param rewards: ``(n_envs,)``
        :param dones: ``(n_envs,)`` episode ended (terminated or truncated)
        :param truncated: ``(n_envs,)`` the episode ended by a time limit, not by termination
        """
        pos = self.pos
        self.observations[pos] = np.asarray(obs).reshape(self.observations.shape[1:])
        if self.next_observations is None:
            self.observations[(pos + 1) % self.buffer_size] = np.asarray(next_obs).reshape(self.observations.shape[1:])
        else:
            self.next_observations[pos] = np.asarray(next_obs).reshape(self.observations.shape[1:])
        self.action_types[pos] = action_types
        self.params[pos] = params
        self.rewards[pos] = rewards
        self.dones[pos] = dones
        self.timeouts[pos] = truncated
        self.pos = (pos + 1) % self.buffer_size
        self.full = self.full or self.pos == 0

    def sample(self, batch_size: int, rng: np.random.Generator) -> ParameterizedReplayBufferSamples:
        """
        Uniform minibatch (with replacement) over the stored transitions of all environments.

        :param batch_size: Number of transitions
        :param rng: Random generator for the indices (the algorithm's own, so reruns are reproducible)
        """
        if self.optimize_memory_usage and self.full:
            # Row `pos` (the oldest) had its observation overwritten by the newest next observation: leave it out.
            rows = (rng.integers(1, self.buffer_size, size=batch_size) + self.pos) % self.buffer_size
        else:
            rows = rng.integers(0, self.size(), size=batch_size)
        envs = rng.integers(0, self.n_envs, size=batch_size)
        if self.next_observations is None:
            next_obs = self.observations[(rows + 1) % self.buffer_size, envs]
        else:
            next_obs = self.next_observations[rows, envs]
        dones = self.dones[rows, envs]
        if self.handle_timeout_termination:
            dones = dones * (1.0 - self.timeouts[rows, envs])

        def tensor(array: np.ndarray) -> th.Tensor:
            return th.as_tensor(array, device=self.device)

        return ParameterizedReplayBufferSamples(
            observations=tensor(self.observations[rows, envs]),
            action_types=tensor(self.action_types[rows, envs]),
            params=tensor(self.params[rows, envs]),
            next_observations=tensor(next_obs),
            dones=tensor(dones),
            rewards=tensor(self.rewards[rows, envs]),
        )

    def check_spaces(self, observation_space: spaces.Space[Any], action_space: spaces.Space[Any], n_envs: int) -> None:
        """
        :raises ValueError: if this buffer was filled in other spaces or with another number of environments
        """
        if self.observation_space != observation_space or self.action_space != action_space:
            raise ValueError(
                f"The replay buffer holds transitions of observation space {self.observation_space} and action space "
                f"{self.action_space}, but the model has {observation_space} and {action_space}"
            )
        if self.n_envs != n_envs:
            raise ValueError(f"The replay buffer was filled by {self.n_envs} environments, but the model has {n_envs}")
