"""What every algorithm guards beyond SB3 (sb3_aac.common.guards), over tests.helpers.ALGO_CLASSES: learn's budget,
finite env output, saves that cannot lose a model; and loading a model only to act, as rl-zoo3's enjoy does."""

from __future__ import annotations

import math
import os
import re
import zipfile

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from stable_baselines3.common.vec_env import DummyVecEnv

from sb3_aac.common.envs import ParameterizedTargetEnv
from tests.helpers import ALGO_CLASSES, algos


class LateNaNEnv(gym.Env):
    """Finite observations and rewards until step ``at`` of the run, then NaN in the observation or the reward."""

    def __init__(self, where: str, at: int = 3):
        self.where, self.at, self.t = where, at, 0
        self.observation_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.action_space = spaces.Tuple((spaces.Discrete(2), spaces.Box(-1.0, 1.0, (1,), np.float32)))

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(2, np.float32), {}

    def step(self, action):
        self.t += 1
        bad = self.t >= self.at
        obs = np.array([np.nan if bad and self.where == "obs" else 0.1, 0.0], np.float32)
        reward = math.inf if bad and self.where == "reward" else 1.0
        return obs, reward, False, self.t % 5 == 0, {}


@algos(ALGO_CLASSES)
@pytest.mark.parametrize("budget", [-5, 0, math.nan, math.inf, "100", True, 2.5, None])
def test_learn_refuses_a_budget_that_is_not_a_whole_number_of_steps(case, budget) -> None:
    model = case.make(ParameterizedTargetEnv(), seed=0)
    with pytest.raises(ValueError, match=r"total_timesteps must be a whole number of env steps >= 1, got"):
        model.learn(budget)
    assert model.num_timesteps == 0


@algos(ALGO_CLASSES)
def test_learn_takes_a_whole_float_budget(case) -> None:
    assert case.make(ParameterizedTargetEnv(), seed=0).learn(60.0).num_timesteps >= 60


@algos(ALGO_CLASSES)
@pytest.mark.parametrize(("where", "named"), [("obs", "observations of lanes [1]"), ("reward", "rewards of lanes [1]")])
def test_non_finite_env_output_stops_learn_naming_lane_and_step(case, where, named) -> None:
    envs = [lambda: LateNaNEnv(where, at=10**9), lambda: LateNaNEnv(where, at=3)]  # lane 1 goes bad at its 3rd step
    model = case.make(DummyVecEnv(envs), seed=0)
    with pytest.raises(ValueError, match=rf"non-finite \(NaN or inf\) {re.escape(named)} at timestep 6"):
        model.learn(100)


@algos(ALGO_CLASSES)
def test_a_failed_save_keeps_the_earlier_model(case, tmp_path, monkeypatch) -> None:
    model = case.make(ParameterizedTargetEnv(), seed=0)
    model.learn(60)
    model.save(tmp_path / "model")  # no suffix: model.zip, as SB3 names it
    before = (tmp_path / "model.zip").read_bytes()
    model.learn(60, reset_num_timesteps=False)

    def disk_full(self, *args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(zipfile.ZipFile, "writestr", disk_full)
    with pytest.raises(OSError, match="No space"):
        model.save(tmp_path / "model.zip")
    monkeypatch.undo()
    assert (tmp_path / "model.zip").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.zip"]  # no temporary left
    assert case.algo.load(tmp_path / "model.zip").num_timesteps == case.timesteps(60)


@algos(ALGO_CLASSES)
def test_saves_get_the_umask_permissions(case, tmp_path) -> None:
    previous = os.umask(0o022)
    try:
        case.make(ParameterizedTargetEnv(), seed=0).save(tmp_path / "model.zip")
    finally:
        os.umask(previous)
    assert os.stat(tmp_path / "model.zip").st_mode & 0o777 == 0o644


@algos(ALGO_CLASSES)
def test_a_model_loads_to_act_as_rl_zoo3_enjoy_loads_it(case, tmp_path) -> None:
    model = case.make(ParameterizedTargetEnv(), seed=0)
    model.learn(60)
    model.save(tmp_path / "model.zip")
    # rl_zoo3.enjoy's custom_objects
    custom_objects = {"learning_rate": 0.0, "lr_schedule": lambda _: 0.0, "clip_range": lambda _: 0.0}
    loaded = case.algo.load(tmp_path / "model.zip", custom_objects=custom_objects)
    obs = np.stack([model.observation_space.sample() for _ in range(20)])
    expected, got = model.predict(obs, deterministic=True)[0], loaded.predict(obs, deterministic=True)[0]
    assert [a[0] for a in expected] == [a[0] for a in got]


@pytest.mark.parametrize(
    ("algo", "policy", "kwargs", "message"),
    [
        ("SarsaAAC", "MlpPolicy", dict(policy_kwargs=dict(hidden_units=100_000_000)), r"approximators .* would take .* GiB"),
        ("SarsaAAC", "MlpPolicy", dict(policy_kwargs=dict(hidden_units=1e8)), "hidden_units must be a whole number"),
        ("SarsaAAC", "RbfPolicy", dict(policy_kwargs=dict(n_rbf=2.5)), "n_rbf must be a whole number"),
        (
            "SarsaAAC",
            "TilePolicy",
            dict(policy_kwargs=dict(tiles_per_input=100_000)),
            r"tiles_per_input=100000, .* would take",
        ),
        ("SarsaAAC", "TilePolicy", dict(policy_kwargs=dict(n_tilings=100_000_000)), r"n_tilings=100000000: .* would take"),
        ("HybridPPO", "MlpPolicy", dict(n_steps=2**28), r"rollout buffer \(n_steps=268,435,456 x 1 envs\) would take"),
        ("MPDQN", "MlpPolicy", dict(buffer_size=10**10), r"replay buffer \(buffer_size=10,000,000,000\) would take"),
        ("MPDQN", "MlpPolicy", dict(buffer_size=1e6), "buffer_size must be an integer >= 1"),
        ("PDQN", "MlpPolicy", dict(policy_kwargs=dict(net_arch=[-5])), r"net_arch must hold whole numbers in 1 .. 65,536"),
        ("PDQN", "MlpPolicy", dict(policy_kwargs=dict(actor_net_arch="64")), "actor_net_arch must be a list"),
    ],
)
def test_sizes_beyond_the_limits_are_refused_at_construction(algo, policy, kwargs, message) -> None:
    import sb3_aac

    with pytest.raises(ValueError, match=message):
        getattr(sb3_aac, algo)(policy, ParameterizedTargetEnv(), **kwargs)


@algos(ALGO_CLASSES)
def test_an_empty_batch_is_one_clear_error_everywhere(case, tmp_path) -> None:
    from sb3_aac import RuntimePolicy, export_policy

    model = case.make(ParameterizedTargetEnv(), seed=0)
    empty = np.zeros((0, *model.observation_space.shape), np.float32)
    for deterministic in (True, False):
        with pytest.raises(ValueError, match=r"empty batch of shape \(0, 2\)"):
            model.predict(empty, deterministic=deterministic)
    runtime = RuntimePolicy.load(export_policy(model, tmp_path / "policy.aacp"))
    for call in (runtime.act_batch, runtime.predict, runtime.outputs):
        with pytest.raises(ValueError, match=r"empty batch of shape \(0, 2\)"):
            call(empty)


@algos(ALGO_CLASSES)
def test_an_observation_no_policy_can_take_is_named_for_what_it_is(case, tmp_path) -> None:
    """Complex numbers, finite values beyond float32 (not "NaN or inf"), and a Dict space (no MultiInputPolicy here)."""
    from sb3_aac import RuntimePolicy, export_policy

    model = case.make(ParameterizedTargetEnv(), seed=0)
    obs = model.observation_space.sample()
    with pytest.raises(ValueError, match="holds complex numbers: observations are real"):
        model.predict(obs + 1j, deterministic=True)
    with pytest.raises(ValueError, match=r"values beyond float32's range \(\|x\| > 3.4e\+38\)"):
        model.predict(np.full(obs.shape, 1e300), deterministic=True)
    runtime = RuntimePolicy.load(export_policy(model, tmp_path / "policy.aacp"))
    with pytest.raises(ValueError, match="too large to compute with"):
        runtime.act(np.full(obs.shape, 1e300))
    env = ParameterizedTargetEnv()
    env.observation_space = spaces.Dict({"position": env.observation_space})
    with pytest.raises(ValueError, match=r"sb3-aac's policies take a Box observation .*FlattenObservation") as error:
        case.make(env)
    assert "MultiInputPolicy" not in str(error.value)


def test_one_hybrid_ppo_shared_by_threads_decides_as_alone() -> None:
    from concurrent.futures import ThreadPoolExecutor

    from sb3_aac import HybridPPO

    model = HybridPPO("MlpPolicy", ParameterizedTargetEnv(), seed=0)
    obs = np.stack([model.observation_space.sample() for _ in range(400)])
    alone = [model.predict(o, deterministic=True)[0] for o in obs]
    with ThreadPoolExecutor(4) as pool:
        shared = list(pool.map(lambda o: model.predict(o, deterministic=True)[0], obs))
    assert all(a[0] == b[0] and np.array_equal(a[1][a[0]], b[1][b[0]]) for a, b in zip(alone, shared, strict=True))


def test_one_runtime_policy_shared_by_threads_decides_as_alone(tmp_path) -> None:
    from concurrent.futures import ThreadPoolExecutor

    from sb3_aac import RuntimePolicy, SarsaAAC, export_policy

    model = SarsaAAC("RbfPolicy", ParameterizedTargetEnv(), seed=0)
    model.learn(200)
    runtime = RuntimePolicy.load(export_policy(model, tmp_path / "policy.aacp"))
    obs = np.stack([model.observation_space.sample() for _ in range(3000)])
    alone = [runtime.act(o) for o in obs]
    with ThreadPoolExecutor(4) as pool:
        shared = list(pool.map(runtime.act, obs))
    assert all(a[0] == b[0] and np.array_equal(a[1], b[1]) for a, b in zip(alone, shared, strict=True))


@algos(ALGO_CLASSES)
def test_set_random_seed_without_seed_repeats_a_run(case) -> None:
    """SB3's set_random_seed before a constructor without seed= repeats the run, as for SB3's own algorithms (the
    algorithms' own generators draw their seed from numpy's global state)."""
    import torch as th
    from stable_baselines3.common.utils import set_random_seed

    runs = []
    for _ in range(2):
        set_random_seed(7)
        env = ParameterizedTargetEnv()
        env.reset(seed=7)  # the env's own generator, as make_vec_env(seed=...) seeds it
        model = case.make(env)
        model.learn(300)
        runs.append(th.cat([p.detach().flatten() for p in model.policy.parameters()]))
    assert th.equal(runs[0], runs[1])
