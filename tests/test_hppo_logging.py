"""HybridPPO's own callback locals and log dumps (what every algorithm shows and logs is tests/test_logging.py's)."""

import csv

from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.logger import configure

from sb3_aac import HybridPPO
from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import HPPO_SMALL


class LocalsCheck(BaseCallback):
    """The locals HybridPPO adds: the executed type and clipped scaled parameters, and the sampled packed rows."""

    def _on_step(self) -> bool:
        k, params, packed = self.locals["k"], self.locals["params"], self.locals["packed"]
        assert k.shape == (2,) and params.shape == (2, 5) and packed.shape == (2, 6)
        assert (k == packed[:, 0]).all() and (abs(params) <= 1).all()
        return True


def test_callback_locals_and_progress_bar():
    model = HybridPPO("MlpPolicy", make_vec_env(ParameterizedTargetEnv, n_envs=2), seed=0, **HPPO_SMALL)
    model.learn(64, callback=LocalsCheck(), progress_bar=True)
    assert model.num_timesteps == 64


def test_each_dump_follows_its_rollouts_update(tmp_path):
    """A dump's train/ keys are of the update on the rollouts it reports (SB3's PPO dumps before the update: its first
    dump has none, and a learn's last update waits for the next learn); log_interval counts rollouts; the run ends
    with a dump of the rollouts since the previous one."""
    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(), seed=0, **HPPO_SMALL)  # 16 steps a rollout
    model.set_logger(configure(str(tmp_path), ["csv"]))
    model.learn(80, log_interval=2)  # 5 rollouts: dumps after the 2nd, the 4th and (the end) the 5th
    rows = list(csv.DictReader((tmp_path / "progress.csv").open()))
    assert [int(row["time/total_timesteps"]) for row in rows] == [32, 64, 80]
    assert [int(row["time/iterations"]) for row in rows] == [2, 4, 5]
    assert [int(row["train/n_updates"]) for row in rows] == [4, 8, 10]  # n_epochs = 2 per update
    assert all(row["train/policy_loss_discrete"] and row["rollout/type_freq_0"] for row in rows)
