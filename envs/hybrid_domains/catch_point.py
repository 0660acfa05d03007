"""Catching Point (Fan et al., IJCAI 2019, H-PPO) as the HyAR code implements it.

Facts taken from Fan, Su, Zhang & Yu, "Hybrid Actor-Critic Reinforcement Learning in Parameterized Action Space"
(arXiv:1903.01344: an agent must catch a target point with a limited number of catch attempts, using MOVE(direction)
and CATCH), and from the public implementation the field compares on, TJU-DRL-LAB/self-supervised-rl
``RL_with_Action_Representation/HyAR`` (Li et al., ICLR 2022; its README calls it a "mimic implementation of the
environment used in HPPO"): ``multiagent/scenarios/simple_catch.py`` (start, reward, catch rule, observation),
``multiagent/core.py`` (time step 0.1, damping 0.25, unit mass, catch radius 0.2) and ``multiagent/environment.py``
(action code 1: force ``2 (sin d, cos d)`` for MOVE, none for CATCH), ``Raw_RL/main_direction_catch_*.py``
(directions ``pi * p`` for ``p in [-1, 1]``; 25 steps; an episode ends at a catch or when the misses run out). The code
is ours.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from gymnasium import spaces

from hybrid_domains.episodes import EpisodicEnv
from hybrid_domains.actions import float32_box, parse_nested

MOVE, CATCH = 0, 1
ACTION_NAMES = ("move", "catch")
PARAMETER_SIZES = (1, 0)
FORCE = 2.0  # a MOVE's force; the agent's mass is 1
DT = 0.1
DAMPING = 0.25
CATCH_RADIUS = 0.2
CATCH_BONUS = 20.0
MAX_MISSES = 11  # HyAR counts a miss while its counter is <= 10, then the next step pays 0 and ends the episode
SPEED_MAX = FORCE * DT / DAMPING  # |v'| <= (1 - damping) |v| + force dt, from rest: |v| < 0.8
OBSERVATION_NAMES = ("vx", "vy", "target_dx", "target_dy")


class CatchPointEnv(EpisodicEnv[np.ndarray]):
    """## Description

    Catching Point (H-PPO, Fan et al. 2019) as implemented in the HyAR code (Li et al. 2022, where HyAR-TD3 catches
    the point in about 90 % of episodes): a point agent in the plane must come within 0.2 of a fixed target point
    and CATCH it, with a limited number of misses. Motion is a damped point mass: ``v = 0.75 v + 0.1 F``, then
    ``pos += 0.1 v``.

    ## Action Space

    ``Tuple(Discrete(2), Tuple(Box([-pi], [pi]), Box(0)))`` float32: 0 ``move(direction)`` applies the force
    ``F = 2 (sin d, cos d)`` (HyAR's convention: ``d = 0`` pushes along +y), 1 ``catch()`` applies no force (the
    agent drifts on) and tries to catch. A direction outside [-pi, pi] is clipped (HyAR's agents send ``pi * p``
    with ``p`` in [-1, 1]).

    ## Observation Space

    ``Box(4)`` float32 as HyAR: the agent's velocity and the target's position relative to the agent
    (:data:`OBSERVATION_NAMES`). Bounds: ``|v| < 0.8`` (see :data:`SPEED_MAX`); the offset starts inside [-2, 2] and
    moves at most ``0.08`` a step, so it stays within ``2 + 0.08 max_steps``.

    ## Rewards

    ``-d^2`` each step, ``d`` the distance to the target after the move; a catch within 0.2 pays ``20 - d^2``. HyAR's
    metric is the share of episodes with a catch (``info["caught"]``).

    ## Starting State

    Agent and target uniform in [-1, 1]^2, agent at rest.

    ## Episode End

    1. Termination: a catch, or the 11th miss (HyAR pays 0 for one more step and ends then; the return is the same).
    2. Truncation: ``max_steps`` (25, HyAR's episode length) steps.

    An invalid action (wrong structure, a type outside 0..1, a non-real or non-finite direction, a non-empty catch
    parameter) raises ``ValueError`` and changes nothing; :meth:`step` before :meth:`reset`, or after the episode ended,
    raises ``ResetNeeded``.

    ## Arguments

    ``max_steps`` (25). No rendering (``render_mode`` None only).

    ## Version History

    * v0: HyAR's ``simple_catch`` scenario (action code 1) as a single-agent Gymnasium 1.x env, with the episode
      rules of HyAR's training scripts inside the env.
    """

    def __init__(self, max_steps: int = 25, render_mode: str | None = None) -> None:
        self._check_render_mode(render_mode)
        if isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1:  # type: ignore[redundant-expr]
            raise ValueError(f"max_steps must be an integer >= 1, got {max_steps!r}")
        self.max_steps = max_steps
        directions = spaces.Box(np.float32(-math.pi), np.float32(math.pi), shape=(1,), dtype=np.float32)
        self.action_space = spaces.Tuple(
            (spaces.Discrete(2), spaces.Tuple((directions, spaces.Box(0.0, 0.0, shape=(0,), dtype=np.float32))))
        )
        offset_max = 2.0 + max_steps * DT * SPEED_MAX
        self.observation_space = float32_box(
            [-SPEED_MAX, -SPEED_MAX, -offset_max, -offset_max], [SPEED_MAX, SPEED_MAX, offset_max, offset_max]
        )
        self.x = self.y = self.vx = self.vy = self.target_x = self.target_y = 0.0
        self.misses = 0
        self.steps = -1  # -1 until the first reset

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self.x, self.y = (float(v) for v in self.np_random.uniform(-1.0, 1.0, size=2))
        self.target_x, self.target_y = (float(v) for v in self.np_random.uniform(-1.0, 1.0, size=2))
        self.vx = self.vy = 0.0
        self.misses, self.steps = 0, 0
        return self._observation(), {"caught": False}

    def _step(self, action: tuple[Any, ...]) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        k, parameters = parse_nested(action, PARAMETER_SIZES)
        fx = fy = 0.0
        if k == MOVE:
            direction = min(max(float(parameters[MOVE][0]), -math.pi), math.pi)
            fx, fy = FORCE * math.sin(direction), FORCE * math.cos(direction)
        self.vx = self.vx * (1.0 - DAMPING) + fx * DT
        self.vy = self.vy * (1.0 - DAMPING) + fy * DT
        self.x += self.vx * DT
        self.y += self.vy * DT
        self.steps += 1
        squared = (self.x - self.target_x) ** 2 + (self.y - self.target_y) ** 2
        caught = k == CATCH and squared <= CATCH_RADIUS**2
        if k == CATCH and not caught:
            self.misses += 1
        reward = CATCH_BONUS - squared if caught else -squared
        terminated = caught or self.misses >= MAX_MISSES
        truncated = not terminated and self.steps >= self.max_steps
        return self._observation(), reward, terminated, truncated, {"caught": caught}

    def _observation(self) -> np.ndarray:
        return np.array([self.vx, self.vy, self.target_x - self.x, self.target_y - self.y], dtype=np.float32)
