"""The abstract SarsaAACPolicy is the whole contract: a family written as one subclass trains, predicts and saves."""

from typing import Any

import numpy as np
import pytest
import torch as th
from torch import nn

from sb3_aac import SarsaAAC, SarsaAACPolicy
from sb3_aac.common.envs import ParameterizedTargetEnv


class LinearKernel:
    """Normalised LMS on the scaled inputs, on views of the policy's weights (the cache is the inputs)."""

    def __init__(self, policy: "LinearPolicy"):
        self.w, self.b = policy.weight.detach().numpy(), policy.bias.detach().numpy()
        self.mid, self.half = policy.mid, policy.half

    def forward(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x = (obs - self.mid) / self.half
        return x @ self.w.T + self.b, x

    def update(self, cache: np.ndarray, err: np.ndarray, lr: np.ndarray, hidden_gain: np.ndarray | None = None) -> None:
        x = cache[: len(err)]
        step = err * lr / (1.0 + (x * x).sum(1, keepdims=True)) / len(err)
        self.w += step.T @ x
        self.b += step.sum(0)


class LinearPolicy(SarsaAACPolicy):
    """A family that is not a numpy bank: one linear map per output, weights in two torch parameters."""

    def __init__(self, observation_space: Any, action_space: Any, obs_bounds: Any = None):
        super().__init__(observation_space, action_space, obs_bounds)
        low, high = self.input_bounds()
        self.mid, self.half = (high + low) / 2, (high - low) / 2
        self.weight = nn.Parameter(th.zeros((self.n_outputs, len(low)), dtype=th.float64), requires_grad=False)
        self.bias = nn.Parameter(th.zeros(self.n_outputs, dtype=th.float64), requires_grad=False)
        self._kernel: LinearKernel | None = None

    def evaluate(self, obs: np.ndarray) -> tuple[np.ndarray, Any]:
        return self.kernel().forward(obs.reshape(len(obs), -1))

    def kernel(self) -> LinearKernel:
        if self._kernel is None:
            self._kernel = LinearKernel(self)
        return self._kernel

    def rebind(self) -> LinearKernel:
        self._kernel = None
        return self.kernel()

    def scale_outputs(self, columns: list[int], factor: float) -> None:
        with th.no_grad():
            self.weight[columns] *= factor
            self.bias[columns] *= factor

    def finite_outputs(self) -> np.ndarray:
        return np.isfinite(self.weight.detach().numpy()).all(1) & np.isfinite(self.bias.detach().numpy())

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return dict(observation_space=self.observation_space, action_space=self.action_space, obs_bounds=self.obs_bounds)


def test_the_abstract_policy_builds_nothing():
    env = ParameterizedTargetEnv()
    with pytest.raises(TypeError, match="abstract"):
        SarsaAACPolicy(env.observation_space, env.action_space)  # type: ignore[abstract]


def test_a_family_is_one_subclass(tmp_path):
    env = ParameterizedTargetEnv()
    model = SarsaAAC(LinearPolicy, env, seed=0)
    model.learn(1_000)
    weights = model.policy.weight.detach().numpy()
    assert np.isfinite(weights).all() and np.abs(weights).max() > 0  # it learned, with return-scaled values
    assert model.return_scale > 0
    obs = np.stack([env.observation_space.sample() for _ in range(8)])
    actions, _ = model.predict(obs, deterministic=True)
    assert all(env.action_space.contains(a) for a in actions)
    model.save(tmp_path / "model.zip")
    loaded = SarsaAAC.load(tmp_path / "model.zip")
    assert isinstance(loaded.policy, LinearPolicy)
    assert repr(loaded.predict(obs, deterministic=True)[0]) == repr(actions)
