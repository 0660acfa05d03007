"""P-DQN / MP-DQN's own callback locals and replay-buffer checkpoints; what every algorithm logs alike is in
test_logging.py."""

import os

import pytest
from stable_baselines3.common.callbacks import (
    BaseCallback,
    CallbackList,
    CheckpointCallback,
    EvalCallback,
    StopTrainingOnRewardThreshold,
)
from stable_baselines3.common.env_util import make_vec_env

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
