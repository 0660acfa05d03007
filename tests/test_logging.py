"""Logging and callbacks of every algorithm (SB3's test_tensorboard / test_callbacks shapes), over tests.helpers.ALGOS."""

import os

import numpy as np
import pytest
import torch as th
from stable_baselines3.common.callbacks import (
    BaseCallback,
    CallbackList,
    CheckpointCallback,
    EvalCallback,
    EveryNTimesteps,
    LogEveryNTimesteps,
    StopTrainingOnMaxEpisodes,
    StopTrainingOnRewardThreshold,
)
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy
from stable_baselines3.common.logger import configure
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import ALGO_CLASSES, algos

# The keys every algorithm logs (besides its own, Algo.own_tags).
COMMON_TAGS = (
    "rollout/ep_rew_mean",
    "rollout/ep_len_mean",
    "rollout/ep_distance_mean",
    "rollout/ep_ball_lost_mean",
    "rollout/type_freq_0",
    "rollout/param_mean_0_0",
    "rollout/param_std_0_0",
    "time/fps",
)


def scalar_tags(folder):
    events = EventAccumulator(str(folder))
    events.Reload()
    return events, set(events.Tags()["scalars"])


@algos(ALGO_CLASSES)
def test_tensorboard(tmp_path, case):
    name = case.algo.__name__
    model = case.make(ParameterizedTargetEnv(), tensorboard_log=str(tmp_path), seed=0, **case.log_often)
    model.learn(300, log_interval=2)
    model.learn(300, log_interval=2, reset_num_timesteps=False)
    assert os.path.isdir(tmp_path / f"{name}_1")
    assert not os.path.isdir(tmp_path / f"{name}_2")  # reset_num_timesteps=False continues the run
    events, tags = scalar_tags(tmp_path / f"{name}_1")
    for tag in (*COMMON_TAGS, *case.own_tags, f"{case.value_stats}_mean"):
        assert tag in tags, tag
    steps = [event.step for event in events.Scalars("rollout/ep_distance_mean")]
    assert steps == sorted(steps) and steps[-1] > 300  # the second learn() logged into the same run
    for event in events.Scalars("rollout/ep_ball_lost_mean"):
        assert 0.0 <= event.value <= 1.0
    if "rollout/exploration_rate" in case.own_tags:
        epsilons = [event.value for event in events.Scalars("rollout/exploration_rate")]
        assert epsilons[0] > epsilons[-1]


@algos(ALGO_CLASSES)
def test_custom_tb_log_name(tmp_path, case):
    model = case.make(ParameterizedTargetEnv(), tensorboard_log=str(tmp_path), seed=0)
    model.learn(100, tb_log_name="other")
    model.learn(100, tb_log_name="other")
    assert os.path.isdir(tmp_path / "other_1") and os.path.isdir(tmp_path / "other_2")


@algos(ALGO_CLASSES)
def test_custom_info_keywords(tmp_path, case):
    env = ParameterizedTargetEnv()
    model = case.make(env, info_keywords=("distance",), tensorboard_log=str(tmp_path), **case.log_often)
    model.learn(200, log_interval=1, tb_log_name="run")
    _, tags = scalar_tags(tmp_path / "run_1")
    assert "rollout/ep_distance_mean" in tags and "rollout/ep_ball_lost_mean" not in tags


@algos(ALGO_CLASSES)
def test_log_interval_none_never_dumps(tmp_path, case):
    model = case.make(ParameterizedTargetEnv(), seed=0)
    model.set_logger(configure(str(tmp_path), ["csv"]))
    model.learn(300, log_interval=None)
    assert (tmp_path / "progress.csv").read_text() == ""


class Counter(BaseCallback):
    def _on_step(self) -> bool:
        return True


class LocalsCheck(BaseCallback):
    """The locals every algorithm shows its callbacks on the SB3 path."""

    def _on_step(self) -> bool:
        for name in ("new_obs", "rewards", "dones", "infos", "actions"):
            assert name in self.locals, name
        assert self.locals["new_obs"].shape == (self.training_env.num_envs, 2)
        assert self.locals["actions"].dtype == object
        return True


@algos()
def test_callbacks(tmp_path, case):
    log_folder = tmp_path / "logs"
    model = case.make(ParameterizedTargetEnv(), seed=0)
    checkpoint = CheckpointCallback(save_freq=100, save_path=str(log_folder), name_prefix="model")
    eval_env = make_vec_env(ParameterizedTargetEnv, n_envs=1, seed=1)
    # Stop as soon as the mean reward beats -inf: proves the threshold callback ends training.
    stop_threshold = StopTrainingOnRewardThreshold(reward_threshold=-np.inf, verbose=1)
    eval_callback = EvalCallback(
        eval_env, callback_on_new_best=stop_threshold, best_model_save_path=str(log_folder), eval_freq=100, n_eval_episodes=2
    )
    event_counter = Counter()
    event_callback = EveryNTimesteps(n_steps=50, callback=event_counter)
    log_callback = LogEveryNTimesteps(n_steps=50)

    model.learn(500, callback=CallbackList([checkpoint, eval_callback, event_callback, log_callback, LocalsCheck()]))
    # Stopped by the reward threshold at the first evaluation (step 100), not at 500.
    assert model.num_timesteps == 100
    assert os.path.exists(log_folder / "model_100_steps.zip")
    assert os.path.exists(log_folder / "best_model.zip")
    assert event_counter.n_calls == 2  # at 50 and 100
    # The evaluation runs after env.step and before that step's update, and stopping skips the update,
    # so the saved best model is exactly the final one and evaluates to the same mean reward.
    best = case.algo.load(log_folder / "best_model.zip")
    for key, value in best.get_parameters()["policy"].items():
        assert th.equal(value, model.get_parameters()["policy"][key]), key
    eval_env.seed(1)
    assert evaluate_policy(best, eval_env, n_eval_episodes=2)[0] == pytest.approx(eval_callback.last_mean_reward)


@algos(ALGO_CLASSES)
def test_stop_training_on_max_episodes(case):
    model = case.make(ParameterizedTargetEnv(max_episode_steps=5, loss_threshold=0.0), seed=0)
    model.learn(10_000, callback=StopTrainingOnMaxEpisodes(max_episodes=3))
    assert model.num_timesteps == 15  # stopped at the step that ended the third episode


class InfoValueLogger(BaseCallback):
    """The SB3 docs' "log an info value" callback, and the locals every algorithm shows on the array path."""

    def __init__(self) -> None:
        super().__init__()
        self.distances: list[float] = []

    def _on_step(self) -> bool:
        infos, dones = self.locals["infos"], self.locals["dones"]
        n = self.training_env.num_envs
        assert isinstance(infos, list) and len(infos) == n and all(isinstance(info, dict) for info in infos)
        types, params = self.locals["actions"]  # the array path's (types, scaled parameters)
        assert types.shape == (n,) and params.shape == (n, 7) and np.all(np.abs(params) <= 1)
        for info, done in zip(infos, dones, strict=True):
            assert ("terminal_observation" in info) == done
            if "distance" in info:
                self.distances.append(info["distance"])
                self.logger.record_mean("custom/distance", info["distance"])
        return True


@algos(ALGO_CLASSES)
def test_callback_locals_on_the_array_path(case):
    from robocup_dribble import DribbleVecEnv

    callback = InfoValueLogger()
    case.make(DribbleVecEnv(3, profile="v11"), seed=0).learn(300, callback=callback)
    assert callback.distances and np.isfinite(callback.distances).all()


@algos(ALGO_CLASSES)
def test_learn_ends_with_a_dump_and_logs_actions_and_values(tmp_path, case):
    """A short learn writes its figures (a dump at the end), with the action-type shares, each type's parameter
    means and standard deviations in the env's units, and the critic's value statistics."""
    env = ParameterizedTargetEnv()
    model = case.make(env, seed=0)
    model.set_logger(configure(str(tmp_path), ["csv"]))
    model.learn(250)  # fewer steps than SarsaAAC's log_min_timesteps (2,000)
    import csv

    rows = list(csv.DictReader((tmp_path / "progress.csv").open()))
    assert rows and int(float(rows[-1]["time/total_timesteps"])) == model.num_timesteps
    last = {key: float(value) for key, value in rows[-1].items() if value != ""}
    shares = [last[f"rollout/type_freq_{k}"] for k in range(env.action_space[0].n)]
    assert sum(shares) == pytest.approx(1.0)
    spec = model.policy.spec
    for k, dim in enumerate(spec.dims):
        if shares[k] == 0:
            continue
        for i in range(dim):
            low, high = spec.low[spec.offsets[k] + i], spec.high[spec.offsets[k] + i]
            assert low <= last[f"rollout/param_mean_{k}_{i}"] <= high
            assert 0 <= last[f"rollout/param_std_{k}_{i}"] <= (high - low) / 2
    value = case.value_stats
    assert last[f"{value}_min"] <= last[f"{value}_mean"] <= last[f"{value}_max"] and last[f"{value}_std"] >= 0
