"""The physics against the hand-checked one-cycle test vectors of docs/physics.md §9 (noise off)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from robocup_dribble import physics
from robocup_dribble.params import make_profile, without_noise
from robocup_dribble.player_types import default_player_type, generate_player_types, stack_player_types

V19 = without_noise(make_profile("v19"))
V11 = without_noise(make_profile("v11"))
COMMANDS = {None: physics.CMD_NONE, "dash": physics.CMD_DASH, "kick": physics.CMD_KICK, "turn": physics.CMD_TURN}


def one_cycle(
    command=None,
    power=0.0,
    direction=0.0,
    player=(0, 0, 0, 0),
    body=0.0,
    ball=(0, 25, 0, 0),
    profile=V19,
    player_type=None,
    stamina=None,
):
    """Run one server cycle from the given set-up; returns (state row, events row)."""
    player_type = player_type or default_player_type(profile)
    types = stack_player_types([player_type])
    state = physics.new_state(1)
    physics.recover(state, types, profile)
    if stamina is not None:
        state[0, physics.S_STAMINA] = stamina
    state[0, [physics.P_X, physics.P_Y, physics.P_VX, physics.P_VY]] = player
    state[0, physics.P_BODY] = math.radians(body)
    state[0, [physics.B_X, physics.B_Y, physics.B_VX, physics.B_VY]] = ball
    commands = np.array([[COMMANDS[command], power, direction]])
    events = physics.step(state, types, commands, np.full((1, physics.N_UNIFORMS), 0.5), physics.profile_constants(profile))
    return state[0], events[0]


def player_of(s):
    return s[[physics.P_X, physics.P_Y, physics.P_VX, physics.P_VY]]


def ball_of(s):
    return s[[physics.B_X, physics.B_Y, physics.B_VX, physics.B_VY]]


def test_t1_dash_from_rest():
    s, _ = one_cycle("dash", 100)
    np.testing.assert_allclose(player_of(s), [0.6, 0, 0.24, 0], atol=1e-12)
    assert s[physics.S_STAMINA] == 7945 and s[physics.S_CAPACITY] == 130555
    assert s[physics.S_EFFORT] == 1 and s[physics.S_RECOVERY] == 1


@pytest.mark.parametrize(
    ("profile", "start", "expected"),
    [
        (V19, (0.6, 0, 0.24, 0), [1.44, 0, 0.336, 0]),  # T2a
        (V19, (0, 0, 0.6, 0), [1.05, 0, 0.42, 0]),  # T2b: capped at 1.05
        (V11, (0, 0, 0.7, 0), [1.2, 0, 0.48, 0]),  # T2b, v11: capped at 1.2
        (V19, (0, 0, 0.7, 0), [1.05, 0, 0.42, 0]),
    ],
)
def test_t2_second_dash_and_speed_cap(profile, start, expected):
    s, _ = one_cycle("dash", 100, player=start, profile=profile)
    np.testing.assert_allclose(player_of(s), expected, atol=1e-9)


@pytest.mark.parametrize(
    ("body", "direction", "power", "player", "expected"),
    [
        (30, 45, 100, (0, 0, 0, 0), [0.108703999, 0.405688847, 0.0434815996, 0.162275539]),
        (0, 90, 100, (0, 0, 0, 0), [0, 0.24, 0, 0.096]),
        (0, 180, 100, (0, 0, 0, 0), [-0.42, 0, -0.168, 0]),
        (0, 44.5, 100, (0, 0, 0, 0), [0.305000075, 0.294535149, None, None]),  # rounds to 44
        (0, 45.5, 100, (0, 0, 0, 0), [0.288977882, 0.299245357, None, None]),  # rounds to 46
        (0, 0, 50, (0, 0, 0.1, 0.2), [0.4, 0.2, 0.16, 0.08]),
    ],
)
def test_t3_omnidirectional_dash(body, direction, power, player, expected):
    s, _ = one_cycle("dash", power, direction, player=player, body=body)
    for got, want in zip(player_of(s), expected, strict=True):
        if want is not None:
            assert got == pytest.approx(want, abs=1e-8)
    assert s[physics.S_STAMINA] == (7995 if power == 50 else 7945)


def test_t4_kick_straight_ahead_and_to_the_side():
    s, events = one_cycle("kick", 100, 0, ball=(0.5, 0, 0, 0))
    np.testing.assert_allclose(ball_of(s), [3.08910714, 0, 2.43376071, 0], atol=1e-8)
    np.testing.assert_allclose(player_of(s), [0, 0, 0, 0])
    assert events[physics.E_KICK_OK]
    s, _ = one_cycle("kick", 100, 0, ball=(0, 0.6, 0, 0))
    np.testing.assert_allclose(ball_of(s), [2.15517857, 0.6, 2.02586786, 0], atol=1e-8)


def test_t5_oblique_kick_of_a_moving_ball():
    s, _ = one_cycle("kick", 50, -45, player=(10, -5, 0, 0), body=90, ball=(10.4, -4.3, 0.2, 0.3))
    np.testing.assert_allclose(ball_of(s), [11.3715506, -3.22844938, 0.913257582, 1.00725758], atol=1e-7)


@pytest.mark.parametrize(("profile", "expected"), [(V19, [3.5, 0, 2.82, 0]), (V11, [3.2, 0, 2.538, 0])])
def test_t6_kick_adds_to_velocity_and_is_capped(profile, expected):
    s, _ = one_cycle("kick", 100, 0, ball=(0.5, 0, 1.0, 0), profile=profile)
    np.testing.assert_allclose(ball_of(s), expected, atol=1e-9)


@pytest.mark.parametrize(("speed", "expected_body"), [(0.24, 40.9090909), (0.0, 90.0)])
def test_t7_turn_with_inertia(speed, expected_body):
    s, _ = one_cycle("turn", 90, player=(0, 0, speed, 0))
    assert math.degrees(s[physics.P_BODY]) == pytest.approx(expected_body, abs=1e-6)
    np.testing.assert_allclose(player_of(s), [speed, 0, 0.4 * speed, 0], atol=1e-12)


def test_t8_collision_pushes_out_and_reverses():
    s, events = one_cycle(ball=(1.0, 0, -0.7, 0))
    assert events[physics.E_COLLISION]
    np.testing.assert_allclose(ball_of(s), [0.3425, 0, 0.0658, 0], atol=1e-9)
    np.testing.assert_allclose(player_of(s), [-0.0425, 0, 0, 0], atol=1e-9)


def test_t9_kick_from_behind_at_the_edge_then_collision():
    s, events = one_cycle("kick", 100, 0, ball=(-1.08, 0, 0, 0))
    assert events[physics.E_KICK_OK] and events[physics.E_COLLISION]
    np.testing.assert_allclose(ball_of(s), [0.329910714, 0, -0.127353214, 0], atol=1e-8)
    np.testing.assert_allclose(player_of(s), [-0.0550892858, 0, 0, 0], atol=1e-8)
    s, events = one_cycle("kick", 100, 0, ball=(-1.09, 0, 0, 0))
    assert not events[physics.E_KICK_OK]
    np.testing.assert_allclose(ball_of(s), [-1.09, 0, 0, 0])


def test_t10_dash_into_a_resting_ball():
    s, events = one_cycle("dash", 100, ball=(0.9, 0, 0, 0))
    assert events[physics.E_COLLISION]
    np.testing.assert_allclose(player_of(s), [0.5575, 0, -0.024, 0], atol=1e-9)
    np.testing.assert_allclose(ball_of(s), [0.9425, 0, 0, 0], atol=1e-9)
    assert s[physics.S_STAMINA] == 7945


def test_t11_negative_kick_power():
    s, _ = one_cycle("kick", -50, 90, ball=(0.6, 0, 0, 0))
    np.testing.assert_allclose(ball_of(s), [0.6, -1.24633929, 0, -1.17155893], atol=1e-8)


def test_t12_free_rolling_ball_is_not_capped():
    s, _ = one_cycle(ball=(0, 5, 2, 0))
    np.testing.assert_allclose(ball_of(s), [2, 5, 1.88, 0], atol=1e-12)


def test_t13_v19_bipedal_dash_with_short_stamina_turns_the_body():
    profile = make_profile(V19, stamina_max=40)
    s, _ = one_cycle("dash", 100, profile=profile)
    np.testing.assert_allclose(player_of(s), [0.554210526, 0, 0.221684211, 0], atol=1e-8)
    assert math.degrees(s[physics.P_BODY]) == pytest.approx(-2.71401061, abs=1e-7)
    assert s[physics.S_STAMINA] == pytest.approx(40)
    assert s[physics.S_EFFORT] == pytest.approx(0.995) and s[physics.S_RECOVERY] == pytest.approx(0.998)
    assert s[physics.S_CAPACITY] == pytest.approx(130560)
    single_leg = dataclasses.replace(profile, dash_model="single")
    s, _ = one_cycle("dash", 100, profile=single_leg)
    np.testing.assert_allclose(player_of(s), [0.54, 0, 0.216, 0], atol=1e-12)
    assert s[physics.P_BODY] == 0


def test_t14_effort_and_recovery_drop_below_the_threshold():
    s, _ = one_cycle("dash", 100, stamina=2400)
    np.testing.assert_allclose(player_of(s), [0.6, 0, 0.24, 0], atol=1e-12)
    assert s[physics.S_RECOVERY] == pytest.approx(0.998) and s[physics.S_EFFORT] == pytest.approx(0.995)
    assert s[physics.S_STAMINA] == pytest.approx(2344.91) and s[physics.S_CAPACITY] == pytest.approx(130555.09)


def test_t15_heterogeneous_type_seed_42():
    hetero = generate_player_types(V19, seed=42)[1]  # noise off: kick_rand 0, the other parameters unchanged
    s, _ = one_cycle("dash", 100, player_type=hetero)
    np.testing.assert_allclose(player_of(s), [0.455010019, 0, 0.208990013, 0], atol=1e-8)
    s, _ = one_cycle("kick", 100, 0, ball=(1.14, 0, 0, 0), player_type=hetero)
    np.testing.assert_allclose(ball_of(s), [3.16583775, 0, 1.90428748, 0], atol=1e-7)
    s, _ = one_cycle("turn", 90, player=(0, 0, 0.2, 0), player_type=hetero)
    assert math.degrees(s[physics.P_BODY]) == pytest.approx(39.1893383, abs=1e-6)
    assert s[physics.P_VX] == pytest.approx(0.2 * hetero.player_decay)


def test_t16_v11_backward_dash_costs_double():
    s, _ = one_cycle("dash", -100, profile=V11)
    np.testing.assert_allclose(player_of(s), [-0.6, 0, -0.24, 0], atol=1e-12)
    assert s[physics.S_STAMINA] == pytest.approx(3845)
    s, _ = one_cycle("dash", -100, profile=V19)  # v17+: clamped to power 0, nothing happens
    np.testing.assert_allclose(player_of(s), [0, 0, 0, 0])
    assert s[physics.S_STAMINA] == 8000


def test_v11_effort_bug_raises_effort_from_the_decrease_threshold():
    profile = V11
    weak = default_player_type(profile)._replace(effort_max=1.0)
    types = stack_player_types([weak])
    state = physics.new_state(1)
    physics.recover(state, types, profile)
    state[0, physics.S_STAMINA] = 0.4 * profile.server.stamina_max  # above effort_dec_thr, below effort_inc_thr
    state[0, physics.S_EFFORT] = 0.9
    physics.step(state, types, np.zeros((1, 3)), np.full((1, physics.N_UNIFORMS), 0.5), physics.profile_constants(profile))
    assert state[0, physics.S_EFFORT] == pytest.approx(0.91)
    fixed = dataclasses.replace(profile, effort_inc_uses_dec_thr=False)
    state[0, physics.S_STAMINA] = 0.4 * profile.server.stamina_max
    state[0, physics.S_EFFORT] = 0.9
    physics.step(state, types, np.zeros((1, 3)), np.full((1, physics.N_UNIFORMS), 0.5), physics.profile_constants(fixed))
    assert state[0, physics.S_EFFORT] == pytest.approx(0.9)


def test_step_rejects_mismatched_shapes():
    state = physics.new_state(2)
    with pytest.raises(ValueError, match="commands must have shape"):
        physics.step(
            state,
            np.zeros((2, physics.TYPE_SIZE)),
            np.zeros((3, 3)),
            np.zeros((2, physics.N_UNIFORMS)),
            physics.profile_constants(V19),
        )


@pytest.mark.parametrize(
    ("state", "types", "commands", "message"),
    [
        (
            np.zeros((2, physics.STATE_SIZE), dtype=np.float32),
            np.zeros((2, physics.TYPE_SIZE)),
            np.zeros((2, 3)),
            "state must be",
        ),
        (np.zeros((2, physics.STATE_SIZE))[:, ::-1], np.zeros((2, physics.TYPE_SIZE)), np.zeros((2, 3)), "C-contiguous"),
        (np.zeros((2, 5)), np.zeros((2, physics.TYPE_SIZE)), np.zeros((2, 3)), "state must have shape"),
        (np.zeros((2, physics.STATE_SIZE)), np.zeros((2, 3)), np.zeros((2, 3)), "types must have shape"),
        (np.zeros((2, physics.STATE_SIZE)), np.zeros((2, physics.TYPE_SIZE)), np.full((2, 3), 7.0), "command kinds"),
        (np.zeros((2, physics.STATE_SIZE)), np.zeros((2, physics.TYPE_SIZE)), [["dash", 1, 2]] * 2, "commands must be"),
    ],
)
def test_step_checks_arrays_before_the_kernel_and_changes_nothing(state, types, commands, message):
    kept = np.array(state, copy=True)
    with pytest.raises(ValueError, match=message):
        physics.step(state, types, commands, np.zeros((2, physics.N_UNIFORMS)), physics.profile_constants(V19))
    np.testing.assert_array_equal(state, kept)


def test_recover_checks_its_arrays():
    with pytest.raises(ValueError, match="types must have shape"):
        physics.recover(physics.new_state(3), np.zeros((2, physics.TYPE_SIZE)), V19)
