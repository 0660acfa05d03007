"""EpisodeKeywordsCallback (sb3_aac/common/episode_stats.py): SB3's own algorithms, trained through the action
wrappers, log ``rollout/ep_<key>_mean`` with the meaning this package's algorithms give it."""

from __future__ import annotations

import csv

import numpy as np
import pytest
from stable_baselines3 import DQN, PPO, TD3
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.logger import configure
from stable_baselines3.common.vec_env import SubprocVecEnv

from sb3_aac import DiscretizeParameterizedAction, FlattenParameterizedAction
from sb3_aac.common.envs import ParameterizedTargetEnv
from sb3_aac.common.episode_stats import EpisodeKeywordsCallback

KEYWORDS = ("distance", "ball_lost")
# Small and fast; every setting below dumps the logs several times within the budget.
SMALL = dict(policy_kwargs=dict(net_arch=[16]))
# algo: (class, wrapper, settings, log_interval)
SETTINGS = {
    "TD3": (TD3, FlattenParameterizedAction, dict(learning_starts=50, batch_size=16, **SMALL), 2),
    "PPO": (PPO, FlattenParameterizedAction, dict(n_steps=32, batch_size=32, n_epochs=1, **SMALL), 1),
    "DQN": (DQN, DiscretizeParameterizedAction, dict(learning_starts=50, batch_size=16, **SMALL), 2),
}
MEANS = ("rollout/ep_rew_mean", "rollout/ep_distance_mean", "rollout/ep_ball_lost_mean")


def dump_rows(folder) -> list[dict[str, str]]:
    with open(folder / "progress.csv", newline="") as f:
        return list(csv.DictReader(f))


def test_the_means_are_those_of_the_last_finished_episodes_that_reported_the_key():
    """Hand-checked: a window of 2 episodes; a lane that has not finished, and an episode without the key, add nothing."""
    model = PPO("MlpPolicy", make_vec_env(ParameterizedTargetEnv, 2, wrapper_class=FlattenParameterizedAction),
                stats_window_size=2)  # fmt: skip
    model.set_logger(configure(None, []))
    callback = EpisodeKeywordsCallback(KEYWORDS)
    callback.init_callback(model)
    values = model.logger.name_to_value
    steps = [
        ([True, False], [{"distance": 1.0, "ball_lost": True}, {"distance": 99.0, "ball_lost": True}]),
        ([False, False], [{"distance": 99.0}, {"distance": 99.0}]),
        ([True, True], [{"distance": 3.0, "ball_lost": False}, {"other": 1.0}]),
        ([False, True], [{"distance": 99.0}, {"distance": 5.0}]),
    ]
    logged = []
    for dones, infos in steps:
        callback.update_locals({"dones": np.array(dones), "infos": infos})
        callback.on_step()
        logged.append((values.get("rollout/ep_distance_mean"), values.get("rollout/ep_ball_lost_mean")))
    assert logged == [(1.0, 1.0), (1.0, 1.0), (2.0, 0.5), (4.0, 0.5)]
    assert list(callback.buffers["distance"]) == [3.0, 5.0] and list(callback.buffers["ball_lost"]) == [1.0, 0.0]


@pytest.mark.parametrize("algo", sorted(SETTINGS))
def test_sb3_algorithms_log_the_info_means_at_every_dump(tmp_path, algo):
    """ParameterizedTargetEnv's ``info["distance"]`` at an episode's last step is the episode's return, so at every
    dump ``ep_distance_mean`` must equal SB3's ``ep_rew_mean`` over the same episodes (Monitor rounds to 1e-6)."""
    cls, wrapper, kwargs, log_interval = SETTINGS[algo]
    env = make_vec_env(ParameterizedTargetEnv, n_envs=2, seed=0, wrapper_class=wrapper)
    model = cls("MlpPolicy", env, seed=0, stats_window_size=5, **kwargs)
    model.set_logger(configure(str(tmp_path), ["csv"]))
    model.learn(256, callback=EpisodeKeywordsCallback(KEYWORDS), log_interval=log_interval)
    rows = dump_rows(tmp_path)
    assert len(rows) >= 3
    for row in rows:
        assert len({bool(row[key]) for key in MEANS}) == 1  # all three or none
        if row["rollout/ep_rew_mean"]:
            assert float(row["rollout/ep_distance_mean"]) == pytest.approx(float(row["rollout/ep_rew_mean"]), abs=1e-5)
            assert 0.0 <= float(row["rollout/ep_ball_lost_mean"]) <= 1.0
    assert rows[-1]["rollout/ep_distance_mean"]


def test_on_a_subprocess_vec_env(tmp_path):
    env = make_vec_env(ParameterizedTargetEnv, n_envs=2, seed=0, wrapper_class=FlattenParameterizedAction,
                       vec_env_cls=SubprocVecEnv, vec_env_kwargs={"start_method": "fork"})  # fmt: skip
    cls, _, kwargs, _ = SETTINGS["PPO"]
    model = cls("MlpPolicy", env, seed=0, stats_window_size=5, **kwargs)
    model.set_logger(configure(str(tmp_path), ["csv"]))
    try:
        model.learn(128, callback=EpisodeKeywordsCallback(("distance",)))
    finally:
        env.close()
    rows = [row for row in dump_rows(tmp_path) if row["rollout/ep_rew_mean"]]
    assert rows and "rollout/ep_ball_lost_mean" not in rows[0]
    for row in rows:
        assert float(row["rollout/ep_distance_mean"]) == pytest.approx(float(row["rollout/ep_rew_mean"]), abs=1e-5)


def test_the_windows_are_emptied_when_learn_resets_the_timestep_count():
    """As SB3's ``ep_info_buffer``: TD3 counts its episodes in ``_episode_num``, which a ``learn`` that resets the
    timestep count resets too, so the (never full) window holds ``_episode_num`` values after every ``learn``."""
    cls, wrapper, kwargs, _ = SETTINGS["TD3"]
    model = cls("MlpPolicy", make_vec_env(ParameterizedTargetEnv, 1, seed=0, wrapper_class=wrapper), seed=0,
                stats_window_size=1000, **kwargs)  # fmt: skip
    callback = EpisodeKeywordsCallback(("distance",))
    held = []
    for reset in (True, False, True):
        model.learn(40, callback=callback, reset_num_timesteps=reset)
        held.append((len(callback.buffers["distance"]), model._episode_num))
    assert [n for n, _ in held] == [episodes for _, episodes in held]
    assert held[0][0] < held[1][0] and held[2][0] < held[1][0], held  # kept by the second learn, not by the third


@pytest.mark.parametrize("info_keywords", ["distance", ("distance", 3), None])
def test_bad_info_keywords(info_keywords):
    with pytest.raises(ValueError, match=r"info_keywords must be a tuple of info keys \(str\)"):
        EpisodeKeywordsCallback(info_keywords)
