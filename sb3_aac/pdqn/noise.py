"""Exploration noise on the scaled action parameters, one independent process per environment."""

from __future__ import annotations

import numpy as np

PARAM_NOISES = ("gaussian", "ornstein_uhlenbeck")


class ParamNoise:
    """
    Gaussian or Ornstein-Uhlenbeck noise of shape ``(n_envs, n_params)``, drawn from a given generator.

    - ``"gaussian"``: independent ``N(0, std^2)`` each step.
    - ``"ornstein_uhlenbeck"``: ``z <- z - theta * z + std * N(0, 1)`` (mean 0, time step 1), started at 0 and reset
      to 0 where an episode ends. The reference MP-DQN code uses ``theta = 0.15`` with a very small ``std``.

    :param kind: ``"gaussian"`` or ``"ornstein_uhlenbeck"``
    :param shape: ``(n_envs, n_params)``
    :param std: Standard deviation of the Gaussian increments
    :param theta: Mean reversion of the Ornstein-Uhlenbeck process
    """

    def __init__(self, kind: str, shape: tuple[int, int], std: float, theta: float = 0.15):
        if kind not in PARAM_NOISES:
            raise ValueError(f"Unknown param_noise {kind!r}, valid values: {list(PARAM_NOISES)} or None")
        if not std >= 0 or not 0 <= theta <= 1:
            raise ValueError(f"Noise std must be >= 0 and theta in [0, 1], got std={std}, theta={theta}")
        self.kind, self.std, self.theta = kind, std, theta
        self.state: np.ndarray = np.zeros(shape)

    def __call__(self, rng: np.random.Generator) -> np.ndarray:
        """The next noise sample ``(n_envs, n_params)``."""
        increment: np.ndarray = self.std * rng.standard_normal(self.state.shape)
        if self.kind == "gaussian":
            return increment
        self.state += increment - self.theta * self.state
        sample: np.ndarray = self.state.copy()
        return sample

    def reset(self, done: np.ndarray) -> None:
        """Restart the process of the environments where ``done`` (``(n_envs,)`` bool) is set."""
        self.state[done] = 0.0
