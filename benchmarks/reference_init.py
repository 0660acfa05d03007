"""The reference MP-DQN code's initial action-parameter policy on Goal-v0, beside the yml settings (the grid's MP-DQN
on Goal-v0).

cycraig/MP-DQN (``run_goal_pdqn.py``, ``initialise_params=True``) starts the parameter actor at a fixed linear function
of the scaled observation (``set_action_parameter_passthrough_weights``: a frozen "passthrough" layer added to the
actor's output): kick-to ``x = -0.375 + 0.5 ball_x + 0.0625 u_x`` and ``y = 0.8333 ball_y + 0.1111 u_y`` (scaled
units; ``u`` the keeper-to-ball unit vector), shoot ``+/-0.857`` (6.01 m). sb3-aac's policies start at a constant
(``initial_params``); :class:`PassthroughPolicy` adds the reference's function. Facts from the reference code; the
code is ours.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch as th
from torch import nn

from hybrid_domains.goal import GOAL_WIDTH, PITCH_LENGTH, PITCH_WIDTH
from sb3_aac.pdqn.policies import MlpPolicy

# run_goal_pdqn.py (scale_actions=True): rows kick-to x, kick-to y, shoot left, shoot right over its 17 features
_WEIGHTS = np.zeros((4, 17))
_WEIGHTS[0, [10, 11, 14, 15]] = [0.5, 0.0, 0.0625, 0.0]
_WEIGHTS[1, [10, 11, 14, 15]] = [0.0, 0.8333333333333333, 0.0, 0.1111111111111111]
_BIAS = np.array([-0.375, 0.0, 0.857346647646219686, -0.857346647646219686])
# the bounds its ScaledStateWrapper scales those features with (gym-goal's Box, then GoalObservationWrapper's)
_HALF_X, _W = PITCH_LENGTH / 2, PITCH_WIDTH / 2
_LOW = np.array([0, -_W, -1, -1, -np.pi] * 2 + [0, -_W, -3, -3] + [-1, -1, -GOAL_WIDTH / 2], dtype=float)
_HIGH = np.array([_HALF_X, _W, 1, 1, np.pi] * 2 + [_HALF_X, _W, 3, 3] + [1, 1, GOAL_WIDTH], dtype=float)


def goal_passthrough(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The reference's passthrough ``(W, b)`` re-expressed on features scaled with ``low``/``high`` (the policy's
    observation Box), so that it computes the same parameters from the same observation."""
    mid, half = (high + low) / 2, (high - low) / 2
    ref_range = _HIGH - _LOW
    a = 2 * half / ref_range  # f_ref = a * f_ours + c
    c = 2 * (mid - _LOW) / ref_range - 1
    return _WEIGHTS * a, _WEIGHTS @ c + _BIAS


class WithPassthrough(nn.Module):
    """``actor(f) + f @ W.T + b`` with ``W``, ``b`` fixed (buffers: not trained, not averaged into the target)."""

    def __init__(self, actor: nn.Module, weight: np.ndarray, bias: np.ndarray):
        super().__init__()
        self.actor = actor
        self.register_buffer("weight", th.as_tensor(weight, dtype=th.float32))
        self.register_buffer("bias", th.as_tensor(bias, dtype=th.float32))

    def forward(self, features: th.Tensor) -> th.Tensor:
        return self.actor(features) + features @ self.weight.T + self.bias


class PassthroughPolicy(MlpPolicy):
    """P-DQN's ``MlpPolicy`` whose parameter actor (and its target) add the reference's fixed linear start on Goal-v0
    (the policy's ``initial_params`` should then be None: the passthrough carries the bias)."""

    def _build(self, lr_schedule: Any) -> None:
        super()._build(lr_schedule)
        box = self.observation_space
        weight, bias = goal_passthrough(np.asarray(box.low, dtype=float), np.asarray(box.high, dtype=float))
        self.actor = WithPassthrough(self.actor, weight, bias)
        self.actor_target = WithPassthrough(self.actor_target, weight, bias)


def with_reference_start(kwargs: dict[str, Any]) -> tuple[type[PassthroughPolicy], dict[str, Any]]:
    """The policy and keyword arguments that start a P-DQN / MP-DQN with settings ``kwargs`` at the reference's
    function on Goal-v0: :class:`PassthroughPolicy`, whose passthrough carries the bias, so no ``initial_params``."""
    return PassthroughPolicy, {**kwargs, "policy_kwargs": {**kwargs.get("policy_kwargs", {}), "initial_params": None}}
