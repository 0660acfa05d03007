"""HybridPPO's features extractor: the observation flattened and scaled by the observation space's bounds."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch as th
from gymnasium import spaces
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor


class BoundsScaledFlatten(BaseFeaturesExtractor):
    """
    Flatten a ``Box`` observation and map every coordinate with finite bounds affinely from ``[low, high]`` to
    ``[-1, 1]``; coordinates with an infinite (or degenerate) bound pass unchanged.

    Env observation spaces often have narrow ranges (the dribbling env's lie within widths of 0.002 to 7), which a
    network with default initialisation barely tells apart; scaled inputs make the defaults work across envs.

    :param observation_space: A ``Box`` observation space (any shape)
    """

    obs_mid: th.Tensor
    obs_half: th.Tensor

    def __init__(self, observation_space: spaces.Space[Any]):
        if not isinstance(observation_space, spaces.Box):
            raise ValueError(
                f"BoundsScaledFlatten takes a Box observation space, got {observation_space} (use SB3's "
                "FlattenExtractor or CombinedExtractor as features_extractor_class for other spaces)"
            )
        super().__init__(observation_space, int(np.prod(observation_space.shape)))
        low = np.asarray(observation_space.low, dtype=np.float64).ravel()
        high = np.asarray(observation_space.high, dtype=np.float64).ravel()
        finite = np.isfinite(low) & np.isfinite(high) & (high > low)
        self.register_buffer("obs_mid", th.as_tensor(np.where(finite, (high + low) / 2, 0.0), dtype=th.float32))
        self.register_buffer("obs_half", th.as_tensor(np.where(finite, (high - low) / 2, 1.0), dtype=th.float32))

    def forward(self, observations: th.Tensor) -> th.Tensor:
        return (observations.reshape(len(observations), -1).float() - self.obs_mid) / self.obs_half
