"""Callbacks, TensorBoard keys and the progress bar of HybridPPO (SB3's test_callbacks / test_tensorboard shapes)."""

import os

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

from sb3_aac import HybridPPO
from sb3_aac.common.envs import ParameterizedTargetEnv

SMALL = dict(n_steps=32, batch_size=32, n_epochs=2, policy_kwargs=dict(net_arch=[16]))


class LocalsCheck(BaseCallback):
    def _on_step(self) -> bool:
        for name in ("new_obs", "rewards", "dones", "infos", "actions", "k", "params", "packed"):
            assert name in self.locals, name
        assert self.locals["actions"].dtype == object and len(self.locals["infos"]) == 2
        assert self.locals["packed"].shape == (2, 6) and self.locals["params"].shape == (2, 5)
        return True


def test_callbacks(tmp_path):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=2)
    model = HybridPPO("MlpPolicy", env, seed=0, **SMALL)
    checkpoint = CheckpointCallback(save_freq=32, save_path=str(tmp_path), name_prefix="m")
    evaluation = EvalCallback(
        make_vec_env(ParameterizedTargetEnv),
        callback_on_new_best=StopTrainingOnRewardThreshold(1e9),
        eval_freq=32,
        n_eval_episodes=2,
        best_model_save_path=str(tmp_path),
    )
    model.learn(128, callback=CallbackList([checkpoint, evaluation, LocalsCheck()]), progress_bar=True)
    assert os.path.isfile(tmp_path / "m_128_steps.zip") and os.path.isfile(tmp_path / "best_model.zip")
    assert evaluation.last_mean_reward > 0
    HybridPPO.load(tmp_path / "best_model.zip")


def test_stop_training_on_max_episodes():
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(max_episode_steps=5, loss_threshold=0.0), seed=0, **SMALL)
    model.learn(10_000, callback=StopTrainingOnMaxEpisodes(max_episodes=3))
    assert model.num_timesteps == 15  # stopped at the step that ended the third episode


def test_tensorboard(tmp_path):
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(), tensorboard_log=str(tmp_path), seed=0, **SMALL)
    model.learn(64)
    model.learn(64, reset_num_timesteps=False)
    assert os.path.isdir(tmp_path / "HybridPPO_1") and not os.path.isdir(tmp_path / "HybridPPO_2")
    events = EventAccumulator(str(tmp_path / "HybridPPO_1"))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    for tag in (
        "rollout/ep_rew_mean",
        "rollout/ep_len_mean",
        "rollout/type_freq_0",
        "rollout/type_freq_2",
        "rollout/param_mean_1_1",
        "rollout/ep_distance_mean",
        "train/value_mean",
        "train/policy_loss_discrete",
        "train/policy_loss_params",
        "train/clip_fraction_discrete",
        "train/clip_fraction_params",
        "train/entropy_discrete",
        "train/entropy_params",
        "train/value_loss",
        "train/approx_kl",
        "train/explained_variance",
        "train/std",
        "train/clip_range",
        "train/clip_range_params",
        "train/learning_rate",
        "time/fps",
    ):
        assert tag in tags, tag
    shares = [sum(events.Scalars(f"rollout/type_freq_{k}")[-1].value for k in range(3))]
    assert abs(shares[0] - 1.0) < 1e-6
    assert events.Scalars("train/value_loss")[-1].step == 128
