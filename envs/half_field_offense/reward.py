"""HFO's shaped 1v0 reward as dqn-hfo codes it and gym-soccer's ``SoccerScoreGoal-v0`` (which MP-DQN ran) restates
it, read from the features of the state after each step (Hausknecht & Stone 2016, eq. 2, with the code's gates).

With ``ball = 1 - ball proximity``, ``goal = 1 - goal-centre proximity`` and ``alpha`` the angle between their
bearings (each recovered from its cosine with the sign of its sine), the ball-to-goal distance is
``sqrt(ball^2 + goal^2 - 2 ball goal cos(alpha))`` (in proximity units). A step pays

    d(ball proximity)                       (when nobody or the agent holds the ball: always in 1v0)
    + 1, once a trial, when kickable rises  (the kickable feature grows by >= 1)
    + 3 * -d(ball-to-goal distance)         when the agent holds the ball (0.2 of it once kickable was rewarded
                                            and someone else holds it: never in 1v0)
    + 5 on a goal,

with ``d`` the change since the previous step. A trial's first step pays 0 (it only records the values), and with
``zero_terminal_deltas`` (dqn-hfo) a trial's last step pays only the goal bonus. The sparse variant pays 1 for a goal.
"""

from __future__ import annotations

import math

from numba import njit

from half_field_offense import task
from half_field_offense.features import (
    F_BALL_COS,
    F_BALL_PROXIMITY,
    F_BALL_SIN,
    F_GOAL_COS,
    F_GOAL_PROXIMITY,
    F_GOAL_SIN,
    F_KICKABLE,
)

APPROACH_WEIGHT = 1.0
KICKABLE_BONUS = 1.0
GOAL_PROGRESS_WEIGHT = 3.0
OTHER_HOLDER_FACTOR = 0.2
GOAL_BONUS = 5.0
SPARSE_GOAL_REWARD = 1.0
MEMORY_FIELDS = ("ball_proximity", "kickable", "ball_to_goal", "started", "kickable_rewarded")
"""What the shaped reward keeps between steps, per lane: the last values, whether a trial's first step was seen,
whether the kickable bonus was paid."""
M_BALL_PROXIMITY, M_KICKABLE, M_BALL_TO_GOAL, M_STARTED, M_KICKABLE_REWARDED = range(len(MEMORY_FIELDS))


@njit(cache=True, error_model="numpy", inline="always")
def _angle(sin: float, cos: float) -> float:
    """The angle in [-pi, pi] of a bearing's sine and cosine, as gym-soccer recovers it (acos with the sine's sign)."""
    angle = math.acos(min(max(cos, -1.0), 1.0))
    return -angle if sin < 0.0 else angle


@njit(cache=True, error_model="numpy", inline="always")
def ball_to_goal(obs, oi: int) -> float:
    """The ball-to-goal distance (proximity units) from the features in row ``oi`` of ``obs``."""
    ball, goal = 1.0 - obs[oi, F_BALL_PROXIMITY], 1.0 - obs[oi, F_GOAL_PROXIMITY]
    alpha = abs(_angle(obs[oi, F_BALL_SIN], obs[oi, F_BALL_COS]) - _angle(obs[oi, F_GOAL_SIN], obs[oi, F_GOAL_COS]))
    return math.sqrt(max(ball * ball + goal * goal - 2.0 * ball * goal * math.cos(alpha), 0.0))


@njit(cache=True, error_model="numpy")
def reward(obs, oi: int, memory, i: int, agent_holds: bool, nobody_holds: bool, goal: bool, last: bool, c) -> float:
    """The reward of a step whose next features are row ``oi`` of ``obs``, updating lane ``i``'s ``memory`` row
    (:data:`MEMORY_FIELDS`; zero it when a trial starts)."""
    if c[task.R_SPARSE_REWARD] > 0.5:
        return SPARSE_GOAL_REWARD if goal else 0.0
    ball_proximity, kickable, distance = obs[oi, F_BALL_PROXIMITY], obs[oi, F_KICKABLE], ball_to_goal(obs, oi)
    started = memory[i, M_STARTED] > 0.5
    approach = ball_proximity - memory[i, M_BALL_PROXIMITY]
    kickable_rise = kickable - memory[i, M_KICKABLE]
    progress = -(distance - memory[i, M_BALL_TO_GOAL])
    memory[i, M_BALL_PROXIMITY], memory[i, M_KICKABLE], memory[i, M_BALL_TO_GOAL] = ball_proximity, kickable, distance
    memory[i, M_STARTED] = 1.0
    if not started:
        return 0.0
    total = GOAL_BONUS if goal else 0.0
    if last and c[task.R_ZERO_TERMINAL_DELTAS] > 0.5:
        return total
    if agent_holds or nobody_holds:
        total += APPROACH_WEIGHT * approach
    if kickable_rise >= 1.0 and memory[i, M_KICKABLE_REWARDED] < 0.5:
        total += KICKABLE_BONUS
        memory[i, M_KICKABLE_REWARDED] = 1.0
    if agent_holds:
        total += GOAL_PROGRESS_WEIGHT * progress
    elif memory[i, M_KICKABLE_REWARDED] > 0.5:
        total += GOAL_PROGRESS_WEIGHT * OTHER_HOLDER_FACTOR * progress
    return total
