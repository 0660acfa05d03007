import os

from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from sb3_aac import SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv


def test_tensorboard(tmp_path):
    logname = "SarsaAAC"
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), tensorboard_log=str(tmp_path), seed=0, log_min_timesteps=0)
    model.learn(300, log_interval=2)
    model.learn(300, log_interval=2, reset_num_timesteps=False)
    assert os.path.isdir(tmp_path / f"{logname}_1")
    assert not os.path.isdir(tmp_path / f"{logname}_2")  # reset_num_timesteps=False continues the run

    events = EventAccumulator(str(tmp_path / f"{logname}_1"))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    for tag in (
        "rollout/ep_distance_mean",
        "rollout/ep_ball_lost_mean",
        "rollout/ep_rew_mean",
        "rollout/exploration_rate",
        "rollout/type_freq_1",
        "train/td_error_abs_mean",
        "train/critic_loss",
        "train/q_loss",
        "train/param_update_fraction",
        "train/param_noise",
        "time/fps",
    ):
        assert tag in tags, tag
    steps = [event.step for event in events.Scalars("rollout/ep_distance_mean")]
    assert steps == sorted(steps) and steps[-1] > 300  # the second learn() logged into the same run
    for event in events.Scalars("rollout/ep_ball_lost_mean"):
        assert 0.0 <= event.value <= 1.0


def test_custom_tb_log_name(tmp_path):
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), tensorboard_log=str(tmp_path), seed=0)
    model.learn(100, tb_log_name="other")
    model.learn(100, tb_log_name="other")
    assert os.path.isdir(tmp_path / "other_1") and os.path.isdir(tmp_path / "other_2")


def test_custom_info_keywords(tmp_path):
    env = ParameterizedTargetEnv()
    model = SarsaAAC("RbfPolicy", env, info_keywords=("distance",), tensorboard_log=str(tmp_path), log_min_timesteps=0)
    model.learn(200, log_interval=1)
    events = EventAccumulator(str(tmp_path / "SarsaAAC_1"))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    assert "rollout/ep_distance_mean" in tags and "rollout/ep_ball_lost_mean" not in tags
