"""SarsaAAC's own callback and logging behaviour (cadence, stopping, dump keys); what every algorithm does alike is
in test_logging.py."""

import csv
from itertools import pairwise

import pytest
from stable_baselines3.common.callbacks import (
    BaseCallback,
    EvalCallback,
    StopTrainingOnMaxEpisodes,
    StopTrainingOnNoModelImprovement,
)
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.logger import configure

from sb3_aac import SarsaAAC
from sb3_aac.common.envs import ParameterizedTargetEnv


class Counter(BaseCallback):
    def _on_step(self) -> bool:
        return True


def test_no_model_improvement_and_max_episodes():
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), seed=0)
    stop = StopTrainingOnNoModelImprovement(max_no_improvement_evals=1, min_evals=1)
    eval_callback = EvalCallback(make_vec_env(ParameterizedTargetEnv, n_envs=1), eval_freq=50, callback_after_eval=stop)
    model.learn(100_000, callback=eval_callback)
    assert model.num_timesteps < 100_000

    model = SarsaAAC("RbfPolicy", make_vec_env(ParameterizedTargetEnv, n_envs=2, seed=0), seed=0)
    model.learn(100_000, callback=StopTrainingOnMaxEpisodes(max_episodes=5))
    assert model.num_timesteps < 100_000
    assert model.episode_num >= 5


def test_function_callback_and_n_calls():
    calls = []

    def callback(_locals, _globals):
        calls.append(_locals["self"].num_timesteps)
        return len(calls) < 30

    model = SarsaAAC("RbfPolicy", make_vec_env(ParameterizedTargetEnv, n_envs=2, seed=0), seed=0)
    model.learn(1000, callback=callback)
    assert calls == list(range(2, 62, 2))
    counter = Counter()
    model.learn(100, callback=counter)
    assert counter.n_calls * 2 == model.num_timesteps == 100


def test_progress_bar():
    SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), seed=0).learn(100, progress_bar=True)


def test_dump_logs_keys(tmp_path):
    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), seed=0, log_min_timesteps=0)
    model.set_logger(configure(str(tmp_path), ["csv"]))
    model.learn(400, log_interval=5)
    model.dump_logs()  # no arguments, as LogEveryNTimesteps calls it
    rows = (tmp_path / "progress.csv").read_text().splitlines()
    header = rows[0].split(",")
    for key in (
        "rollout/ep_rew_mean",
        "rollout/ep_len_mean",
        "rollout/exploration_rate",
        "rollout/ep_distance_mean",
        "rollout/ep_ball_lost_mean",
        "rollout/type_freq_0",
        "rollout/type_freq_2",
        "train/td_error_mean",
        "train/td_error_abs_mean",
        "train/critic_loss",
        "train/q_loss",
        "train/param_update_fraction",
        "train/param_noise",
        "train/learning_rate",
        "train/q_learning_rate",
        "train/param_learning_rate",
        "time/fps",
        "time/total_timesteps",
        "time/episodes",
    ):
        assert key in header, key
    first = dict(zip(header, rows[1].split(","), strict=True))
    freqs = [float(first[f"rollout/type_freq_{k}"]) for k in range(3)]
    assert sum(freqs) == pytest.approx(1.0)
    assert 0.0 <= float(first["train/param_update_fraction"]) <= 1.0
    assert 0.0 <= float(first["rollout/ep_ball_lost_mean"]) <= 1.0


def test_stopping_keeps_the_latest_observation():
    """A callback that stops training skips that step's update; the next learn() continues from new_obs."""
    seen = {}

    def stop_at_three(_locals, _globals):
        seen["new_obs"] = _locals["new_obs"]
        return _locals["self"].num_timesteps < 3

    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), seed=0)
    model.learn(100, callback=stop_at_three)
    assert model.num_timesteps == 3 and model._n_updates == 2
    assert model._last_obs is seen["new_obs"]
    model.learn(10, reset_num_timesteps=False)
    assert model.num_timesteps == 13 and model._n_updates == 12


@pytest.mark.parametrize(("log_min_timesteps", "n_envs"), [(0, 1), (0, 16), (500, 16), (2000, 1)])
def test_logs_are_dumped_by_episodes_and_timesteps(tmp_path, log_min_timesteps: int, n_envs: int):
    """The first dump comes after log_interval episodes; each later one needs log_interval more episodes and
    log_min_timesteps more env steps than the previous one; learn ends with a dump."""
    env = make_vec_env(ParameterizedTargetEnv, n_envs=n_envs, seed=0)
    model = SarsaAAC("RbfPolicy", env, seed=0, log_min_timesteps=log_min_timesteps)
    model.set_logger(configure(str(tmp_path), ["csv"]))
    model.learn(4000, log_interval=3)
    rows = list(csv.DictReader((tmp_path / "progress.csv").open()))
    steps = [int(row["time/total_timesteps"]) for row in rows]
    episodes = [int(row["time/episodes"]) for row in rows]
    assert len(rows) >= 2 and episodes[0] >= 3 and steps[-1] == model.num_timesteps
    spaced = list(pairwise(steps[:-1]))  # the last dump is the end of learn's
    assert all(b - a >= max(log_min_timesteps, 1) for a, b in spaced)
    assert all(b - a >= 3 for a, b in pairwise(episodes[:-1]))
    if log_min_timesteps:
        assert steps[0] < log_min_timesteps  # the first dump does not wait for the spacing
        assert len(rows) <= 4000 // log_min_timesteps + 2
    else:  # SB3's cadence: at the first step at which 3 more episodes have ended
        assert len(rows) >= 20
