"""Reference policies for every domain of this package, and their figures over fixed episodes.

A policy here is a function from an observation to an env action. :func:`random_policy` draws uniformly from the
action space; :func:`scripted_policy` is a short hand-written controller per domain (see each ``*_script``).
:func:`policy_figures` plays ``episodes`` episodes, episode ``j`` from ``reset(seed=seed + j)``, so two policies
meet the same episodes. ``python -m hybrid_domains.baselines [--episodes 1000] [--seed 0]`` prints the table of
docs/hybrid_domains.md: mean (std) return, success share, actions per episode and env steps per CPU second (policy
included; the process's CPU time, so a loaded machine does not lower it).
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from hybrid_domains import ENV_CLASSES, catch_point, goal, moving

Policy = Callable[[Any], Any]
SUCCESS_KEYS = {"Goal-v0": "goal", "Moving-v0": "success", "Sliding-v0": "success", "CatchPoint-v0": "caught"}
"""The ``info`` key that flags a successful episode (at its last step), per env id."""

GOAL_ADVANCE_UNTIL_X = 10.0  # the Goal script kicks the ball forward until it is this far up the field, then shoots
GOAL_SHOT_Y = goal.GOAL_WIDTH / 2 - 1.0  # 6.01: aaai-goal's initial shooting aim (learn.py)
MOVING_CRUISE_SPEED = 4.0  # 0.02 a step: the farthest target (2.7 away) is reached in ~140 steps
MOVING_AIM_TOLERANCE = 0.01  # rad
MOVING_STOP_SLACK = 0.03  # brake when the braking distance reaches the distance to the centre minus this
CATCH_REACH = 0.9 * catch_point.CATCH_RADIUS  # catch when the drift of a catch step ends this close to the target


def random_policy(action_space: gym.spaces.Space[Any], seed: int) -> Policy:
    """Uniformly random actions from ``action_space`` (seeded once with ``seed``)."""
    action_space.seed(seed)
    return lambda observation: action_space.sample()


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


def goal_script(observation: Any) -> tuple[Any, ...]:
    """Advance with aaai-goal's initial kick-to rule (target ``ball_x + 2.5 + 1.25 u_x``, ``u`` the unit vector from
    the keeper to the ball; learn.py's Q-PAMDP start) until the ball is 10 m up the field, then shoot at y = +/-6.01 on
    the side away from the keeper. Takes Goal-v0's observation or the 17 reference features (the state comes first)."""
    state = np.asarray(observation[0] if isinstance(observation, tuple) else observation, dtype=np.float64)
    keeper_x, keeper_y, ball_x, ball_y = state[[5, 6, 10, 11]]
    u = np.array([ball_x - keeper_x, ball_y - keeper_y])
    u = u / max(float(np.linalg.norm(u)), 1e-9)
    xfear, yfear, caution = 50 / goal.PITCH_LENGTH, 50 / goal.PITCH_WIDTH, 5 / goal.PITCH_WIDTH  # learn.py
    kick = np.array([2.5 + ball_x + xfear * u[0], (1 - caution) * ball_y + yfear * u[1]], dtype=np.float32)
    aims = (np.array([GOAL_SHOT_Y], dtype=np.float32), np.array([-GOAL_SHOT_Y], dtype=np.float32))
    if ball_x < GOAL_ADVANCE_UNTIL_X:
        k = goal.KICK_TO
    else:
        k = goal.SHOOT_GOAL_LEFT if keeper_y < 0 else goal.SHOOT_GOAL_RIGHT
    return k, (kick, *aims)


def moving_script(
    max_turn: float = math.pi / 2, max_acceleration: float = 0.5, delta_t: float = 0.005, brake: float = 0.1
) -> Callable[[Any], tuple[int, np.ndarray]]:
    """Moving-v0 / Sliding-v0 (default arguments): at rest, turn towards the target (or brake, which succeeds, inside
    it); accelerate to 4 along the heading; brake when the distance braking covers reaches the distance to the target's
    centre. It turns only at rest, so on Sliding the velocity points where the heading does."""

    def act(observation: Any) -> tuple[int, np.ndarray]:
        x, y, speed, cos_h, sin_h, target_x, target_y, distance = (float(v) for v in observation[:8])
        none = np.zeros(2, dtype=np.float32)
        if speed == 0:
            if distance < moving.TARGET_RADIUS - MOVING_STOP_SLACK:
                return moving.BRAKE, none
            error = _wrap(math.atan2(target_y - y, target_x - x) - math.atan2(sin_h, cos_h))
            if abs(error) > MOVING_AIM_TOLERANCE:
                return moving.TURN, np.array([0.0, max(-1.0, min(1.0, error / max_turn))], dtype=np.float32)
        steps = math.ceil(speed / brake)
        braking = delta_t * sum(max(speed - brake * i, 0.0) for i in range(1, steps + 1))
        if braking >= distance - MOVING_STOP_SLACK:
            return moving.BRAKE, none
        push = max(0.0, min(1.0, (MOVING_CRUISE_SPEED - speed) / max_acceleration))
        return moving.ACCELERATE, np.array([push, 0.0], dtype=np.float32)

    return act


def catch_script(observation: Any) -> tuple[int, tuple[np.ndarray, np.ndarray]]:
    """CatchPoint-v0: catch when the drift of a catch step (velocity x 0.75 x 0.1) ends within 0.18 of the target,
    else push towards it (force ``(sin d, cos d)``: ``d = atan2(dx, dy)``)."""
    vx, vy, dx, dy = (float(v) for v in observation[:4])
    drift = (1.0 - catch_point.DAMPING) * catch_point.DT
    empty = np.zeros(0, dtype=np.float32)
    if math.hypot(dx - drift * vx, dy - drift * vy) <= CATCH_REACH:
        return catch_point.CATCH, (np.zeros(1, dtype=np.float32), empty)
    return catch_point.MOVE, (np.array([math.atan2(dx, dy)], dtype=np.float32), empty)


def scripted_policy(env_id: str) -> Policy:
    """The scripted policy of a registered id of this package (with its default arguments)."""
    scripts: dict[str, Policy] = {
        "Goal-v0": goal_script,
        "Moving-v0": moving_script(),
        "Sliding-v0": moving_script(),
        "CatchPoint-v0": catch_script,
    }
    if env_id not in scripts:
        raise ValueError(f"No scripted policy for {env_id!r}; there are {sorted(scripts)}")
    return scripts[env_id]


def policy_figures(env_id: str, policy: Policy, episodes: int = 1000, seed: int = 0) -> dict[str, float]:
    """Play ``episodes`` episodes of ``env_id`` (episode ``j`` from ``reset(seed=seed + j)``) with ``policy``.

    :return: ``episodes``, ``return_mean``, ``return_std``, ``success_share`` (the episodes whose last ``info`` flags
        :data:`SUCCESS_KEYS`), ``length_mean`` (actions per episode) and ``steps_per_second`` (env steps per second
        of this process's CPU time, policy included)
    """
    if episodes < 1:
        raise ValueError(f"episodes must be >= 1, got {episodes}")
    env = gym.make(env_id)
    returns, lengths, successes = np.zeros(episodes), np.zeros(episodes), np.zeros(episodes, dtype=bool)
    start = time.process_time()
    for j in range(episodes):
        observation, _ = env.reset(seed=seed + j)
        done = False
        while not done:
            observation, reward, terminated, truncated, info = env.step(policy(observation))
            returns[j] += float(reward)
            lengths[j] += 1
            done = terminated or truncated
        successes[j] = bool(info[SUCCESS_KEYS[env_id]])
    seconds = time.process_time() - start
    env.close()
    return {
        "episodes": episodes,
        "return_mean": float(returns.mean()),
        "return_std": float(returns.std()),
        "success_share": float(successes.mean()),
        "length_mean": float(lengths.mean()),
        "steps_per_second": float(lengths.sum() / seconds),
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description="The figures of a uniformly random and a scripted policy on every env (docs/hybrid_domains.md)."
    )
    parser.add_argument("--episodes", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(f"{args.episodes} episodes per row, episode j from reset(seed={args.seed} + j)\n")
    print("| env | policy | return mean (std) | success share | actions / episode | env steps / CPU s |")
    print("|---|---|---|---|---|---|")
    for env_id in ENV_CLASSES:
        policies = {
            "uniform random": random_policy(gym.make(env_id).action_space, args.seed),
            "scripted": scripted_policy(env_id),
        }
        for name, policy in policies.items():
            f = policy_figures(env_id, policy, args.episodes, args.seed)
            print(
                f"| {env_id} | {name} | {f['return_mean']:.3f} ({f['return_std']:.3f}) | {f['success_share']:.3f} "
                f"| {f['length_mean']:.1f} | {f['steps_per_second']:,.0f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
