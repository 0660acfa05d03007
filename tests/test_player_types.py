"""Heterogeneous player types against docs/physics.md §7 and the recorded rcssserver 19.0.0 messages."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robocup_dribble.params import EPS, make_profile
from robocup_dribble.player_types import (
    TYPE_FIELDS,
    PlayerType,
    ServerRandom,
    default_player_type,
    draw_type_table,
    generate_player_types,
    stack_player_types,
)
from tests.conftest import golden_file

SEEDS = st.integers(min_value=0, max_value=2**32 - 1)


@pytest.fixture(scope="module")
def golden() -> dict:
    return json.loads(golden_file("rcss-player-types.json").read_text())


def assert_matches_printed(types: list[PlayerType], printed: list[dict]) -> None:
    """The server prints 6 significant digits."""
    assert len(types) == len(printed)
    for t, p in zip(types, printed, strict=True):
        for name in TYPE_FIELDS:
            ours = getattr(t, name)
            assert math.isclose(ours, p[name], rel_tol=1e-5, abs_tol=1e-9), (p["id"], name, ours, p[name])


def with_player(profile, **changes):
    return dataclasses.replace(profile, player=dataclasses.replace(profile.player, **changes))


# --- basics -----------------------------------------------------------------------------------


def test_field_order_is_the_physics_column_order():
    assert TYPE_FIELDS == (
        "player_speed_max", "stamina_inc_max", "player_decay", "inertia_moment", "dash_power_rate", "player_size",
        "kickable_margin", "kick_rand", "extra_stamina", "effort_max", "effort_min", "kick_power_rate",
        "foul_detect_probability", "catchable_area_l_stretch",
    )  # fmt: skip


def test_default_types():
    t = default_player_type("v19")
    assert tuple(t) == (1.05, 45.0, 0.4, 5.0, 0.006, 0.3, 0.7, 0.1, 50.0, 1.0, 0.6, 0.027, 0.5, 1.0)
    assert t.kickable_area(0.085) == pytest.approx(1.085)
    assert t.terminal_speed == pytest.approx(1.0)
    v11 = default_player_type("v11")
    assert (v11.player_speed_max, v11.kick_rand, v11.extra_stamina) == (1.2, 0.0, 0.0)


def test_stack_and_from_array_round_trip():
    types = generate_player_types("v19", 7)
    arr = stack_player_types(types)
    assert arr.shape == (18, len(TYPE_FIELDS)) and arr.dtype == np.float64
    assert [PlayerType.from_array(row) for row in arr] == types
    assert [PlayerType._make(row) for row in arr.tolist()] == types and PlayerType(*arr[3].tolist()) == types[3]
    assert all(type(v) is float for v in PlayerType.from_array(arr[1]))
    assert stack_player_types([]).shape == (0, len(TYPE_FIELDS))
    with pytest.raises(ValueError):
        PlayerType.from_array([1.0, 2.0])


# --- the server's random source ---------------------------------------------------------------


def test_numpy_random_state_is_std_mt19937():
    raw = np.random.RandomState(5489).randint(0, 2**32, size=10000, dtype=np.uint64)
    assert raw[0] == 3499211612 and raw[1] == 581869302
    assert raw[-1] == 4123659995  # the C++ standard's check value for default-seeded std::mt19937


def test_server_random_pairs_raw_outputs_across_blocks():
    raw = np.random.RandomState(42).randint(0, 2**32, size=40, dtype=np.uint64).astype(np.float64)
    expected = (raw[0::2] + raw[1::2] * 2.0**32) / 2.0**64
    sr = ServerRandom(42, block=3)
    got = np.concatenate([sr.canonical(1), sr.canonical(5), sr.canonical(0), sr.canonical(14)])
    np.testing.assert_array_equal(got, expected)
    assert sr.used == 20
    np.testing.assert_array_equal(ServerRandom(42).uniform(2.0, 5.0, 20), 2.0 + 3.0 * expected)


def test_server_random_clamps_below_one():
    class AllOnes:
        def randint(self, lo, hi, size, dtype):
            return np.full(size, 2**32 - 1, dtype=dtype)

    sr = ServerRandom(0)
    sr._engine = AllOnes()
    u = sr.canonical(4)
    assert np.all(u < 1.0) and u[0] == np.nextafter(1.0, 0.0)


def test_server_random_rejects_seeds_the_server_would_replace():
    for bad in (-1, 2**32):
        with pytest.raises(ValueError):
            ServerRandom(bad)


# --- exact reproduction of the server ---------------------------------------------------------


def test_seed_42_full_precision():
    types = generate_player_types("v19", 42)
    expected = {
        1: dict(player_decay=0.4593085968575692, inertia_moment=6.48271492143923, dash_power_rate=0.005166869575786737,
                stamina_inc_max=49.998782545279575, kickable_margin=0.7559381995225323, kick_rand=0.15593819952253227,
                extra_stamina=79.84250807900283, effort_max=0.8806299676839887, effort_min=0.4806299676839887,
                catchable_area_l_stretch=1.13374982726453),
        2: dict(player_decay=0.31999498410876814, inertia_moment=2.9998746027192036, dash_power_rate=0.005718497775708364,
                stamina_inc_max=46.689013345749814, kickable_margin=0.6667417223037302, kick_rand=0.06674172230373025,
                extra_stamina=57.14334072080808, effort_max=0.9714266371167677, effort_min=0.5714266371167677,
                catchable_area_l_stretch=1.1952665420278026),
        8: dict(player_decay=0.4219993313365634, dash_power_rate=0.0064663898264501135, kickable_margin=0.6346729294412949),
    }  # fmt: skip
    for i, fields in expected.items():
        for name, value in fields.items():
            assert getattr(types[i], name) == pytest.approx(value, rel=1e-12), (i, name)


def test_seed_sweep_matches_server(golden):
    runs = golden["seed_sweep"]["runs"]
    assert len(runs) == 20
    for run in runs:
        assert [p["id"] for p in run["player_types"]] == list(range(18))
        assert_matches_printed(generate_player_types("v19", run["player_random_seed"]), run["player_types"])


@pytest.mark.parametrize("run_name", ["det", "det-negdash", "noise"])
def test_server_runs_match(golden, run_name):
    run = golden["server_runs"][run_name]
    opts = run["options"]
    noise_and_dash = {"player_rand", "ball_rand", "kick_rand", "min_dash_power"}
    server = {k.split("::", 1)[1]: float(v) for k, v in opts.items() if k.split("::", 1)[1] in noise_and_dash}
    profile = make_profile("v19", **server)
    factor = opts.get("player::kick_rand_delta_factor")
    types = generate_player_types(profile, seed=opts["player::random_seed"], kick_rand_delta_factor=factor)
    assert_matches_printed(types, run["player_types"])


def test_kick_rand_delta_factor_0_changes_only_kick_rand():
    base = generate_player_types("v19", 3)
    zero = generate_player_types("v19", 3, kick_rand_delta_factor=0.0)
    for b, z in zip(base, zero, strict=True):
        assert z.kick_rand == 0.1
        assert b._replace(kick_rand=0.1) == z


# --- ranges and rules -------------------------------------------------------------------------

V11_RANGES = {  # docs/physics.md §7.3, v11 column
    "player_speed_max": (1.2, 1.2), "player_decay": (0.4, 0.6), "inertia_moment": (5.0, 10.0),
    "dash_power_rate": (0.006, 0.008), "stamina_inc_max": (25.0, 45.0), "player_size": (0.3, 0.3),
    "kickable_margin": (0.7, 0.9), "kick_rand": (0.0, 0.1), "extra_stamina": (0.0, 100.0), "effort_max": (0.8, 1.0),
    "effort_min": (0.4, 0.6), "kick_power_rate": (0.027, 0.027), "catchable_area_l_stretch": (1.0, 1.0),
}  # fmt: skip
V19_RANGES = {  # docs/physics.md §7.3, v13-v19 column
    "player_speed_max": (1.05, 1.05), "player_decay": (0.3, 0.5), "inertia_moment": (2.5, 7.5),
    "dash_power_rate": (0.0048, 0.0068), "stamina_inc_max": (40.2, 52.2), "player_size": (0.3, 0.3),
    "kickable_margin": (0.6, 0.8), "kick_rand": (0.0, 0.2), "extra_stamina": (50.0, 100.0), "effort_max": (0.8, 1.0),
    "effort_min": (0.4, 0.6), "kick_power_rate": (0.027, 0.027), "foul_detect_probability": (0.5, 0.5),
    "catchable_area_l_stretch": (1.0, 1.3),
}  # fmt: skip


def assert_in_ranges(table: np.ndarray, ranges: dict) -> None:
    for name, (lo, hi) in ranges.items():
        col = table[..., TYPE_FIELDS.index(name)]
        tol = 1e-12 * max(1.0, abs(hi))
        assert np.all(col >= lo - tol) and np.all(col <= hi + tol), name


@settings(max_examples=40, deadline=None)
@given(seed=SEEDS)
def test_v11_types_lie_in_v11_ranges(seed):
    types = generate_player_types("v11", seed)
    assert len(types) == 7
    assert types[0] == default_player_type("v11") and types[0].player_speed_max == 1.2
    assert_in_ranges(stack_player_types(types[1:]), V11_RANGES)
    for t in types[1:]:
        assert t.kick_rand == pytest.approx(0.5 * (t.kickable_margin - 0.7), abs=1e-15)
        assert t.inertia_moment == pytest.approx(5 + 25 * (t.player_decay - 0.4), abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(seed=SEEDS)
def test_v19_types_lie_in_ranges_and_acceptance_window(seed):
    types = generate_player_types("v19", seed)
    assert types[0] == default_player_type("v19")
    assert_in_ranges(stack_player_types(types), V19_RANGES)
    for t in types[1:]:
        assert 0.75 - EPS < t.terminal_speed < 1.05 + EPS
        assert t.kick_rand == pytest.approx(0.1 + (t.kickable_margin - 0.7), abs=1e-15)
        assert t.stamina_inc_max == pytest.approx(45 - 6000 * (t.dash_power_rate - 0.006), abs=1e-9)


def test_no_random_number_is_drawn_when_min_equals_max():
    # without an acceptance window every first trial is accepted, so the count of draws is exact
    sr = ServerRandom(5)
    draw_type_table("v11", 1, sr)
    assert sr.used == 6 * 4  # decay, dash power rate, kickable margin, extra stamina; no catchable-area draw
    sr = ServerRandom(5)
    draw_type_table(dataclasses.replace(make_profile("v19"), hetero_acceptance="none"), 1, sr)
    assert sr.used == 17 * 5  # ... plus the stretch
    sr = ServerRandom(5)
    fixed = with_player(dataclasses.replace(make_profile("v19"), hetero_acceptance="none"), catchable_area_l_stretch_min=1.2,
                        catchable_area_l_stretch_max=1.2)  # fmt: skip
    table = draw_type_table(fixed, 1, sr)
    assert sr.used == 17 * 4 and np.all(table[0, 1:, TYPE_FIELDS.index("catchable_area_l_stretch")] == 1.2)


def test_swapped_bounds_are_the_same_range():
    v19 = make_profile("v19")
    swapped = with_player(v19, player_decay_delta_min=0.1, player_decay_delta_max=-0.1,
                          kickable_margin_delta_min=0.1, kickable_margin_delta_max=-0.1)  # fmt: skip
    assert generate_player_types(swapped, 9) == generate_player_types(v19, 9)
    np.testing.assert_array_equal(draw_type_table(swapped, 1, ServerRandom(9)), draw_type_table(v19, 1, ServerRandom(9)))


@pytest.mark.parametrize("n_sets", [1, 3])
def test_default_type_after_1000_failed_trials(n_sets):
    impossible = make_profile("v19", player_speed_max_min=2.0)  # no type can reach the window
    sr = ServerRandom(1)
    table = draw_type_table(impossible, n_sets, sr)
    np.testing.assert_array_equal(table, np.broadcast_to(stack_player_types([default_player_type(impossible)]), table.shape))
    assert sr.used == n_sets * 17 * 1000 * 5
    assert generate_player_types(impossible, 1) == [default_player_type(impossible)] * 18


def test_a_rejected_trial_draws_nothing_more():
    """docs/physics.md §7.2: a rejection ends the trial at once; the next trial starts again from the first draw."""
    profile = with_player(dataclasses.replace(make_profile("v19", kick_rand=0.0), hetero_acceptance="none"), player_types=2)
    script = [0.5, 0.5, 0.2, 0.5, 0.5, 0.9, 0.25, 0.5]  # trial 1 stops after the kickable margin (kick_rand < 0)

    class Scripted:  # the script, then 0.5s; draw_type_table gives back what it fetched beyond its needs
        used = 0

        def __call__(self, lo, hi, n):
            values = (script + [0.5] * n)[self.used : self.used + n]
            self.used += n
            return lo + (hi - lo) * np.array(values)

        def unread(self, n):
            self.used -= n

    uniform = Scripted()
    t = PlayerType.from_array(draw_type_table(profile, 1, uniform)[0, 1])
    assert uniform.used == 8  # decay, dash power rate, margin; then decay, dash power rate, margin, extra stamina, stretch
    assert t.kickable_margin == pytest.approx(0.7 + 0.08) and t.kick_rand == pytest.approx(0.08)
    assert t.extra_stamina == pytest.approx(62.5) and t.effort_max == pytest.approx(0.95)
    assert t.catchable_area_l_stretch == pytest.approx(1.15) and t.player_decay == pytest.approx(0.4)


# --- one set and many sets --------------------------------------------------------------------

PROFILES = {
    "v19": make_profile("v19"),
    "v11": make_profile("v11"),
    "v19 kick_rand 0": make_profile("v19", kick_rand=0.0),  # kick_rand < 0 rejects in mid-trial
    "v19 kick_rand 0.03": make_profile("v19", kick_rand=0.03),
    "v19 factor 0": with_player(make_profile("v19", kick_rand=0.0), kick_rand_delta_factor=0.0),
}


@pytest.mark.parametrize("name", list(PROFILES))
def test_generate_player_types_is_one_set(name):
    profile = PROFILES[name]
    for seed in range(10):
        types = generate_player_types(profile, seed)
        assert len(types) == profile.player.player_types and all(isinstance(t, PlayerType) for t in types)
        np.testing.assert_array_equal(stack_player_types(types), draw_type_table(profile, 1, ServerRandom(seed))[0])


@pytest.mark.parametrize("kick_rand", [0.1, 0.0])  # with 0, every trial whose margin is below 0.7 is rejected
def test_many_sets_from_a_numpy_generator(kick_rand):
    rng = np.random.default_rng(0)
    profile = make_profile("v19", kick_rand=kick_rand)
    table = draw_type_table(profile, 500, lambda lo, hi, n: rng.uniform(lo, hi, n))
    assert table.shape == (500, 18, len(TYPE_FIELDS)) and table.dtype == np.float64
    np.testing.assert_array_equal(table[:, 0], np.broadcast_to(stack_player_types([default_player_type(profile)]), (500, 14)))
    assert_in_ranges(table[:, 1:], V19_RANGES)
    c = {name: table[:, 1:, j] for j, name in enumerate(TYPE_FIELDS)}
    v = 100 * c["dash_power_rate"] * c["effort_max"] / (1 - c["player_decay"])
    assert np.all((0.75 - EPS < v) & (v < 1.05 + EPS))
    np.testing.assert_allclose(c["inertia_moment"], 5 + 25 * (c["player_decay"] - 0.4), atol=1e-12)
    np.testing.assert_allclose(c["kick_rand"], kick_rand + (c["kickable_margin"] - 0.7), atol=1e-15)
    assert np.all(c["kick_rand"] >= 0) and (kick_rand > 0 or np.all(c["kickable_margin"] >= 0.7))
    np.testing.assert_allclose(c["effort_max"] - c["effort_min"], 0.4, atol=1e-12)
    np.testing.assert_allclose(c["extra_stamina"], 50 + (1 - c["effort_max"]) / 0.004, atol=1e-9)
    assert len(np.unique(table[:, 1:].reshape(-1, 14), axis=0)) == 500 * 17  # every set differs
    assert not np.array_equal(table[0], table[1])


def test_many_v11_sets_lie_in_v11_ranges():
    rng = np.random.default_rng(2)
    table = draw_type_table("v11", 300, lambda lo, hi, n: rng.uniform(lo, hi, n))
    assert table.shape == (300, 7, len(TYPE_FIELDS))
    assert_in_ranges(table[:, 1:], V11_RANGES)
    c = {name: table[:, 1:, j] for j, name in enumerate(TYPE_FIELDS)}
    assert c["player_decay"].min() < 0.41 and c["player_decay"].max() > 0.59  # no acceptance window cuts the range
    np.testing.assert_allclose(c["kick_rand"], 0.5 * (c["kickable_margin"] - 0.7), atol=1e-15)


def test_many_sets_follow_the_one_type_at_a_time_distribution():
    """Many sets drawn at once (their values interleaved in the stream) follow the distribution of one set at a time."""
    rng = np.random.default_rng(1)
    uniform = lambda lo, hi, n: rng.uniform(lo, hi, n)  # noqa: E731
    flat = draw_type_table("v19", 400, uniform)[:, 1:].reshape(-1, 14)
    one_by_one = np.concatenate([draw_type_table("v19", 1, uniform)[0, 1:] for _ in range(400)])
    for name in ("player_decay", "dash_power_rate", "extra_stamina", "kickable_margin", "catchable_area_l_stretch"):
        j = TYPE_FIELDS.index(name)
        a, b = flat[:, j], one_by_one[:, j]
        se = math.sqrt(a.var() / a.size + b.var() / b.size)
        assert abs(a.mean() - b.mean()) < 4 * se, name


def test_zero_sets_and_bad_input():
    assert draw_type_table("v19", 0, ServerRandom(1)).shape == (0, 18, 14)
    with pytest.raises(ValueError):
        draw_type_table("v19", -1, ServerRandom(1))
    with pytest.raises(ValueError):
        draw_type_table("v99", 1, ServerRandom(1))
