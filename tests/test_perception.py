"""The env's model of a match player's perception (robocup_dribble.perception, perception="match"): the server's
quantisation against hand-computed values and against the recorded rcssserver session, the estimate shared with the
real-server client, and the env option (off by default)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import robocup_dribble
from robocup_dribble import DribbleEnv, perception, physics, skills
from robocup_dribble.dribbler import HandCodedDribbler
from robocup_dribble.evaluation import evaluate_dribbling
from robocup_dribble.lanes import DribbleLanes
from robocup_dribble.params import make_profile
from robocup_dribble.rcss import protocol
from robocup_dribble.rcss.perception import PerceivedWorld, SeenBall, read_seen_ball, read_speed
from robocup_dribble.task import DribbleTask
from robocup_dribble.vec_env import DribbleVecEnv, parse_actions

SESSION = Path(robocup_dribble.__file__).parent / "data" / "rcss" / "session-v19.jsonl"


def one_lane(px: float, py: float, pvx: float, pvy: float, body_deg: float, bx: float, by: float, bvx: float, bvy: float):
    state = physics.new_state(1)
    state[0, [physics.P_X, physics.P_Y, physics.P_VX, physics.P_VY]] = px, py, pvx, pvy
    state[0, physics.P_BODY] = math.radians(body_deg)
    state[0, [physics.B_X, physics.B_Y, physics.B_VX, physics.B_VY]] = bx, by, bvx, bvy
    return state


# --- the server's quantisation, by hand -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("actual", "seen"),
    [
        (0.6, 0.6),  # log 0.6 = -0.511 -> -0.5 -> e^-0.5 = 0.607 -> 0.6
        (0.75, 0.7),  # log 0.75 = -0.288 -> -0.3 -> 0.741 -> 0.7
        (1.0, 1.0),  # log 1 = 0 -> 1
        (12.0, 12.2),  # log 12 = 2.485 -> 2.5 -> 12.18 -> 12.2
        (0.0, 0.0),  # log 1e-10 = -23.03 -> -23.0 -> 1e-10 -> 0
    ],
)
def test_seen_distance_is_the_logarithmic_then_decimetre_quantisation(actual: float, seen: float) -> None:
    assert perception.seen_distance(actual) == pytest.approx(seen, abs=1e-12)


def test_directions_round_in_a_see_and_truncate_in_sense_body() -> None:
    assert perception.rounded_degrees(math.radians(-7.6)) == -8.0
    assert perception.whole_degrees(math.radians(-7.6)) == -7.0
    assert perception.rounded_degrees(math.radians(48.4)) == 48.0
    assert perception.whole_degrees(math.radians(48.9)) == 48.0
    assert perception.quantise(0.25, 0.1) == pytest.approx(0.2)  # C's rint: halves to even
    assert perception.quantise(-14.27, 0.1) == pytest.approx(-14.3)


def test_a_ball_in_the_view_cone_comes_with_its_quantised_changes() -> None:
    # ball 0.583 m away at 30.96 degrees, relative velocity (0.2, 0): radial 0.1715 m/cycle, across -0.1029 m/cycle
    kind, distance, direction, distance_change, direction_change = perception.seen_ball(
        one_lane(0, 0, 0, 0, 0, 0.5, 0.3, 0.2, 0), 0
    )
    assert kind == perception.SEEN_IN_CONE
    assert distance == pytest.approx(0.6) and direction == 31.0
    assert distance_change == pytest.approx(0.6 * 0.3)  # 0.1715 / 0.583 = 0.294 -> 0.30 (steps of 0.02), times 0.6
    assert direction_change == pytest.approx(-10.1)  # -0.1029 / 0.583 rad = -10.11 deg -> -10.1


def test_a_ball_outside_the_cone_is_seen_without_changes_within_three_metres_only() -> None:
    behind = perception.seen_ball(one_lane(0, 0, 0, 0, 0, -0.5, 0.1, 0.3, 0), 0)
    assert behind[0] == perception.SEEN_CLOSE and behind[2] == 169.0 and behind[3:] == (0.0, 0.0)
    edge = 1.0
    inside = perception.seen_ball(one_lane(0, 0, 0, 0, 0, edge * math.cos(1.04), edge * math.sin(1.04), 0, 0), 0)
    outside = perception.seen_ball(one_lane(0, 0, 0, 0, 0, edge * math.cos(1.05), edge * math.sin(1.05), 0, 0), 0)
    assert inside[0] == perception.SEEN_IN_CONE and outside[0] == perception.SEEN_CLOSE  # the cone is 120 degrees wide
    turned = perception.seen_ball(one_lane(0, 0, 0, 0, 90, -0.5, 0.1, 0, 0), 0)  # body along +y: 168.69 - 90 degrees
    assert turned[0] == perception.SEEN_CLOSE and turned[2] == 79.0
    assert perception.seen_ball(one_lane(0, 0, 0, 0, 0, -3.5, 0, 0, 0), 0)[0] == perception.NOT_SEEN


def test_sense_body_speed_is_quantised_to_a_centimetre_and_truncated_degrees() -> None:
    speed, direction = perception.sensed_speed(one_lane(0, 0, 0.123, -0.456, 10, 0, 0, 0, 0), 0)
    assert speed == pytest.approx(0.47)  # |v| = 0.4723
    assert direction == -84.0  # atan2 = -74.90 degrees, minus the body's 10: -84.90 -> -84


# --- against the real server --------------------------------------------------------------------------------------------


def recorded_cycles() -> list[dict[str, str]]:
    """The player's fullstate, sense_body and (every second cycle) see of each cycle of the recorded session."""
    cycles: dict[int, dict[str, str]] = {}
    for line in SESSION.read_text().splitlines()[1:]:
        message = json.loads(line)
        kind = protocol.kind(message["text"])
        if message["client"] == "player" and message["direction"] == "received" and kind in ("fullstate", "see", "sense_body"):
            cycles.setdefault(protocol.read_time(message["text"]), {})[kind] = message["text"]
    return [cycles[time] for time in sorted(cycles)]


def test_the_model_sends_what_the_real_server_sent_for_the_same_state() -> None:
    """Every see's ball and every sense_body's speed of the recorded rcssserver 19.0.0 session equal the model's of
    the true state of that cycle (the same cycle's fullstate, printed to 6 digits)."""
    cycles = recorded_cycles()
    kinds = []
    for cycle in cycles:
        state = protocol.read_fullstate(cycle["fullstate"]).state.reshape(1, physics.STATE_SIZE)
        amount, direction, head = read_speed(cycle["sense_body"])
        assert head == 0
        assert perception.sensed_speed(state, 0) == pytest.approx((amount, direction), abs=1e-9)
        if "see" not in cycle:
            continue
        seen = read_seen_ball(cycle["see"])
        kind, distance, ball_direction, distance_change, direction_change = perception.seen_ball(state, 0)
        kinds.append(kind)
        if seen is None:
            assert kind == perception.NOT_SEEN
            continue
        assert (distance, ball_direction) == pytest.approx((seen.distance, seen.direction), abs=1e-9)
        if seen.distance_change is None:
            assert kind == perception.SEEN_CLOSE
        else:
            assert kind == perception.SEEN_IN_CONE
            changes = (seen.distance_change, seen.direction_change)
            assert (distance_change, direction_change) == pytest.approx(changes, abs=1e-9)
    assert len(cycles) >= 100 and len(kinds) == len(cycles) // 2  # a see every second cycle
    assert {perception.NOT_SEEN, perception.SEEN_CLOSE, perception.SEEN_IN_CONE} <= set(kinds)


# --- the estimate: one model for the env and the client -----------------------------------------------------------------


def test_the_env_keeps_the_estimate_the_client_computes_from_the_same_perceptions() -> None:
    profile = make_profile("v19")
    lanes = DribbleLanes(1, profile, DribbleTask(), np.random.default_rng(5), perception="match")
    obs = lanes.reset(np.array([0]))
    world = PerceivedWorld(profile)
    world.start(lanes.state[0])
    dribbler, k = HandCodedDribbler("v19"), physics.profile_constants(profile)
    low, high = skills.parameter_bounds(profile)
    differed = False
    for _ in range(DribbleTask().max_actions):
        kinds, params = parse_actions(dribbler.predict(obs)[0])
        command = np.empty(physics.COMMAND_SIZE)
        skills.command_lane(lanes.estimate[0], lanes.types[0], int(kinds[0]), np.clip(params[0], low, high), k, command)
        out = lanes.step(kinds, params, autoreset=False)
        if out.terminated[0]:
            break
        speed = (*perception.sensed_speed(lanes.state, 0), 0.0)
        ball = None
        if lanes.clock[0] % perception.SIGHT_INTERVAL == 1:
            kind_seen, distance, direction, distance_change, direction_change = perception.seen_ball(lanes.state, 0)
            if kind_seen == perception.SEEN_IN_CONE:
                ball = SeenBall(distance, direction, distance_change, direction_change)
            elif kind_seen == perception.SEEN_CLOSE:
                ball = SeenBall(distance, direction, None, None)
        estimate = world.update(lanes.types[0], command, lanes.state[0, physics.P_BODY], speed, ball)
        np.testing.assert_array_equal(estimate, lanes.estimate[0])
        differed |= not np.array_equal(estimate, lanes.state[0])
        obs = out.observations
    assert differed  # the estimate is not the state: the test compares two models, not two copies of the truth


# --- the env option ------------------------------------------------------------------------------------------------------


def test_perception_full_is_the_default_and_match_changes_only_what_the_policy_reads() -> None:
    kinds = np.full(8, skills.KICK_POSITION)
    params = np.tile(np.array([0, 0, 0.6, 0.4, 0, 0, 0], dtype=np.float64), (8, 1))
    runs = {}
    for name, kwargs in (("default", {}), ("full", {"perception": "full"}), ("match", {"perception": "match"})):
        env = DribbleVecEnv(8, "v19", **kwargs)
        env.seed(3)
        first = env.reset()
        steps = [env.step_arrays(kinds, params) for _ in range(6)]
        runs[name] = (first, steps, env._lanes)
    (d_first, d_steps, d_lanes), (f_first, f_steps, _), (m_first, m_steps, m_lanes) = runs.values()
    np.testing.assert_array_equal(d_first, f_first)
    for a, b in zip(d_steps, f_steps, strict=True):
        np.testing.assert_array_equal(a.observations, b.observations)
        np.testing.assert_array_equal(a.rewards, b.rewards)
    assert d_lanes.estimate is d_lanes.state  # no estimate is kept without perception
    np.testing.assert_array_equal(m_first, d_first)  # an episode starts from the known placement
    assert not np.array_equal(m_steps[-1].observations, d_steps[-1].observations)
    # the observation is the estimate's; the task's rules run on the true state
    obs = np.empty((8, 10), dtype=np.float32)
    settings = m_lanes._settings
    for i in range(8):
        robocup_dribble.task.observe(m_lanes.estimate, i, m_lanes.types, i, settings.obs_low, settings.obs_high, obs, i)
    ongoing = ~(m_steps[-1].terminated | m_steps[-1].truncated)
    np.testing.assert_array_equal(obs[ongoing], m_steps[-1].observations[ongoing])
    assert not np.array_equal(m_lanes.estimate, m_lanes.state)


def test_an_unknown_perception_is_refused_with_the_choices() -> None:
    for make in (lambda: DribbleEnv(perception="fullstate"), lambda: DribbleVecEnv(2, perception="see")):
        with pytest.raises(ValueError, match=r"perception must be one of \['full', 'match'\]"):
            make()


def test_a_slots_sights_do_not_depend_on_the_number_of_lanes() -> None:
    dribbler = HandCodedDribbler("v19")
    few = evaluate_dribbling(dribbler, 24, seed=4, n_lanes=5, perception="match")
    many = evaluate_dribbling(dribbler, 24, seed=4, n_lanes=24, perception="match")
    exact = evaluate_dribbling(dribbler, 24, seed=4, n_lanes=24)
    np.testing.assert_array_equal(few.distances, many.distances)
    assert not np.array_equal(many.distances, exact.distances)


def test_a_policy_trains_and_is_evaluated_on_the_perception_model() -> None:
    from sb3_aac import SarsaAAC

    env = DribbleVecEnv(4, "v19", perception="match")
    model = SarsaAAC("TilePolicy", env, seed=0).learn(2_000)
    report = evaluate_dribbling(model, 40, seed=1, perception="match")
    assert np.isfinite(report.distances).all() and report.mean_distance > 0
    single = DribbleEnv(perception="match")
    obs, _ = single.reset(seed=0)
    assert single.observation_space.contains(obs)
