"""The observation checks shared by every policy and algorithm of this package."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

# The largest observation magnitude the networks can take: their float32 inputs hold up to this, beyond it is inf.
MAX_OBSERVATION_MAGNITUDE = float(np.finfo(np.float32).max)


def check_box_observation_space(observation_space: spaces.Space[Any], policies: str) -> None:
    """
    Refuse an observation space that is not a ``Box``: the policies of this package take flat observation vectors.

    :param observation_space: the env's observation space
    :param policies: who refuses it, for the message (``"P-DQN policies"``)
    :raises ValueError: naming the space and what to do, unless it is a ``Box``
    """
    if not isinstance(observation_space, spaces.Box):
        raise ValueError(
            f"Unsupported observation space {observation_space}: {policies} take a Box observation "
            "(flatten Dict/Tuple observations first, e.g. with gymnasium.wrappers.FlattenObservation)"
        )


def observation_batch(observation: Any, observation_space: spaces.Space[Any]) -> tuple[np.ndarray, bool]:
    """
    ``observation`` as a float64 batch ``(n, *obs_shape)``, and whether it was a batch already.

    One observation of ``observation_space.shape`` becomes a batch of one; an array of shape ``(n, *obs_shape)`` is
    a batch of ``n``. The values are unchanged (float32 observations convert to float64 exactly).

    :param observation: one observation or a batch, anything ``numpy.asarray`` takes
    :param observation_space: the ``Box`` space the observations belong to
    :raises ValueError: for a space without a shape, a wrong observation shape, an empty batch (0 observations),
        complex numbers, NaN or inf values, or finite values beyond :data:`MAX_OBSERVATION_MAGNITUDE`
    """
    if np.iscomplexobj(observation):
        raise ValueError(f"The observation holds complex numbers: observations are real ({observation_space})")
    obs = np.asarray(observation, dtype=np.float64)
    shape = observation_space.shape
    if shape is None:
        raise ValueError(f"The observation space {observation_space} has no shape; the policy needs a Box")
    if obs.shape == shape or obs.shape[1:] == shape:
        if obs.size == 0 and obs.shape != shape:
            raise ValueError(f"Got an empty batch of shape {obs.shape}: predict needs at least one observation")
        if not np.isfinite(obs).all():
            raise ValueError(f"The observation holds NaN or inf values: {observation}")
        if obs.size and np.abs(obs).max() > MAX_OBSERVATION_MAGNITUDE:
            raise ValueError(
                f"The observation holds values beyond float32's range (|x| > {MAX_OBSERVATION_MAGNITUDE:.3g}), which the "
                f"networks cannot take: {observation}"
            )
        return (obs.reshape(1, *shape), False) if obs.shape == shape else (obs, True)
    raise ValueError(
        f"Error: Unexpected observation shape {obs.shape} for Box environment, "
        f"please use {shape} or (n_env, {', '.join(map(str, shape))}) for the observation shape."
    )
