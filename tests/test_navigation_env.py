"""NavigationEnv: Gymnasium's checks, its geometry, and bad arguments."""

import math

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from sb3_aac.common.envs import NavigationEnv


def test_gymnasium_checks():
    check_env(NavigationEnv(), skip_render_check=True)


def test_turn_then_move_reaches_the_target():
    env = NavigationEnv()
    for seed in range(20):
        obs, _ = env.reset(seed=seed)
        offset = 2 * obs[:2].astype(np.float64)
        turn = np.array([math.atan2(offset[1], offset[0])], np.float32)
        obs, reward, terminated, _, info = env.step((0, (turn, np.zeros(1, np.float32))))
        assert not terminated and reward == pytest.approx(-0.01)
        assert obs[2:] == pytest.approx([offset[0] / np.hypot(*offset), offset[1] / np.hypot(*offset)], abs=1e-6)
        distance = float(np.hypot(*offset))
        while not terminated:  # farther than one move: keep going straight
            move = np.array([min(distance, 1.0)], np.float32)
            obs, reward, terminated, truncated, info = env.step((1, (np.zeros(1, np.float32), move)))
            distance = info["distance"]
            assert not truncated
        assert info["is_success"] and reward > 1.0


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(max_episode_steps=0), "max_episode_steps must be an int >= 1"),
        (dict(radius=-1.0), "radius must be a finite number > 0"),
        (dict(step_cost=float("nan")), "step_cost must be a finite number"),
    ],
)
def test_bad_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        NavigationEnv(**kwargs)


def test_bad_actions():
    env = NavigationEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="Action type must be 0"):
        env.step((2, (np.zeros(1), np.zeros(1))))
    with pytest.raises(ValueError, match="must be finite"):
        env.step((1, (np.zeros(1), np.array([np.nan]))))
