"""The lane count buys wall time, not a different learning curve per env step (sb3_aac.sarsa_aac.lane_steps), and
where lanes are split into chunks."""

import itertools
from typing import Any

import numpy as np
import pytest
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

from sb3_aac import SarsaAAC
from sb3_aac.common.envs import NavigationEnv, ParameterizedTargetEnv
from sb3_aac.sarsa_aac.lane_steps import LANE_CHUNK

STEPS, CHECKPOINTS = 16_000, (8_000, 16_000)
# The toy env's short runs want bolder steps than the defaults (as in test_sarsa_aac_learning).
HYPERPARAMETERS = dict(learning_rate=0.3, q_learning_rate=0.3, param_learning_rate=0.3, param_noise_initial=0.5)


class Curve(BaseCallback):
    """The greedy return (30 fixed episodes) at each checkpoint of env steps."""

    def __init__(self) -> None:
        super().__init__()
        self.points: list[float] = []

    def _on_step(self) -> bool:
        if len(self.points) < len(CHECKPOINTS) and self.num_timesteps >= CHECKPOINTS[len(self.points)]:
            env = make_vec_env(ParameterizedTargetEnv, n_envs=1, seed=100)
            self.points.append(evaluate_policy(self.model, env, n_eval_episodes=30, deterministic=True)[0])
        return True


def curve(policy: str, n_envs: int) -> list[float]:
    model = SarsaAAC(policy, make_vec_env(ParameterizedTargetEnv, n_envs=n_envs, seed=0), seed=0, **HYPERPARAMETERS)
    watch = Curve()
    model.learn(STEPS, callback=watch)
    return watch.points


@pytest.mark.parametrize("policy", ["TilePolicy", "RbfPolicy"])
def test_same_curve_per_env_step_on_1_16_and_64_lanes(policy):
    """Each point of the 16- and 64-lane curves is within 1.0 (of a return of 10) of the one-lane curve's, and all
    learn the task (the earlier rule, the lanes' summed steps divided by their overlap, left 64 lanes far behind)."""
    one = curve(policy, 1)
    assert one[-1] >= 8.5
    for n_envs in (16, 64):
        points = curve(policy, n_envs)
        assert max(abs(a - b) for a, b in zip(points, one, strict=True)) <= 1.0, (n_envs, points, one)


# ---------------------------------------------------------------------------------------------------------------------
# Chunks of lanes: where every weight moves with every sample, at most LANE_CHUNK lanes' errors on the same weights
# ---------------------------------------------------------------------------------------------------------------------

CHUNKED = [("DeepPolicy", {}), ("DeepPolicy", {"trace_lambda": 0.8}), ("MlpPolicy", {}), ("RbfMlpPolicy", {})]


@pytest.mark.parametrize(("policy", "kwargs"), CHUNKED)
def test_lanes_beyond_a_chunk_are_updated_chunk_after_chunk(policy: str, kwargs: dict, monkeypatch) -> None:
    """
    With hidden layers and more than LANE_CHUNK lanes, each chunk's errors are measured on the weights the earlier
    chunks' steps left: one forward pass per chunk (its s and s' rows), each after the previous chunk's update.
    """
    n = 2 * LANE_CHUNK + 3
    model = lane_model(policy, n, **kwargs)
    assert model.policy.chunks_lanes
    model.learn(5 * n)  # past the first steps (the return scale is set)
    calls = forward_calls(monkeypatch, model)
    model.learn(n, reset_num_timesteps=False)
    assert [rows for rows, _ in calls] == [2 * LANE_CHUNK, 2 * LANE_CHUNK, 2 * 3]
    weights = [w for _, w in calls] + [model.policy.parameters_to_vector()]
    assert all(not np.array_equal(before, after) for before, after in itertools.pairwise(weights))


@pytest.mark.parametrize(
    ("policy", "n_envs"), [("DeepPolicy", LANE_CHUNK), ("MlpPolicy", LANE_CHUNK), ("TilePolicy", 40), ("RbfPolicy", 40)]
)
def test_a_chunk_of_lanes_or_linear_heads_take_one_forward_pass(policy: str, n_envs: int, monkeypatch) -> None:
    """Up to LANE_CHUNK lanes, and any number of lanes of linear heads, are updated together: one forward pass of s
    and s' per env step."""
    model = lane_model(policy, n_envs)
    assert model.policy.chunks_lanes == (policy in ("DeepPolicy", "MlpPolicy"))
    model.learn(2 * n_envs)
    calls = forward_calls(monkeypatch, model)
    model.learn(n_envs, reset_num_timesteps=False)
    assert [rows for rows, _ in calls] == [2 * n_envs]


def lane_model(policy: str, n_envs: int, **kwargs: Any) -> SarsaAAC:
    """A model of ``n_envs`` navigation lanes without replay (whose forward passes would come after the chunks')."""
    return SarsaAAC(policy, make_vec_env(NavigationEnv, n_envs=n_envs, seed=0), seed=0, replay_ratio=0, **kwargs)


def forward_calls(monkeypatch: pytest.MonkeyPatch, model: SarsaAAC) -> list[tuple[int, np.ndarray]]:
    """From now on, every training forward pass's number of rows and the policy's weights when it ran."""
    calls: list[tuple[int, np.ndarray]] = []
    kernel_class = type(model.policy.kernel())
    forward = kernel_class.forward

    def spy(kernel: Any, obs: np.ndarray) -> tuple[np.ndarray, object]:
        calls.append((len(obs), model.policy.parameters_to_vector()))
        return forward(kernel, obs)

    monkeypatch.setattr(kernel_class, "forward", spy)
    return calls
