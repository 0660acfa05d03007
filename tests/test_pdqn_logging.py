"""Callbacks and TensorBoard keys of P-DQN / MP-DQN (SB3's test_callbacks / test_tensorboard shapes)."""

import os

import pytest
from stable_baselines3.common.callbacks import (
    BaseCallback,
    CallbackList,
    CheckpointCallback,
    EvalCallback,
    StopTrainingOnMaxEpisodes,
    StopTrainingOnRewardThreshold,
)
from stable_baselines3.common.env_util import make_vec_env
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from sb3_aac import MPDQN, PDQN
from sb3_aac.common.envs import ParameterizedTargetEnv

SMALL = dict(learning_starts=50, batch_size=16, policy_kwargs=dict(net_arch=[16]))


class LocalsCheck(BaseCallback):
    def _on_step(self) -> bool:
        for name in ("new_obs", "rewards", "dones", "infos", "actions", "k", "params"):
            assert name in self.locals, name
        assert self.locals["actions"].dtype == object and self.locals["params"].shape[1] == 5
        return True


@pytest.mark.parametrize("algo", [PDQN, MPDQN])
def test_callbacks(tmp_path, algo):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=2)
    model = algo("MlpPolicy", env, seed=0, **SMALL)
    checkpoint = CheckpointCallback(save_freq=50, save_path=str(tmp_path), name_prefix="m", save_replay_buffer=True)
    evaluation = EvalCallback(
        make_vec_env(ParameterizedTargetEnv),
        callback_on_new_best=StopTrainingOnRewardThreshold(1e9),
        eval_freq=50,
        n_eval_episodes=2,
        best_model_save_path=str(tmp_path),
    )
    model.learn(200, callback=CallbackList([checkpoint, evaluation, LocalsCheck()]))
    assert os.path.isfile(tmp_path / "m_200_steps.zip") and os.path.isfile(tmp_path / "m_replay_buffer_200_steps.pkl")
    assert os.path.isfile(tmp_path / "best_model.zip") and evaluation.last_mean_reward > 0
    algo.load(tmp_path / "best_model.zip").load_replay_buffer(tmp_path / "m_replay_buffer_200_steps.pkl")


def test_stop_training_on_max_episodes():
    model = PDQN("MlpPolicy", ParameterizedTargetEnv(max_episode_steps=5, loss_threshold=0.0), seed=0, **SMALL)
    model.learn(10_000, callback=StopTrainingOnMaxEpisodes(max_episodes=3))
    assert model.num_timesteps == 15  # stopped at the step that ended the third episode


@pytest.mark.parametrize("algo", [PDQN, MPDQN])
def test_tensorboard(tmp_path, algo):
    name = algo.__name__
    model = algo("MlpPolicy", ParameterizedTargetEnv(), tensorboard_log=str(tmp_path), seed=0, **SMALL)
    model.learn(300, log_interval=2)
    model.learn(300, log_interval=2, reset_num_timesteps=False)
    assert os.path.isdir(tmp_path / f"{name}_1") and not os.path.isdir(tmp_path / f"{name}_2")
    events = EventAccumulator(str(tmp_path / f"{name}_1"))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    for tag in (
        "rollout/ep_rew_mean",
        "rollout/ep_len_mean",
        "rollout/ep_distance_mean",
        "rollout/ep_ball_lost_mean",
        "rollout/exploration_rate",
        "train/critic_loss",
        "train/actor_loss",
        "train/learning_rate",
        "train/actor_learning_rate",
        "time/fps",
    ):
        assert tag in tags, tag
    steps = [event.step for event in events.Scalars("rollout/ep_distance_mean")]
    assert steps == sorted(steps) and steps[-1] > 300
    epsilons = [event.value for event in events.Scalars("rollout/exploration_rate")]
    assert epsilons[0] > epsilons[-1]


def test_info_keywords_chosen(tmp_path):
    model = PDQN("MlpPolicy", ParameterizedTargetEnv(), info_keywords=("distance",), tensorboard_log=str(tmp_path), **SMALL)
    model.learn(200, log_interval=1, tb_log_name="run")
    events = EventAccumulator(str(tmp_path / "run_1"))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    assert "rollout/ep_distance_mean" in tags and "rollout/ep_ball_lost_mean" not in tags
