"""Robot Soccer Goal (Masson, Ranchod & Konidaris, AAAI 2016) with the dynamics of cycraig/gym-goal.

Facts taken from cycraig/gym-goal (commit 8e142be, ``gym_goal/envs/goal_env.py``, ``config.py``, ``util.py``), itself a
port of WarwickMasson/aaai-goal (``simulator.py``; the same physics): every constant below, the entity models
(accelerate with angle and velocity noise, decay, component-wise clipping), the player skills (turn, dash, to-ball,
kick, kick-to, shoot-goal), the keeper, the collision pass, the terminal checks, the reward and the observation. The
code is ours.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium import spaces

from hybrid_domains.episodes import EpisodicEnv
from hybrid_domains.actions import float32_box, parse_nested

# gym_goal/envs/config.py ("taken from the robot soccer server manual 7.07"); lengths in metres, one step = one cycle.
PITCH_LENGTH = 40.0  # the field is the half x in [0, PITCH_LENGTH / 2], y in [-PITCH_WIDTH / 2, PITCH_WIDTH / 2]
PITCH_WIDTH = 30.0
GOAL_WIDTH = 14.02
GOAL_DEPTH = 2.44
GOAL_AREA_LENGTH = 5.5
GOAL_AREA_WIDTH = 18.32
KICKABLE = 0.9 + 0.7  # player size + kickable margin
CATCHABLE = 2.0  # the keeper catches a ball closer than this (catch probability 1.0)
INERTIA_MOMENT = 5.0
MIN_POWER, MAX_POWER = -100.0, 100.0
# goal_env.py
MAX_ACTIONS = 100  # the 100th action ends the episode without being simulated
GOAL_REWARD = 50.0
FACING_TOLERANCE = math.pi / 8  # util.angle_close
STOPPED_SPEED = 0.1  # kick-to lasts until the ball is slower than this (and kickable)
TO_BALL_DASH_POWER = 10.0
KEEPER_INTERCEPT_POWER = 20.0
KEEPER_FOLLOW_POWER = 8.0
BALL_START_EPSILON = 1e-12  # the ball starts just inside the kickable distance

KICK_TO, SHOOT_GOAL_LEFT, SHOOT_GOAL_RIGHT = 0, 1, 2
ACTION_NAMES = ("kick_to", "shoot_goal_left", "shoot_goal_right")
PARAMETER_LOW = (np.array([0.0, -PITCH_WIDTH / 2]), np.array([-GOAL_WIDTH / 2]), np.array([-GOAL_WIDTH / 2]))
PARAMETER_HIGH = (np.array([PITCH_LENGTH, PITCH_WIDTH / 2]), np.array([GOAL_WIDTH / 2]), np.array([GOAL_WIDTH / 2]))
PARAMETER_SIZES = (2, 1, 1)

OBSERVATION_NAMES = (
    "player_x", "player_y", "player_vx", "player_vy", "player_orientation",
    "keeper_x", "keeper_y", "keeper_vx", "keeper_vy", "keeper_orientation",
    "ball_x", "ball_y", "ball_vx", "ball_vy",
)  # fmt: skip
POSITION_MARGIN = 10.0  # the Box's positions reach this far beyond the field (see GoalEnv, Observation Space)
MAX_REPORTED_STEPS = 199  # the observation's step count is a Discrete(200), as in gym-goal


@dataclass
class Body:
    """A moving entity: position, velocity (per cycle), orientation (rad) and its soccer-server constants."""

    size: float
    rand: float
    power_rate: float
    accel_max: float
    speed_max: float
    decay: float
    x: float = 0.0
    y: float = 0.0
    vx: float = 0.0
    vy: float = 0.0
    orientation: float = 0.0

    def speed(self) -> float:
        return math.hypot(self.vx, self.vy)

    def distance(self, other: Body) -> float:
        return math.hypot(self.x - other.x, self.y - other.y)

    def angle_to(self, x: float, y: float) -> float:
        return math.atan2(y - self.y, x - self.x)


def player_body() -> Body:
    return Body(size=0.9, rand=0.1, power_rate=0.006, accel_max=1.0, speed_max=1.0, decay=0.4)


def ball_body() -> Body:
    return Body(size=0.4, rand=0.05, power_rate=0.027, accel_max=2.7, speed_max=2.7, decay=0.94)


def norm_angle(angle: float) -> float:
    """``angle`` moved into [-pi, pi] by whole turns."""
    while angle > math.pi:
        angle -= 2 * math.pi
    while angle < -math.pi:
        angle += 2 * math.pi
    return angle


def clip(value: float, low: float, high: float) -> float:
    return low if value < low else high if value > high else value


def accelerate(body: Body, power: float, theta: float, rng: np.random.Generator) -> None:
    """Push ``body`` with ``power`` towards ``theta``: the angle is scaled by ``1 + U(-rand, rand)`` (noise grows with the
    angle's value, as in gym-goal), a velocity noise ``U(-rand |v|, rand |v|)`` is added to each component, and the
    acceleration and then the velocity are clipped component-wise to ``accel_max`` and ``speed_max``."""
    u = rng.random(3)
    theta *= 1.0 + body.rand * (2.0 * u[0] - 1.0)
    noise = body.rand * body.speed()
    rate = power * body.power_rate
    ax = clip(rate * math.cos(theta) + noise * (2.0 * u[1] - 1.0), -body.accel_max, body.accel_max)
    ay = clip(rate * math.sin(theta) + noise * (2.0 * u[2] - 1.0), -body.accel_max, body.accel_max)
    body.vx = clip(body.vx + ax, -body.speed_max, body.speed_max)
    body.vy = clip(body.vy + ay, -body.speed_max, body.speed_max)


def move(body: Body) -> None:
    """One cycle: position += velocity, then velocity *= decay."""
    body.x += body.vx
    body.y += body.vy
    body.vx *= body.decay
    body.vy *= body.decay


def can_kick(player: Body, ball: Body) -> bool:
    return player.distance(ball) <= KICKABLE


def kick_power(player: Body, ball: Body) -> float:
    """The effective kick power factor ``1 - 0.25 dir_diff / pi - 0.25 dist / KICKABLE`` (soccer server kick model)."""
    dir_diff = abs(norm_angle(player.angle_to(ball.x, ball.y) - player.orientation))
    return 1.0 - 0.25 * dir_diff / math.pi - 0.25 * player.distance(ball) / KICKABLE


def turn(player: Body, moment: float) -> None:
    player.orientation += norm_angle(moment) / (1.0 + INERTIA_MOMENT * player.speed())


def facing(player: Body, angle: float) -> bool:
    return abs(norm_angle(player.orientation - angle)) < FACING_TOLERANCE


def to_ball(player: Body, ball: Body, rng: np.random.Generator) -> None:
    """Turn towards the ball unless facing it, else dash at power 10 unless it is kickable."""
    theta = player.angle_to(ball.x, ball.y)
    if not facing(player, theta):
        turn(player, theta - player.orientation)
    elif not can_kick(player, ball):
        accelerate(player, TO_BALL_DASH_POWER, player.orientation, rng)


def kick_to(player: Body, ball: Body, target_x: float, target_y: float, rng: np.random.Generator) -> None:
    """Go to the ball; once it is kickable, kick it so that it would come to rest at the target."""
    if not can_kick(player, ball):
        to_ball(player, ball, rng)
        return
    ax = (1.0 - ball.decay) * (target_x - player.x) - ball.vx
    ay = (1.0 - ball.decay) * (target_y - player.y) - ball.vy
    factor = kick_power(player, ball)
    power = clip(math.hypot(ax, ay) / (factor * ball.power_rate), MIN_POWER, MAX_POWER) * factor
    direction = math.atan2(ay, ax) - player.orientation  # kick_towards: relative to the body, as gym-goal
    accelerate(ball, power, player.orientation + direction, rng)


def keeper_target(ball_x: float, ball_y: float) -> tuple[float, float]:
    """Where the keeper starts: on the line from the ball to the goal centre, inside the goal area."""
    grad = -ball_y / (PITCH_LENGTH / 2 - ball_x)
    yint = ball_y - grad * ball_x
    if ball_x < PITCH_LENGTH / 2 - GOAL_AREA_LENGTH:
        x = ball_x
    elif ball_y < -GOAL_AREA_WIDTH / 2:
        x = (-GOAL_AREA_WIDTH / 2 - yint) / grad
    else:
        x = (GOAL_AREA_WIDTH / 2 - yint) / grad
    x = clip(x, PITCH_LENGTH / 2 - GOAL_AREA_LENGTH, PITCH_LENGTH / 2)
    return x, clip(grad * x + yint, -GOAL_AREA_WIDTH / 2, GOAL_AREA_WIDTH / 2)


def move_keeper(keeper: Body, ball: Body, rng: np.random.Generator) -> None:
    """If the ball's resting point lies behind the goal line near the goal, run (power 20) to the closest point of the
    ball's path; else walk (power 8) towards the resting point. The keeper faces where it goes."""
    end_x = ball.x + ball.vx / (1.0 - ball.decay)
    end_y = ball.y + ball.vy / (1.0 - ball.decay)
    dx, dy = end_x - ball.x, end_y - ball.y
    grad = dy / dx if dx != 0.0 else 0.0
    yint = ball.y - grad * ball.x
    goal_y = grad * PITCH_LENGTH / 2 + yint
    near_goal = -GOAL_WIDTH / 2 - CATCHABLE <= goal_y <= GOAL_WIDTH / 2 + CATCHABLE
    if end_x > PITCH_LENGTH / 2 and near_goal and grad != 0.0:
        grad2 = -1.0 / grad
        yint2 = keeper.y - grad2 * keeper.x
        target_x = (yint2 - yint) / (grad - grad2)
        target_y = grad * target_x + yint
        accelerate(keeper, KEEPER_INTERCEPT_POWER, keeper.angle_to(target_x, target_y), rng)
        keeper.orientation = keeper.angle_to(target_x, target_y)
    else:
        keeper.orientation = keeper.angle_to(end_x, end_y)
        accelerate(keeper, KEEPER_FOLLOW_POWER, keeper.angle_to(end_x, end_y), rng)


def decollide(a: Body, b: Body) -> None:
    """If ``a`` and ``b`` overlap, push each half the overlap apart and reverse both velocities."""
    dist = a.distance(b)
    if dist >= a.size + b.size:
        return
    overlap = (a.size + b.size - dist) / 2
    to_b, to_a = a.angle_to(b.x, b.y), b.angle_to(a.x, a.y)
    a.x += overlap * math.cos(to_a)
    a.y += overlap * math.sin(to_a)
    b.x += overlap * math.cos(to_b)
    b.y += overlap * math.sin(to_b)
    a.vx, a.vy, b.vx, b.vy = -a.vx, -a.vy, -b.vx, -b.vy


def goal_distance(ball: Body) -> float:
    """gym-goal's ``Ball.goal_distance``: in front of the goal line, the distance to the goal mouth (the segment x = 20,
    |y| <= 7.01); behind it, ``y - 7.01`` above the goal, 0 level with it and ``7.01 - y`` (sic: ``7.01 + |y|``, not
    ``|y| - 7.01``) below it."""
    half_goal = GOAL_WIDTH / 2
    if ball.x < PITCH_LENGTH / 2:
        if abs(ball.y) > half_goal:
            return math.hypot(ball.x - PITCH_LENGTH / 2, abs(ball.y) - half_goal)
        return PITCH_LENGTH / 2 - ball.x
    if ball.y < -half_goal:
        return half_goal - ball.y
    return max(ball.y - half_goal, 0.0)


def in_net(ball: Body) -> bool:
    return PITCH_LENGTH / 2 <= ball.x <= PITCH_LENGTH / 2 + GOAL_DEPTH and -GOAL_WIDTH / 2 <= ball.y <= GOAL_WIDTH / 2


def in_field(ball: Body) -> bool:
    return 0.0 <= ball.x <= PITCH_LENGTH / 2 and -PITCH_WIDTH / 2 <= ball.y <= PITCH_WIDTH / 2


def observation_space() -> spaces.Tuple[Any]:
    """``Tuple(Box(14), Discrete(200))``; the Box: see :class:`GoalEnv` (Observation Space)."""
    half = PITCH_LENGTH / 2
    position_low = [-POSITION_MARGIN, -PITCH_WIDTH / 2 - POSITION_MARGIN]
    position_high = [half + POSITION_MARGIN, PITCH_WIDTH / 2 + POSITION_MARGIN]
    player_v, ball_v = 1.0, 2.7
    low = [*position_low, -player_v, -player_v, -math.pi] * 2 + [*position_low, -ball_v, -ball_v]
    high = [*position_high, player_v, player_v, math.pi] * 2 + [*position_high, ball_v, ball_v]
    return spaces.Tuple((float32_box(low, high), spaces.Discrete(MAX_REPORTED_STEPS + 1)))


def action_space() -> spaces.Tuple[Any]:
    boxes = tuple(
        spaces.Box(lo.astype(np.float32), hi.astype(np.float32)) for lo, hi in zip(PARAMETER_LOW, PARAMETER_HIGH, strict=True)
    )
    return spaces.Tuple((spaces.Discrete(len(ACTION_NAMES)), spaces.Tuple(boxes)))


class GoalEnv(EpisodicEnv[tuple[np.ndarray, int]]):
    """## Description

    Robot Soccer Goal (Masson, Ranchod & Konidaris, "Reinforcement Learning with Parameterized Actions", AAAI 2016),
    with the dynamics of cycraig/gym-goal (Bester et al. 2019's port of WarwickMasson/aaai-goal, the domain on which
    MP-DQN reaches P(goal) 0.789): a striker with the ball must score past a keeper on half a 40 x 30 m pitch. The
    physics are a simplified RoboCup soccer server (manual 7.07): player decay 0.4, power rate 0.006, speed and
    acceleration clipped to 1.0 per component; ball size 0.4, decay 0.94, power rate 0.027, clipped to 2.7; kickable
    within 1.6 m, a kick weighted ``1 - 0.25 dir_diff / pi - 0.25 dist / 1.6``; inertia moment 5; angle noise of
    10 % (player) and 5 % (ball) of the angle's value and velocity noise of that share of the speed.

    One action is a *stabilised* macro action: the simulator runs cycles until it is done (below), so an episode
    has at most 99 simulated actions.

    ## Action Space

    ``Tuple(Discrete(3), Tuple(Box(2), Box(1), Box(1)))`` float32, as gym-goal: 0 ``kick_to(x in [0, 40],
    y in [-15, 15])``, 1 ``shoot_goal_left(y in [-7.01, 7.01])``, 2 ``shoot_goal_right(y in [-7.01, 7.01])``.
    Out-of-range parameters are clipped to these bounds, as gym-goal does.

    * ``kick_to``: the player walks to the ball (turning to face it within pi/8, then dashing at power 10) and kicks it
      so that it would stop at the target; the action lasts until the ball is slower than 0.1 and kickable again.
      **As in gym-goal (and aaai-goal), the target is** ``(x, x)``: both simulators pass only the first parameter on
      (``agent.kick_to(self.ball, parameters[0])``), which numpy broadcasts over both coordinates, so ``y`` has no
      effect. We keep that, because the published results were obtained with it.
    * ``shoot_goal_*``: kick-to ``(20.4, y)`` (just behind the goal line) cycle after cycle until the episode ends;
      both types are the same skill (two types so that a policy can hold one aim for each side of the keeper).

    ## Observation Space

    ``Tuple(Box(14), Discrete(200))`` as gym-goal: player x, y, vx, vy, orientation; keeper x, y, vx, vy,
    orientation; ball x, y, vx, vy (:data:`OBSERVATION_NAMES`), and the number of cycles the last action took
    (0 after reset and at the 100th action; capped at 199, where gym-goal's Discrete(200) ends). The Box's velocity
    bounds are exact (1.0 and 2.7 per component). gym-goal's own Box (field x in [0, 20], |y| <= 15) does not hold
    every observation: the ball has left the field at a terminal step, and player and keeper can run past the lines;
    ours extends the positions by 10 m beyond the field. gym-goal lets the player's orientation grow past pi (turns
    add up); the observation reports it wrapped into [-pi, pi] while the dynamics keep the unwrapped value, whose
    size scales the dash noise as in gym-goal.

    ## Rewards

    50 when the ball enters the goal (x in [20, 22.44], |y| <= 7.01); minus the ball's distance to the goal mouth when
    the keeper catches it (closer than 2 m), it leaves the field, or the 100th action is taken; 0 otherwise. Behind
    the goal line and below the goal gym-goal's distance is ``7.01 - y`` (see :func:`goal_distance`); we keep it.
    The published metric is P(goal), the share of episodes with return 50 (``info["goal"]``).

    ## Starting State

    Player at (0, U(-15, 15)) facing the goal centre (20, 0); the ball 1.6 m ahead of it (just kickable); the keeper at
    its guarding point on the ball-goal line inside the goal area, facing the ball; everything at rest.

    ## Episode End

    Termination: goal, catch, ball out of the field, or the 100th action (as gym-goal; its time limit gives a reward
    and is part of the task). The env never truncates.

    ``info``: ``goal`` (bool) and ``cycles`` (simulated cycles of this action, not capped). An invalid action (wrong
    structure, a type outside 0..2, non-real or non-finite parameters) raises ``ValueError`` and changes nothing;
    :meth:`step` before :meth:`reset`, or after the episode ended, raises ``ResetNeeded``.

    ## Arguments

    None (``gym.make("Goal-v0")``). No rendering (``render_mode`` None only).

    ## Version History

    * v0: gym-goal 8e142be's dynamics on Gymnasium 1.x; wrapped player orientation and a wider Box in the observation;
      ``reset(seed=...)`` seeds a numpy ``Generator`` (gym-goal drew from a ``RandomState``, so seeded episodes differ).
    """

    def __init__(self, render_mode: str | None = None) -> None:
        self._check_render_mode(render_mode)
        self.action_space = action_space()
        self.observation_space = observation_space()
        self.player, self.keeper, self.ball = player_body(), player_body(), ball_body()
        self._actions = -1  # -1 until the first reset

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[tuple[np.ndarray, int], dict[str, Any]]:
        super().reset(seed=seed)
        player, keeper, ball = player_body(), player_body(), ball_body()
        player.y = float(self.np_random.uniform(-PITCH_WIDTH / 2, PITCH_WIDTH / 2))
        player.orientation = player.angle_to(PITCH_LENGTH / 2, 0.0)
        ball.x = player.x + (KICKABLE - BALL_START_EPSILON) * math.cos(player.orientation)
        ball.y = player.y + (KICKABLE - BALL_START_EPSILON) * math.sin(player.orientation)
        keeper.x, keeper.y = keeper_target(ball.x, ball.y)
        keeper.orientation = keeper.angle_to(ball.x, ball.y)
        self.player, self.keeper, self.ball = player, keeper, ball
        self._actions = 0
        return self._observation(0), {"goal": False, "cycles": 0}

    def _step(self, action: tuple[Any, ...]) -> tuple[tuple[np.ndarray, int], float, bool, bool, dict[str, Any]]:
        k, parameters = parse_nested(action, PARAMETER_SIZES)
        param = np.clip(parameters[k], PARAMETER_LOW[k], PARAMETER_HIGH[k])
        self._actions += 1
        if self._actions == MAX_ACTIONS:
            return self._observation(0), -goal_distance(self.ball), True, False, {"goal": False, "cycles": 0}
        if k == KICK_TO:
            target = (float(param[0]), float(param[0]))  # gym-goal's (x, x), see the class docstring
        else:
            target = (PITCH_LENGTH / 2 + self.ball.size, float(param[0]))
        cycles, reward, terminated = 0, 0.0, False
        while True:
            cycles += 1
            reward, terminated = self._cycle(target)
            if terminated:
                break
            if k == KICK_TO:
                if can_kick(self.player, self.ball) and self.ball.speed() <= STOPPED_SPEED:
                    break
            # shoot_goal runs until the episode ends
        return self._observation(cycles), reward, terminated, False, {"goal": reward == GOAL_REWARD, "cycles": cycles}

    def _cycle(self, target: tuple[float, float]) -> tuple[float, bool]:
        """One simulator cycle: the player's skill, the keeper, motion, one collision pass, the terminal check."""
        player, keeper, ball, rng = self.player, self.keeper, self.ball, self.np_random
        kick_to(player, ball, target[0], target[1], rng)
        move_keeper(keeper, ball, rng)
        for body in (player, keeper, ball):
            move(body)
        decollide(player, keeper)
        decollide(player, ball)
        decollide(keeper, ball)
        if in_net(ball):
            return GOAL_REWARD, True
        if keeper.distance(ball) < CATCHABLE or not in_field(ball):
            return -goal_distance(ball), True
        return 0.0, False

    def _observation(self, cycles: int) -> tuple[np.ndarray, int]:
        p, k, b = self.player, self.keeper, self.ball
        state = [p.x, p.y, p.vx, p.vy, norm_angle(p.orientation), k.x, k.y, k.vx, k.vy, k.orientation, b.x, b.y, b.vx, b.vy]
        return np.array(state, dtype=np.float32), min(cycles, MAX_REPORTED_STEPS)
