"""evaluate_dribbling on common random numbers: every policy meets the same episode in each slot; the per-slot
distance bound holds for every policy; bad input is refused."""

from __future__ import annotations

import numpy as np
import pytest

from robocup_dribble import physics, skills
from robocup_dribble.dribbler import HandCodedDribbler
from robocup_dribble.env import configure
from robocup_dribble.evaluation import distance_bound, evaluate_dribbling, reliability_test
from robocup_dribble.lanes import DribbleLanes


class DashStraight:
    """Always DASH_MAX(0): runs away from the ball, which it loses within a few cycles."""

    def predict(self, obs, deterministic=True):
        n = len(obs)
        return skills.as_env_actions(np.zeros(n, dtype=np.int64), np.zeros((n, skills.N_PARAMS))), None


class RandomPolicy:
    """Uniformly random action types and parameters (the lanes clip them to their bounds)."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def predict(self, obs, deterministic=True):
        n = len(obs)
        params = self.rng.uniform(-1.0, 1.0, (n, skills.N_PARAMS)) * np.array([100.0, 180.0, 3.0, 180.0, 1.0, 1.0, 1.0])
        return skills.as_env_actions(self.rng.integers(0, skills.N_ACTION_TYPES, n), params), None


@pytest.fixture(scope="module", params=["v11", "v19"])
def profile(request):
    return request.param


@pytest.fixture(scope="module")
def dribbler_report(profile):
    return evaluate_dribbling(HandCodedDribbler(profile), 120, profile, seed=4, n_lanes=50)


def assert_same_report(a, b):
    for field in ("distances", "ball_lost", "player_types", "start_states", "distance_bounds"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field), err_msg=field)


def test_identical_policies_meet_identical_episodes(profile, dribbler_report):
    """Another instance of the same deterministic policy, with other lane counts (so slots go to other lanes at
    other times), gets the same result in every slot."""
    for n_lanes in (7, 120):
        assert_same_report(dribbler_report, evaluate_dribbling(HandCodedDribbler(profile), 120, profile, 4, n_lanes))


def test_slots_do_not_depend_on_the_policy(profile, dribbler_report):
    """A policy that loses the ball at once frees its lanes at other times, yet meets the same types and starts."""
    quick = evaluate_dribbling(DashStraight(), 120, profile, seed=4, n_lanes=50)
    np.testing.assert_array_equal(quick.player_types, dribbler_report.player_types)
    np.testing.assert_array_equal(quick.start_states, dribbler_report.start_states)
    assert quick.loss_rate == 1.0 and dribbler_report.mean_distance > quick.mean_distance + 20.0


def test_slots_are_a_fixed_sequence(profile, dribbler_report):
    """Fewer episodes play the first slots of the same sequence; another seed gives other episodes in every slot."""
    first = evaluate_dribbling(HandCodedDribbler(profile), 30, profile, seed=4, n_lanes=11)
    for field in ("distances", "ball_lost", "player_types", "start_states", "distance_bounds"):
        np.testing.assert_array_equal(getattr(first, field), getattr(dribbler_report, field)[:30])
    other = evaluate_dribbling(DashStraight(), 120, profile, seed=5, n_lanes=50)
    assert not (other.start_states == dribbler_report.start_states).all(axis=1).any()
    # a slot's type is one of a fresh set: some slots play the default type 0, the rest all differ
    assert (other.player_types != dribbler_report.player_types).any(axis=1).mean() > 0.8


def test_types_are_spread_over_fresh_sets(profile, dribbler_report):
    """Every slot plays a type of its own fresh set: the slots' types are nearly all distinct."""
    distinct = len(np.unique(dribbler_report.player_types, axis=0))
    assert distinct > 0.8 * len(dribbler_report.player_types)


@pytest.mark.parametrize("noise", [True, False])
def test_distance_bound_holds_for_every_policy_and_slot(profile, noise):
    policies = [HandCodedDribbler(profile), RandomPolicy(0), DashStraight()]
    for policy in policies:
        report = evaluate_dribbling(policy, 150, profile, seed=9, n_lanes=50, noise=noise)
        assert (report.distances <= report.distance_bounds).all()
    assert report.mean_distance_bound > 30.0  # full speed for 35 cycles: a bound, but not a vacuous one


def test_distance_bound_is_a_ballless_run_with_the_best_noise_plus_one_push(profile, dribbler_report):
    """The bound is what a player without a ball reaches by 35 full dashes along +x, with its start speed along +x and
    every cycle's noise at full length along +x, plus one collision push-out (a collision in the last cycle). With
    polar noise (v19) that is the bound exactly; with box noise (v11) the bound lets the speed grow by the noise
    of both components, which the run along +x does not use."""
    server_profile, task_settings = configure(profile, True, None, {})
    types, state = dribbler_report.player_types, dribbler_report.start_states.copy()
    state[:, physics.B_Y] = 1e3
    state[:, physics.P_VX], state[:, physics.P_VY] = np.hypot(state[:, physics.P_VX], state[:, physics.P_VY]), 0.0
    commands = np.zeros((len(types), physics.COMMAND_SIZE))
    commands[:, physics.C_KIND], commands[:, physics.C_POWER] = physics.CMD_DASH, server_profile.server.max_dash_power
    uniforms = np.full((len(types), physics.N_UNIFORMS), 0.5)
    uniforms[:, physics.U_PLAYER_R] = 1.0  # full noise length (polar) or full x component (box), at angle 0
    constants = physics.profile_constants(server_profile)
    for _ in range(task_settings.max_actions):
        physics.step(state, types, commands, uniforms, constants)
    push = 0.5 * (types[:, physics.T_SIZE] + server_profile.server.ball_size)
    run_and_push = state[:, physics.P_X] - dribbler_report.start_states[:, physics.P_X] + push
    bounds = distance_bound(server_profile, task_settings, types, dribbler_report.start_states)
    np.testing.assert_array_equal(bounds, dribbler_report.distance_bounds)
    if server_profile.noise_shape == "polar":
        np.testing.assert_allclose(bounds, run_and_push, atol=2.5e-4)  # the push-out's allowance for its growth steps
    else:
        assert (bounds >= run_and_push).all() and (bounds - run_and_push < 2.5).all()


def test_a_start_beyond_its_block_continues_on_its_own_counters(profile, monkeypatch):
    """With room for only 8 start values in each slot's block, every start continues on its own counters; the slots
    stay independent of lanes and policies."""
    monkeypatch.setattr("robocup_dribble.evaluation.START_UNIFORMS", 8)
    a = evaluate_dribbling(DashStraight(), 40, profile, seed=2, n_lanes=3)
    b = evaluate_dribbling(DashStraight(), 40, profile, seed=2, n_lanes=40)
    assert_same_report(a, b)
    assert len(np.unique(a.start_states, axis=0)) == 40


def test_reliability_test_plays_the_same_slots(profile):
    a = reliability_test(DashStraight(), 25, profile, seed=3, n_lanes=10)
    b = evaluate_dribbling(DashStraight(), 25, profile, seed=3)
    assert_same_report(a, b)
    assert "upper bound" in a.summary()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"n_episodes": 0}, "n_episodes"),
        ({"n_episodes": 2.5}, "n_episodes"),
        ({"n_episodes": True}, "n_episodes"),
        ({"n_lanes": 0}, "n_lanes"),
        ({"seed": -1}, "seed"),
        ({"seed": 2**64}, "seed"),
        ({"seed": 1.0}, "seed"),
        ({"max_action": 10}, "Unknown argument"),
        ({"max_actions": 0}, "max_actions"),
    ],
)
def test_bad_input_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        evaluate_dribbling(DashStraight(), **{"n_episodes": 5, **kwargs})


def test_start_from_leaves_a_lane_whose_row_ran_short_as_it_was():
    server_profile, task_settings = configure("v19", True, None, {})
    lanes = DribbleLanes(3, server_profile, task_settings, np.random.default_rng(0))
    lanes.reset(np.arange(3))
    before = [array.copy() for array in lanes.arrays]
    rows = np.random.default_rng(1).random((2, 400))
    rows[1, 20:] = np.nan  # only 20 values: far too few for a set of 18 types
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        lanes.start_from(np.array([0, 2]), rows)
    obs, short = lanes.start_from(np.array([0, 2]), rows[:, :20])
    assert short.tolist() == [True, True]
    for array, old in zip(lanes.arrays, before, strict=True):
        np.testing.assert_array_equal(array, old)
    obs, short = lanes.start_from(np.array([2, 0]), np.nan_to_num(rows, nan=0.5))
    assert short.tolist() == [False, False] and obs.shape == (2, 10)
    assert lanes.steps[[0, 2]].tolist() == [0, 0] and lanes.start_x[0] == lanes.state[0, physics.P_X]
    np.testing.assert_array_equal(lanes.types[1], before[1][1])  # lane 1 untouched


def test_step_refuses_bad_uniforms_and_changes_nothing():
    server_profile, task_settings = configure("v11", True, None, {})
    lanes = DribbleLanes(2, server_profile, task_settings, np.random.default_rng(0))
    lanes.reset(np.arange(2))
    before = lanes.state.copy()
    kinds, params = np.zeros(2, dtype=np.int64), np.zeros((2, skills.N_PARAMS))
    for bad in (np.full((2, physics.N_UNIFORMS), 1.5), np.full((3, physics.N_UNIFORMS), 0.5), np.zeros((2, 2))):
        with pytest.raises(ValueError, match="uniforms"):
            lanes.step(kinds, params, uniforms=bad)
    np.testing.assert_array_equal(lanes.state, before)
    a = lanes.step(kinds, params, autoreset=False, uniforms=np.full((2, physics.N_UNIFORMS), 0.5))
    assert a.observations.shape == (2, 10)


def test_distance_bound_holds_for_random_commands_noise_and_collisions(profile):
    """Straight to the physics, without the task's ball-loss end: mostly full dashes along +x mixed with random
    dashes, kicks (which send the ball into the player now and then) and turns, and random noise (for half the
    players, their movement noise at full length along +x); the player's x never gets further from its start than
    the bound, in any cycle."""
    report = evaluate_dribbling(DashStraight(), 400, profile, seed=21, n_lanes=100)
    server_profile, task_settings = configure(profile, True, None, {})
    s = server_profile.server
    rng = np.random.default_rng(0)
    state, types = report.start_states.copy(), report.player_types
    constants = physics.profile_constants(server_profile)
    n = len(types)
    furthest, collisions = np.zeros(n), 0
    for _ in range(task_settings.max_actions):
        commands = np.zeros((n, physics.COMMAND_SIZE))
        kinds = rng.choice([physics.CMD_DASH, physics.CMD_KICK, physics.CMD_TURN], size=n, p=[0.8, 0.15, 0.05])
        commands[:, physics.C_KIND] = kinds
        commands[:, physics.C_POWER] = np.where(
            kinds == physics.CMD_KICK, rng.uniform(0, s.max_power, n), rng.uniform(0.8, 1.0, n) * s.max_dash_power
        )
        commands[:, physics.C_DIRECTION] = np.where(rng.random(n) < 0.7, 0.0, rng.uniform(-180, 180, n))
        uniforms = rng.random((n, physics.N_UNIFORMS))
        uniforms[: n // 2, physics.U_PLAYER_R], uniforms[: n // 2, physics.U_PLAYER_A] = 1.0, 0.5  # noise along +x
        events = physics.step(state, types, commands, uniforms, constants)
        collisions += int(events[:, physics.E_COLLISION].sum())
        furthest = np.maximum(furthest, state[:, physics.P_X] - report.start_states[:, physics.P_X])
    assert collisions > 0
    assert (furthest <= report.distance_bounds).all()
    assert (furthest / report.distance_bounds).max() > 0.8  # some come close: the check has teeth
