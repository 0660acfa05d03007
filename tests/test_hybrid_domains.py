"""hybrid_domains: Goal-v0, Moving-v0, Sliding-v0, CatchPoint-v0 against hand-computed steps, and their API rules."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.error import ResetNeeded
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st

import hybrid_domains
from hybrid_domains import CatchPointEnv, GoalEnv, MovingEnv, SlidingEnv, catch_point, goal, moving
from hybrid_domains.baselines import policy_figures, random_policy, scripted_policy
from hybrid_domains.reference_inputs import GoalFeatures, ScaleReward, keeper_projection

ENV_IDS = tuple(hybrid_domains.ENV_CLASSES)
Z1, Z2 = np.zeros(1, dtype=np.float32), np.zeros(2, dtype=np.float32)
EMPTY = np.zeros(0, dtype=np.float32)


def goal_action(k: int, kick=(0.0, 0.0), left=0.0, right=0.0):
    return k, (np.array(kick, dtype=np.float32), np.array([left], dtype=np.float32), np.array([right], dtype=np.float32))


def move(direction: float):
    return catch_point.MOVE, (np.array([direction], dtype=np.float32), EMPTY)


CATCH = (catch_point.CATCH, (Z1, EMPTY))


def a_valid_action(env_id: str):
    return {
        "Goal-v0": goal_action(goal.KICK_TO, (10.0, 3.0)),
        "Moving-v0": (moving.ACCELERATE, np.array([0.5, 0.0], dtype=np.float32)),
        "Sliding-v0": (moving.ACCELERATE, np.array([0.5, 0.0], dtype=np.float32)),
        "CatchPoint-v0": move(1.0),
    }[env_id]


# --- registration, Gymnasium API, seeding ------------------------------------------------------------------------


@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.filterwarnings("ignore:.*symmetric and normalized space")  # the originals' parameter units, by design
def test_registered_envs_pass_gymnasium_check_env(env_id):
    env = gym.make(env_id)
    assert isinstance(env.unwrapped, hybrid_domains.ENV_CLASSES[env_id])
    check_env(env.unwrapped)
    assert gym.make(f"hybrid_domains:{env_id}").unwrapped.__class__ is hybrid_domains.ENV_CLASSES[env_id]


def test_action_layouts_are_the_originals():
    types, params = GoalEnv().action_space.spaces
    assert types.n == 3 and [box.shape for box in params.spaces] == [(2,), (1,), (1,)]
    np.testing.assert_allclose(params.spaces[0].high, [40, 15])
    np.testing.assert_allclose(params.spaces[1].high, [7.01])
    types, shared = MovingEnv().action_space.spaces  # gym-hybrid's shared Tuple(Discrete(3), Box(2))
    assert types.n == 3 and shared.shape == (2,) and list(shared.low) == [0, -1] and list(shared.high) == [1, 1]
    types, params = CatchPointEnv().action_space.spaces
    assert types.n == 2 and [box.shape for box in params.spaces] == [(1,), (0,)]
    obs_space = GoalEnv().observation_space
    assert obs_space.spaces[0].shape == (14,) and obs_space.spaces[1].n == 200


def rollout(env_id: str, seed: int, steps: int = 150):
    env = gym.make(env_id)
    env.action_space.seed(1)
    out = [env.reset(seed=seed)[0]]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        out += [obs, reward, terminated, truncated, sorted(info.items())]
        if terminated or truncated:
            out.append(env.reset()[0])
    return out


def flat(items) -> np.ndarray:
    return np.concatenate([np.ravel(np.asarray(x[0] if isinstance(x, tuple) else x, dtype=np.float64)) for x in items])


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_same_seed_same_trajectory_other_seed_differs(env_id):
    first, second, other = rollout(env_id, 7), rollout(env_id, 7), rollout(env_id, 8)
    assert len(first) == len(second)
    for a, b in zip(first, second, strict=True):
        if isinstance(a, list):
            assert a == b
        else:
            np.testing.assert_array_equal(flat([a]), flat([b]))
    assert not np.array_equal(flat([first[0]]), flat([other[0]]))


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_step_after_the_episode_ended_is_refused_until_reset(env_id):
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    env.action_space.seed(0)
    for _ in range(10_000):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            break
    assert terminated or truncated
    with pytest.raises(ResetNeeded, match="the episode has ended"):
        env.step(env.action_space.sample())
    env.reset(seed=1)
    env.step(env.action_space.sample())  # a new episode plays


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_render_modes_are_named(env_id):
    with pytest.warns(UserWarning, match="render_modes"), pytest.raises(ValueError, match="render_mode must be None"):
        gym.make(env_id, render_mode="human")  # Gymnasium warns, the env says which modes exist (none)
    with pytest.raises(NotImplementedError, match="no render modes"):
        gym.make(env_id).unwrapped.render()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_step_before_reset_is_refused(env_id):
    with pytest.raises(ResetNeeded):
        hybrid_domains.ENV_CLASSES[env_id]().step(a_valid_action(env_id))


# --- bad actions: a ValueError that changes nothing ---------------------------------------------------------------

BAD_ACTIONS = {
    "Goal-v0": [
        (3, "An action must be a pair"),
        ((1,), "An action must be a pair"),
        ((3, (Z2, Z1, Z1)), r"an integer in 0\.\.2, got 3"),
        ((-1, (Z2, Z1, Z1)), r"an integer in 0\.\.2"),
        ((True, (Z2, Z1, Z1)), "an integer"),
        ((0.5, (Z2, Z1, Z1)), "an integer"),
        (("0", (Z2, Z1, Z1)), "an integer"),
        ((0, (Z2, Z1)), "must be a tuple"),
        ((0, "abc"), "must be a tuple"),
        ((0, (Z1, Z1, Z1)), r"p_0 must hold 2"),
        ((0, (np.array(["a", "b"]), Z1, Z1)), "real vector"),
        ((0, (np.array([np.nan, 0.0]), Z1, Z1)), "finite"),
        ((1, (Z2, np.array([np.inf]), Z1)), "finite"),
    ],
    "Moving-v0": [
        ((0,), "An action must be a pair"),
        ((3, Z2), r"an integer in 0\.\.2"),
        ((None, Z2), "an integer"),
        ((0, Z1), "must hold 2"),
        ((0, np.array([1j, 0])), "real vector"),
        ((1, np.array([0.0, np.nan])), "finite"),
    ],
    "CatchPoint-v0": [
        ((2, (Z1, EMPTY)), r"an integer in 0\.\.1"),
        ((0, (Z2, EMPTY)), "p_0 must hold 1"),
        ((1, (Z1, Z1)), "p_1 must hold 0"),
        ((0, (np.array([np.inf]), EMPTY)), "finite"),
    ],
}
BAD_ACTIONS["Sliding-v0"] = BAD_ACTIONS["Moving-v0"]


@pytest.mark.parametrize(("env_id", "bad", "message"), [(e, b, m) for e, cases in BAD_ACTIONS.items() for b, m in cases])
def test_bad_actions_raise_and_change_nothing(env_id, bad, message):
    env, twin = gym.make(env_id).unwrapped, gym.make(env_id).unwrapped
    env.reset(seed=4)
    twin.reset(seed=4)
    with pytest.raises(ValueError, match=message):
        env.step(bad)
    assert env.np_random.bit_generator.state == twin.np_random.bit_generator.state
    for _ in range(3):  # the rejected action left no trace: the two envs go on alike
        out, twin_out = env.step(a_valid_action(env_id)), twin.step(a_valid_action(env_id))
        np.testing.assert_array_equal(flat([out[0]]), flat([twin_out[0]]))
        assert out[1:4] == twin_out[1:4]
        if out[2]:
            break


# --- Moving-v0 / Sliding-v0 --------------------------------------------------------------------------------------


def placed(cls, x=0.0, y=0.0, heading=0.0, speed=0.0, target=(0.5, 0.0), direction=None, steps=0):
    env = cls()
    env.reset(seed=0)
    env.x, env.y, env.heading, env.speed = x, y, heading, speed
    env.direction = heading if direction is None else direction
    env.target_x, env.target_y = target
    env.steps = steps
    return env


@pytest.mark.parametrize("cls", [MovingEnv, SlidingEnv])
def test_accelerate_from_rest(cls):
    # speed = 0.5 * 0.5 = 0.25; x = 0.005 * 0.25 = 0.00125; distance 0.5 -> 0.49875;
    # reward = 0.5 - 0.49875 - 0.001 = 0.00025
    env = placed(cls)
    obs, reward, terminated, truncated, info = env.step((moving.ACCELERATE, np.array([0.5, -0.7], dtype=np.float32)))
    assert env.speed == pytest.approx(0.25) and env.x == pytest.approx(0.00125) and env.y == 0.0
    assert reward == pytest.approx(0.00025) and not (terminated or truncated or info["success"])
    np.testing.assert_allclose(obs, [0.00125, 0, 0.25, 1, 0, 0.5, 0, 0.49875, 0, 1 / 200], rtol=1e-6, atol=1e-7)


def test_moving_turn_turns_the_motion_sliding_keeps_it():
    # Moving: heading = 0 + (pi / 2) * 0.5 = pi / 4, and it moves along it: x = y = 0.005 * 1 * cos(pi / 4) = 0.0035355
    env = placed(MovingEnv, speed=1.0)
    env.step((moving.TURN, np.array([0.9, 0.5], dtype=np.float32)))
    assert env.heading == pytest.approx(math.pi / 4) and env.x == pytest.approx(0.0035355, abs=1e-7) == env.y
    # Sliding: the heading turns, the velocity keeps direction 0: x = 0.005, y = 0
    env = placed(SlidingEnv, speed=1.0)
    env.step((moving.TURN, np.array([0.9, 0.5], dtype=np.float32)))
    assert env.heading == pytest.approx(math.pi / 4) and env.x == pytest.approx(0.005) and env.y == 0.0


def test_sliding_adds_the_acceleration_as_a_vector():
    # velocity (1, 0), heading pi/2, acceleration 0.5 * 1.0: (1, 0) + (0, 0.5) = (1, 0.5): speed sqrt(1.25) = 1.118034,
    # direction atan2(0.5, 1) = 0.463648; x = 0.005 * 1 = 0.005, y = 0.005 * 0.5 = 0.0025
    env = placed(SlidingEnv, heading=math.pi / 2, speed=1.0, direction=0.0)
    env.step((moving.ACCELERATE, np.array([2.0, 0.0], dtype=np.float32)))  # 2.0 is clipped to 1 (gym-hybrid's rule)
    assert env.speed == pytest.approx(1.118034) and env.direction == pytest.approx(0.463648, abs=1e-6)
    assert env.x == pytest.approx(0.005) and env.y == pytest.approx(0.0025)


@pytest.mark.parametrize("cls", [MovingEnv, SlidingEnv])
def test_stopping_inside_the_target_succeeds(cls):
    # speed 0.05 < brake 0.1 -> 0; no move; distance 0 < 0.1 and speed 0: reward 0 - 0 - 0.001 + 1 = 0.999
    env = placed(cls, x=0.5, speed=0.05)
    obs, reward, terminated, truncated, info = env.step((moving.BRAKE, np.array([0.3, 0.3], dtype=np.float32)))
    assert reward == pytest.approx(0.999) and terminated and not truncated and info["success"] and obs[8] == 1.0
    # braking from 0.25 leaves 0.15 (still moving: no success even inside): reward = -0.001 - 0.005 * 0.15 = -0.00175
    env = placed(cls, x=0.5, speed=0.25, target=(0.6, 0.0))
    _, reward, terminated, _, info = env.step((moving.BRAKE, Z2))
    assert env.speed == pytest.approx(0.15) and reward == pytest.approx(0.00075 - 0.001) and not terminated


@pytest.mark.parametrize("cls", [MovingEnv, SlidingEnv])
def test_leaving_the_field_or_the_time_limit_ends_with_minus_one(cls):
    env = placed(cls, x=0.999, speed=1.0)  # x = 0.999 + 0.005 = 1.004 > 1
    _, reward, terminated, truncated, info = env.step((moving.ACCELERATE, Z2))
    assert (reward, terminated, truncated, info["success"]) == (-1.0, True, False, False)
    env = placed(cls, steps=199)  # step 200 is still inside the limit, step 201 ends it
    assert env.step((moving.BRAKE, Z2))[2] is False
    _, reward, terminated, _, _ = env.step((moving.BRAKE, Z2))
    assert reward == -1.0 and terminated


@pytest.mark.parametrize(
    ("kwargs", "message"), [({"max_step": 0}, "max_step"), ({"delta_t": -1.0}, "delta_t"), ({"penalty": math.nan}, "penalty")]
)
def test_bad_moving_arguments_fail_at_construction(kwargs, message):
    with pytest.raises(ValueError, match=message):
        MovingEnv(**kwargs)


# --- CatchPoint-v0 -----------------------------------------------------------------------------------------------


def placed_catch(position=(0.0, 0.0), velocity=(0.0, 0.0), target=(0.5, 0.5)):
    env = CatchPointEnv()
    env.reset(seed=0)
    (env.x, env.y), (env.vx, env.vy), (env.target_x, env.target_y) = position, velocity, target
    return env


def test_catch_point_move_and_catch_by_hand():
    # move(pi/2): F = 2 (sin, cos) = (2, 0); v = 0.75 * 0 + 0.1 * F = (0.2, 0); pos = 0.1 * v = (0.02, 0);
    # d^2 = 0.48^2 + 0.5^2 = 0.4804
    env = placed_catch()
    obs, reward, terminated, truncated, info = env.step(move(math.pi / 2))
    np.testing.assert_allclose(obs, [0.2, 0.0, 0.48, 0.5], atol=1e-6)
    assert reward == pytest.approx(-0.4804) and not (terminated or truncated or info["caught"])
    # catch at 0.1 from the target, at rest: d^2 = 0.01 <= 0.2^2: reward 20 - 0.01 = 19.99, the episode ends
    env = placed_catch(position=(0.1, 0.0), target=(0.0, 0.0))
    _, reward, terminated, _, info = env.step(CATCH)
    assert reward == pytest.approx(19.99) and terminated and info["caught"]
    # a catch drifts on: v = 0.75 * (0.4, 0) = (0.3, 0), x = 0.03; d^2 = 0.97^2 = 0.9409, a miss
    env = placed_catch(velocity=(0.4, 0.0), target=(1.0, 0.0))
    _, reward, terminated, _, info = env.step(CATCH)
    assert env.x == pytest.approx(0.03) and reward == pytest.approx(-0.9409) and not terminated and env.misses == 1


def test_catch_point_ends_at_the_eleventh_miss_and_truncates_at_25_steps():
    env = placed_catch(target=(1.0, 1.0))
    for miss in range(1, 12):
        _, _, terminated, truncated, _ = env.step(CATCH)
        assert terminated == (miss == 11) and not truncated
    env = placed_catch(target=(1.0, 1.0))
    ends = [env.step(move(math.pi))[2:4] for _ in range(25)]  # away from the target: never caught
    assert ends[-1] == (False, True) and all(end == (False, False) for end in ends[:-1])


def test_catch_point_clips_directions_to_pi():
    a, b = placed_catch(), placed_catch()
    a.step(move(math.pi))
    b.step(move(50.0))
    assert (a.x, a.y) == (b.x, b.y)


# --- Goal-v0 -----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("ball", "distance"),
    [
        ((10.0, 0.0), 10.0),  # in front of the goal: 20 - x
        ((10.0, 10.0), math.hypot(10.0, 10.0 - 7.01)),  # beside it: to the post (20, 7.01) = 10.4374
        ((21.0, 9.0), 9.0 - 7.01),  # behind the line, above: y - 7.01
        ((21.0, -8.0), 7.01 + 8.0),  # behind the line, below: gym-goal's 7.01 - y = 15.01 (sic)
        ((21.0, 0.0), 0.0),
    ],
)
def test_goal_distance_is_gym_goals(ball, distance):
    body = goal.ball_body()
    body.x, body.y = ball
    assert goal.goal_distance(body) == pytest.approx(distance)


def test_a_kick_along_the_body_axis_by_hand():
    # player at the origin facing 0, ball at rest 1.5 ahead: kick power factor 1 - 0 - 0.25 * 1.5 / 1.6 = 0.765625.
    # kick-to (20.4, 0): acceleration 0.06 * 20.4 = 1.224 along 0 (no angle noise at angle 0, no velocity noise at
    # rest): power 1.224 / (0.765625 * 0.027) = 59.2 < 100; ball v = 1.224; after one cycle x = 1.5 + 1.224 = 2.724,
    # v = 1.224 * 0.94 = 1.15056
    player, ball = goal.player_body(), goal.ball_body()
    ball.x = 1.5
    assert goal.kick_power(player, ball) == pytest.approx(0.765625)
    goal.kick_to(player, ball, 20.4, 0.0, np.random.default_rng(0))
    goal.move(ball)
    assert ball.x == pytest.approx(2.724) and ball.vx == pytest.approx(1.15056) and ball.y == 0.0 == ball.vy
    # the same kick needing more than power 100 is capped: target 40 -> 0.06 * 40 = 2.4 > 100 * 0.765625 * 0.027 = 2.067
    player, ball = goal.player_body(), goal.ball_body()
    ball.x = 1.5
    goal.kick_to(player, ball, 40.0, 0.0, np.random.default_rng(0))
    assert ball.vx == pytest.approx(100 * 0.765625 * 0.027)


def test_keeper_start_and_collisions_by_hand():
    # ball (1.6, 0): on the line to the goal centre, x clipped into the goal area: (14.5, 0)
    assert goal.keeper_target(1.6, 0.0) == (14.5, 0.0)
    # ball (18, 8): grad = -8 / 2 = -4, yint = 8 + 72 = 80; x = (9.16 - 80) / -4 = 17.71; y = -4 * 17.71 + 80 = 9.16
    x, y = goal.keeper_target(18.0, 8.0)
    assert x == pytest.approx(17.71) and y == pytest.approx(9.16)
    # player (0, 0) and ball (1.0, 0) overlap by 0.3: each moves 0.15 apart, both velocities reverse
    player, ball = goal.player_body(), goal.ball_body()
    ball.x, ball.vx, player.vx = 1.0, 0.5, 0.2
    goal.decollide(player, ball)
    assert player.x == pytest.approx(-0.15) and ball.x == pytest.approx(1.15) and (player.vx, ball.vx) == (-0.2, -0.5)


def test_goal_start_state():
    env = GoalEnv()
    (state, cycles), info = env.reset(seed=3)
    player, ball = state[0:2], state[10:12]
    assert cycles == 0 and info == {"goal": False, "cycles": 0} and player[0] == 0.0 and abs(player[1]) <= 15
    assert np.hypot(*(ball - player)) == pytest.approx(goal.KICKABLE, abs=1e-5)
    assert state[4] == pytest.approx(math.atan2(-player[1], 20.0), abs=1e-6)  # facing the goal centre
    np.testing.assert_array_equal(state[[2, 3, 7, 8, 12, 13]], 0.0)


def test_kick_to_reads_only_x_as_gym_goal_does_and_clips():
    """gym-goal kicks to (x, x): y plays no role; out-of-range parameters act like the bound."""
    results = []
    for kick in ((12.0, -15.0), (12.0, 15.0), (12.0, 3.0)):
        env = GoalEnv()
        env.reset(seed=5)
        results.append(flat([env.step(goal_action(goal.KICK_TO, kick))[0]]))
    np.testing.assert_array_equal(results[0], results[1])
    np.testing.assert_array_equal(results[0], results[2])
    ends = []
    for aim in (7.01, 30.0):
        env = GoalEnv()
        env.reset(seed=5)
        ends.append(flat([env.step(goal_action(goal.SHOOT_GOAL_LEFT, left=aim))[0]]))
    np.testing.assert_array_equal(ends[0], ends[1])


def test_a_shot_runs_until_the_episode_ends_and_the_100th_action_ends_it():
    env = GoalEnv()
    env.reset(seed=0)
    _, reward, terminated, _, info = env.step(goal_action(goal.SHOOT_GOAL_RIGHT, right=-6.0))
    assert terminated and info["cycles"] > 1 and (reward == 50.0) == info["goal"]
    env.reset(seed=0)
    env._actions = 99  # 99 actions taken, the next is the 100th: not simulated, reward -distance of the ball
    ball_x = env.ball.x
    (state, cycles), reward, terminated, truncated, info = env.step(goal_action(goal.KICK_TO, (10.0, 0.0)))
    assert (cycles, terminated, truncated, info["cycles"]) == (0, True, False, 0)
    assert reward == pytest.approx(-(20.0 - ball_x)) and state[10] == pytest.approx(ball_x)


def test_reference_goal_features():
    env = GoalFeatures(GoalEnv())
    obs, _ = env.reset(seed=2)
    assert obs.shape == (17,) and env.observation_space.contains(obs)
    state = obs[:14].astype(np.float64)
    unit = np.array([state[10] - state[5], state[11] - state[6]])
    np.testing.assert_allclose(obs[14:16], unit / np.linalg.norm(unit), rtol=1e-6)
    # keeper (15, 1), ball (5, -1): grad 0.2, the line meets x = 20 at y = -1 + 0.2 * 15 = 2
    assert keeper_projection(np.array([0, 0, 0, 0, 0, 15, 1, 0, 0, 0, 5, -1, 0, 0.0])) == pytest.approx(2.0)
    raw, scaled = GoalEnv(), ScaleReward(GoalEnv())
    raw.reset(seed=0)
    scaled.reset(seed=0)
    shot = goal_action(goal.SHOOT_GOAL_LEFT, left=6.0)
    assert scaled.step(shot)[1] == pytest.approx(raw.step(shot)[1] / 50) != 0.0
    with pytest.raises(ValueError, match="scale"):
        ScaleReward(GoalEnv(), scale=0.0)


# --- property tests ----------------------------------------------------------------------------------------------

wild = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), env_id=st.sampled_from(["Moving-v0", "Sliding-v0"]),
       actions=st.lists(st.tuples(st.integers(0, 2), wild, wild), min_size=1, max_size=250))  # fmt: skip
def test_moving_observations_stay_in_their_box_and_rewards_are_bounded(seed, env_id, actions):
    env = gym.make(env_id).unwrapped
    obs, _ = env.reset(seed=seed)
    for k, p0, p1 in actions:
        obs, reward, terminated, _, info = env.step((k, np.array([p0, p1])))
        assert env.observation_space.contains(obs)
        assert -1.0 <= reward <= 1.0 + env.delta_t * env.observation_space.high[2]
        assert info["success"] == (terminated and reward > 0.5)
        if terminated:
            obs, _ = env.reset()


@settings(max_examples=15, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1), actions=st.lists(st.tuples(st.integers(0, 2), wild, wild, wild), min_size=1, max_size=12)
)
def test_goal_observations_stay_in_their_box_and_rewards_are_the_originals(seed, actions):
    env = GoalEnv()
    obs, _ = env.reset(seed=seed)
    for k, a, b, c in actions:
        obs, reward, terminated, _, info = env.step(goal_action(k, (a, b), c, c))
        assert env.observation_space.contains(obs)
        assert reward == 50.0 if info["goal"] else -45.0 <= reward <= 0.0
        assert reward == 0.0 or terminated
        if terminated:
            obs, _ = env.reset()


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), actions=st.lists(st.tuples(st.integers(0, 1), wild), min_size=1, max_size=40))
def test_catch_point_observations_stay_in_their_box(seed, actions):
    env = CatchPointEnv()
    obs, _ = env.reset(seed=seed)
    for k, d in actions:
        obs, reward, terminated, truncated, info = env.step((k, (np.array([d]), EMPTY)))
        assert env.observation_space.contains(obs)
        assert (19.96 <= reward <= 20.0) if info["caught"] else reward <= 0.0
        if terminated or truncated:
            obs, _ = env.reset()


# --- reference policies ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_scripted_policies_beat_random_ones_on_the_same_episodes(env_id):
    scripted = policy_figures(env_id, scripted_policy(env_id), 60, seed=100)
    again = policy_figures(env_id, scripted_policy(env_id), 60, seed=100)
    uniform = policy_figures(env_id, random_policy(gym.make(env_id).action_space, 0), 60, seed=100)
    assert {k: v for k, v in scripted.items() if k != "steps_per_second"} == {
        k: v for k, v in again.items() if k != "steps_per_second"
    }
    assert scripted["success_share"] > uniform["success_share"] and scripted["return_mean"] > uniform["return_mean"]
    with pytest.raises(ValueError, match="episodes"):
        policy_figures(env_id, scripted_policy(env_id), 0)


def test_the_package_needs_gymnasium_and_numpy_only():
    import subprocess
    import sys

    code = (
        "import sys, gymnasium as gym, hybrid_domains, hybrid_domains.baselines, hybrid_domains.reference_inputs\n"
        "env = gym.make('Goal-v0'); env.reset(seed=0)\n"
        "print(sorted({m.split('.')[0] for m in sys.modules} & {'sb3_aac', 'torch', 'stable_baselines3', 'robocup_dribble'}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
