"""Moving-v0 and Sliding-v0: stop a point agent inside a target circle (thomashirtz/gym-hybrid).

Facts taken from thomashirtz/gym-hybrid (commit 2256181, ``gym_hybrid/environments.py`` and ``agents.py``; DI-engine's
copy in ``dizoo/gym_hybrid`` has the same dynamics): the constants (field half-size 1, target radius 0.1, max turn
pi/2, max acceleration 0.5, brake 0.1, time step 0.005, 200 steps, penalty 0.001), the three actions and their shared
parameter vector, both agents' kinematics (Moving turns its velocity with its heading; Sliding keeps the velocity
vector and adds the acceleration to it), the reward, the termination rules, the reset distribution and the
observation. The code is ours.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces

from hybrid_domains.episodes import EpisodicEnv
from hybrid_domains.actions import float32_box, parse_shared

ACCELERATE, TURN, BRAKE = 0, 1, 2
ACTION_NAMES = ("accelerate", "turn", "brake")
FIELD_SIZE = 1.0  # the field is [-1, 1]^2
TARGET_RADIUS = 0.1
SUCCESS_BONUS = 1.0
FAILURE_REWARD = -1.0
OBSERVATION_NAMES = ("x", "y", "speed", "cos_heading", "sin_heading", "target_x", "target_y", "distance", "in_target", "time")


class MovingEnv(EpisodicEnv[np.ndarray]):
    """## Description

    Moving-v0 of thomashirtz/gym-hybrid (the "Moving" task of Xiong et al. 2018 and Fan et al. 2019, as DI-engine
    benchmarks it): a point agent in the square [-1, 1]^2 must *stop* inside a target circle of radius 0.1. Its
    velocity always points along its heading, so turning also turns the motion. :class:`SlidingEnv` keeps inertia.

    Every action moves the agent once: ``x += delta_t * speed * cos(angle)`` (and ``y`` with ``sin``), where
    ``angle`` is the heading (Moving) or the velocity's direction (Sliding).

    ## Action Space

    ``Tuple(Discrete(3), Box([0, -1], [1, 1]))`` float32, gym-hybrid's shared layout: type 0 ``accelerate`` reads
    ``p[0]`` (speed += ``max_acceleration * p[0]``), 1 ``turn`` reads ``p[1]`` (heading += ``max_turn * p[1]``, modulo
    2 pi), 2 ``brake`` reads nothing (speed -= ``brake_value``, and 0 if it was below ``brake_value``). Out-of-range
    parameters are clipped to ``[0, 1]`` and ``[-1, 1]``, as gym-hybrid does. gym-hybrid also accepted ``(k, [p_k])``;
    here the action must be an element of the action space (a pair with two parameters).

    ## Observation Space

    ``Box(10)`` float32 (:data:`OBSERVATION_NAMES`): x, y, speed, cos and sin of the heading, target x and y, distance
    to the target, 1.0 if inside the target (distance <= 0.1) else 0.0, and steps taken / ``max_step``. gym-hybrid
    declared ``Box(np.ones(10), -np.ones(10))`` (low and high swapped); the bounds here are the reachable ones: the
    speed grows by at most ``max_acceleration`` a step, so within ``max_step + 1`` steps it stays below ``v_max =
    max_acceleration * (max_step + 1)``, and the agent ends at most ``delta_t * v_max`` outside the field.

    ## Rewards

    ``previous distance - distance - penalty`` each step, plus ``1`` when the agent stops (speed exactly 0) inside the
    target; exactly ``-1`` when it leaves the field (|x| > 1 or |y| > 1) or takes step ``max_step + 1``. DI-engine
    reports the return and reads a return of 1.5 or more as a successful move; ``info["success"]`` says whether the
    agent stopped in the target.

    ## Starting State

    Target centre uniform in [-0.9, 0.9]^2; agent position uniform in [-1, 1]^2, heading uniform in [0, 2 pi), speed 0.

    ## Episode End

    Termination: stopped inside the target (checked first), out of the field, or step ``max_step + 1`` (gym-hybrid's
    time limit is part of the task: it gives -1 and the observation shows the time). The env never truncates.

    An invalid action (wrong structure, a type outside 0..2, non-real or non-finite parameters) raises ``ValueError``
    and changes nothing; :meth:`step` before :meth:`reset`, or after the episode ended,
    raises ``ResetNeeded``.

    ## Arguments

    gym-hybrid's: ``max_turn`` (pi/2), ``max_acceleration`` (0.5), ``delta_t`` (0.005), ``max_step`` (200),
    ``penalty`` (0.001), ``break_value`` (0.1, the brake). No rendering (``render_mode`` None only).

    ## Version History

    * v0: gym-hybrid 2256181's dynamics on Gymnasium 1.x with reachable observation bounds; ``reset(seed=...)``
      seeds the env (gym-hybrid's ``seed`` argument is gone).
    """

    metadata: dict[str, Any] = {"render_modes": []}  # noqa: RUF012  (Gymnasium declares it so)
    sliding = False

    def __init__(
        self,
        max_turn: float = math.pi / 2,
        max_acceleration: float = 0.5,
        delta_t: float = 0.005,
        max_step: int = 200,
        penalty: float = 0.001,
        break_value: float = 0.1,
        render_mode: str | None = None,
    ) -> None:
        self._check_render_mode(render_mode)
        for name, value in (
            ("max_turn", max_turn),
            ("max_acceleration", max_acceleration),
            ("delta_t", delta_t),
            ("break_value", break_value),
        ):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):  # type: ignore[redundant-expr]
                raise ValueError(f"{name} must be a positive finite number, got {value!r}")
        if not (isinstance(penalty, (int, float)) and math.isfinite(penalty) and penalty >= 0):  # type: ignore[redundant-expr]
            raise ValueError(f"penalty must be a finite number >= 0, got {penalty!r}")
        if isinstance(max_step, bool) or not isinstance(max_step, int) or max_step < 1:  # type: ignore[redundant-expr]
            raise ValueError(f"max_step must be an integer >= 1, got {max_step!r}")
        self.max_turn, self.max_acceleration, self.delta_t = float(max_turn), float(max_acceleration), float(delta_t)
        self.max_step, self.penalty, self.break_value = max_step, float(penalty), float(break_value)
        self.action_space = spaces.Tuple(
            (spaces.Discrete(3), spaces.Box(np.array([0, -1], dtype=np.float32), np.array([1, 1], dtype=np.float32)))
        )
        speed_max = self.max_acceleration * (max_step + 1)
        position_max = FIELD_SIZE + self.delta_t * speed_max
        target_max = FIELD_SIZE - TARGET_RADIUS
        distance_max = math.sqrt(2) * (position_max + target_max)
        time_max = (max_step + 1) / max_step
        low = [-position_max, -position_max, 0.0, -1.0, -1.0, -target_max, -target_max, 0.0, 0.0, 0.0]
        high = [position_max, position_max, speed_max, 1.0, 1.0, target_max, target_max, distance_max, 1.0, time_max]
        self.observation_space = float32_box(low, high)
        self.x = self.y = self.speed = self.heading = self.direction = 0.0
        self.target_x = self.target_y = 0.0
        self.steps = -1  # -1 until the first reset

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        limit = FIELD_SIZE - TARGET_RADIUS
        self.target_x, self.target_y = (float(v) for v in self.np_random.uniform(-limit, limit, size=2))
        self.x, self.y = (float(v) for v in self.np_random.uniform(-FIELD_SIZE, FIELD_SIZE, size=2))
        self.heading = float(self.np_random.uniform(0.0, 2 * math.pi))
        self.speed, self.direction = 0.0, self.heading  # at speed 0 the velocity's direction plays no role
        self.steps = 0
        return self._observation(), {"success": False}

    def _step(self, action: tuple[Any, ...]) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        k, p = parse_shared(action, len(ACTION_NAMES), 2)
        last_distance = self.distance()
        self.steps += 1
        if k == ACCELERATE:
            self._accelerate(self.max_acceleration * min(max(float(p[0]), 0.0), 1.0))
        elif k == TURN:
            self.heading = (self.heading + self.max_turn * min(max(float(p[1]), -1.0), 1.0)) % (2 * math.pi)
        else:
            self._brake()
        angle = self.direction if self.sliding else self.heading
        self.x += self.delta_t * self.speed * math.cos(angle)
        self.y += self.delta_t * self.speed * math.sin(angle)
        distance = self.distance()
        success = distance < TARGET_RADIUS and self.speed == 0
        failure = not success and (abs(self.x) > FIELD_SIZE or abs(self.y) > FIELD_SIZE or self.steps > self.max_step)
        if failure:
            reward = FAILURE_REWARD
        else:
            reward = last_distance - distance - self.penalty + (SUCCESS_BONUS if success else 0.0)
        return self._observation(), reward, success or failure, False, {"success": success}

    def _accelerate(self, value: float) -> None:
        if not self.sliding:
            self.speed += value
            return
        # the sum of the velocity (speed, direction) and value along the heading, in polar form (gym-hybrid's formula)
        relative = self.direction - self.heading
        speed = math.sqrt(value**2 + self.speed**2 + 2 * value * self.speed * math.cos(relative))
        self.direction = self.heading + math.atan2(self.speed * math.sin(relative), value + self.speed * math.cos(relative))
        self.speed = speed

    def _brake(self) -> None:
        self.speed = 0.0 if self.speed < self.break_value else self.speed - self.break_value
        if self.speed == 0:
            self.direction = self.heading

    def distance(self) -> float:
        return math.hypot(self.x - self.target_x, self.y - self.target_y)

    def _observation(self) -> np.ndarray:
        distance = self.distance()
        return np.array(
            [
                self.x, self.y, self.speed, math.cos(self.heading), math.sin(self.heading), self.target_x, self.target_y,
                distance, 0.0 if distance > TARGET_RADIUS else 1.0, self.steps / self.max_step,
            ],
            dtype=np.float32,
        )  # fmt: skip


class SlidingEnv(MovingEnv):
    """## Description

    Sliding-v0 of thomashirtz/gym-hybrid: :class:`MovingEnv` with inertia. Turning changes only the heading; the
    velocity keeps its direction until an acceleration along the heading is added to it as a vector
    (``|v'| = sqrt(a^2 + |v|^2 + 2 a |v| cos(phi - theta))``, ``phi' = theta + atan2(|v| sin(phi - theta),
    a + |v| cos(phi - theta))``), and the agent moves along the velocity. Braking shortens the velocity; when it reaches
    0 its direction becomes the heading. Everything else (actions, observation, rewards, start, end, arguments) is
    :class:`MovingEnv`'s.

    ## Version History

    * v0: gym-hybrid 2256181's dynamics on Gymnasium 1.x. gym-hybrid kept the velocity direction of the previous
      episode at reset; it plays no role at speed 0, so the env resets it to the heading.
    """

    sliding = True
