"""The lane count buys wall time, not a different learning curve per env step (sb3_aac.sarsa_aac.lane_steps)."""

import pytest
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

from sb3_aac import SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv

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
