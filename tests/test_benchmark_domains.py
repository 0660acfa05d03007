"""The benchmark's domains (benchmarks/domains.py): Platform-v0 and the hybrid_domains envs beside dribbling, common
random numbers on all, and the summaries every cell file uses."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks import domains


class FixedAction:
    """A deterministic policy whose action depends on the observation (so different episodes score differently)."""

    def __init__(self, action_space, offset: float = 0.0):
        self.space = action_space
        self.offset = offset

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        k = int(np.asarray(obs).ravel()[0] * 7 + self.offset) % 3
        params = tuple(np.asarray((box.low + box.high) / 2, dtype=box.dtype) for box in self.space[1])
        return (k, params), state


@pytest.fixture(scope="module")
def platform_space():
    env = domains.episodic_env("Platform-v0")
    yield env.action_space
    env.close()


def test_platform_slots_are_common_random_numbers(platform_space):
    policy = FixedAction(platform_space)
    first, success = domains.episodic_returns("Platform-v0", policy, 12, seed=5)
    again, _ = domains.episodic_returns("Platform-v0", FixedAction(platform_space), 12, seed=5)
    np.testing.assert_array_equal(first, again)  # identical policies: identical per-episode results
    # slot j is the same episode whatever the set size: the first 6 of 12 are the 6 of a set of 6
    np.testing.assert_array_equal(domains.episodic_returns("Platform-v0", policy, 6, seed=5)[0], first[:6])
    assert np.all((first >= 0) & (first <= 1 + 1e-9)) and success is None  # Platform's success is a return of 1


def run_slot(seed: int, steps: int = 4) -> np.ndarray:
    """The observations of a fixed action sequence in episode slot 0 of evaluation set ``seed``."""
    env = domains.episodic_env("Platform-v0")
    env.reset(seed=seed * domains.SLOT_STRIDE)
    run = np.array([0.0, 10.0, 300.0, 200.0], dtype=np.float32)
    action = (0, tuple(run[1 + i : 2 + i] for i in range(3)))
    observations = []
    for _ in range(steps):
        obs, _, terminated, truncated, _ = env.step(action)
        observations.append(obs)
        if terminated or truncated:
            break
    env.close()
    return np.stack(observations)


def test_platform_slots_fix_the_noise_and_sets_differ():
    """Platform starts alike; its randomness is in the dynamics (the enemies' moves), which a slot's seed fixes."""
    np.testing.assert_array_equal(run_slot(5), run_slot(5))
    assert not np.array_equal(run_slot(5), run_slot(6))


def test_summaries_keep_per_episode_scores_in_slot_order():
    scores = np.array([1.0, 0.5, 0.25])
    summary = domains.summarize("Platform-v0", scores)
    assert summary["episode_scores"] == [1.0, 0.5, 0.25]
    assert summary["return_mean"] == pytest.approx(0.5833, abs=1e-4) and summary["success_share"] == pytest.approx(1 / 3)
    dribble = domains.summarize("RoboCupDribblePaper-v0", np.array([30.0, 10.0]), np.array([False, True]))
    assert dribble["distance_mean"] == 20.0 and dribble["reach20_share"] == 0.5 and dribble["ball_loss_rate"] == 0.5
    assert domains.metric("Platform-v0") == "return_mean" and domains.metric("RoboCupDribble-v0") == "distance_mean"


def test_bad_domain_input_is_named():
    with pytest.raises(ValueError, match="n_episodes"):
        domains.episodic_returns("Platform-v0", None, 0, seed=1)
    with pytest.raises(ValueError, match="unknown env id 'Nope-v0'"):
        domains.train_env("Nope-v0", 1, 0)
    with pytest.raises(ValueError, match="ball_lost"):
        domains.summarize("RoboCupDribble-v0", np.array([1.0]))


class ScriptedPolicy:
    """The hybrid_domains scripted policy of an env id, behind SB3's predict."""

    def __init__(self, env_id: str):
        from hybrid_domains.baselines import scripted_policy

        self.act = scripted_policy(env_id)

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        return self.act(obs), state


@pytest.mark.parametrize(
    ("env_id", "metric", "label"),
    [
        ("Goal-v0", "success_share", "P(goal)"),
        ("Moving-v0", "return_mean", "mean return"),
        ("Sliding-v0", "return_mean", "mean return"),
        ("CatchPoint-v0", "success_share", "success share"),
    ],
)
def test_hybrid_domains_train_and_score_with_their_published_metric(env_id, metric, label):
    assert domains.metric(env_id) == metric and domains.metric_label(env_id) == label
    venv = domains.train_env(env_id, 2, seed=0)
    assert venv.num_envs == 2 and len(venv.observation_space.shape) == 1  # a Box, as the learners take
    venv.close()
    policy = ScriptedPolicy(env_id)
    summary = domains.evaluate(env_id, policy, 20, seed=3)
    again = domains.evaluate(env_id, ScriptedPolicy(env_id), 20, seed=3)
    assert summary == again and summary["episodes"] == 20 and 0.0 <= summary["success_share"] <= 1.0
    assert summary["success_share"] > 0  # the scripted policies succeed now and then on every domain


def test_the_yml_env_wrappers_are_built_in_order():
    import gymnasium as gym

    import hybrid_domains  # noqa: F401  (registers Goal-v0)
    from benchmarks.zoo_hyperparams import env_wrapper
    from hybrid_domains.reference_inputs import GoalFeatures, ScaleReward

    env = env_wrapper("mpdqn", "Goal-v0")(gym.make("Goal-v0"))
    assert isinstance(env, ScaleReward) and env.scale == 0.02 and isinstance(env.env, GoalFeatures)
    assert env.observation_space.shape == (17,)
    platform = env_wrapper("mpdqn", "Platform-v0")(domains.episodic_env("Platform-v0").env)
    assert platform.observation_space.shape == (9,) and platform.index == 0
    unwrapped = gym.make("Goal-v0")
    assert env_wrapper("pdqn", "sb3_aac/ParameterizedTarget-v0")(unwrapped) is unwrapped  # no env_wrapper: identity


def test_the_reference_goal_start_is_the_reference_function_on_our_scaling():
    """The passthrough re-expressed on the policy's feature scaling gives the reference's parameters: at a state with
    the ball at (10, 0) and the keeper straight ahead (u = (-1, 0)), kick-to x = -0.375 + 0.5 * 0 + 0.0625 * -1 and
    y = 0; shoot +/-0.857 (scaled)."""
    import gymnasium as gym

    import hybrid_domains  # noqa: F401  (registers Goal-v0)
    from benchmarks.models import PassthroughPolicy, goal_passthrough
    from hybrid_domains.reference_inputs import GoalFeatures
    from sb3_aac import MPDQN

    box = GoalFeatures(gym.make("Goal-v0")).observation_space
    low, high = box.low.astype(float), box.high.astype(float)
    weight, bias = goal_passthrough(low, high)
    obs = np.zeros(17)
    obs[[5, 10, 14]] = 15.0, 10.0, -1.0  # keeper x 15, ball x 10, unit keeper-to-ball (-1, 0)
    features = (obs - (high + low) / 2) / ((high - low) / 2)
    np.testing.assert_allclose(weight @ features + bias, [-0.375 - 0.0625, 0.0, 0.857347, -0.857347], atol=1e-6)
    model = MPDQN(PassthroughPolicy, GoalFeatures(gym.make("Goal-v0")), learning_starts=10, policy_kwargs={"net_arch": [8]})
    _, params = model._greedy_numpy(obs[None].astype(np.float32))
    np.testing.assert_allclose(params[0], weight @ features + bias, atol=1e-3)  # the trained part starts near 0
