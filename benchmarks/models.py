"""The one model builder of the benchmarks: a cell's untrained model, the object evaluation calls ``predict`` on, and
its ``log_interval`` (:func:`build_model`), with the settings a P-DQN / MP-DQN / HybridPPO cell takes from
``hyperparams/*.yml`` (:func:`peer_settings`)."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch as th
from torch import nn

import sb3_aac
from benchmarks import domains
from benchmarks.adapters import adapter_for, build_baseline
from benchmarks.presets import ON_POLICY, ON_POLICY_PEERS, PEERS, SARSA_CONFIGS, SARSA_N_ENVS, Cell, is_tuned
from benchmarks.tuned import tuned_cell
from benchmarks.zoo_hyperparams import has_settings, settings, zoo_env
from hybrid_domains.goal import GOAL_WIDTH, PITCH_LENGTH, PITCH_WIDTH
from sb3_aac import SarsaAAC
from sb3_aac.pdqn.policies import MlpPolicy


def peer_settings_source(cell: Cell) -> str:
    """Where a peer's settings come from: ``hyperparams/<yml>.yml``'s entry for the env, the entry of the env's
    fallback (:data:`PEERS`), or the algorithm's defaults."""
    spec = PEERS[cell.algo]
    path = f"hyperparams/{spec['yml']}.yml"
    start = ", the reference code's initial parameter policy" if cell.env_id in spec.get("reference_start", ()) else ""
    if has_settings(spec["yml"], cell.env_id):
        return f"{path} ({cell.env_id}{start})"
    if spec["fallback"] is not None:
        return f"{path} ({spec['fallback']}; no entry for {cell.env_id})"
    return f"{cell.algo} defaults (no entry for {cell.env_id} in {path})"


def peer_settings(cell: Cell) -> dict[str, Any]:
    """P-DQN / MP-DQN / HybridPPO constructor arguments: ``hyperparams/<yml>.yml``'s entry (:func:`peer_settings_source`),
    then :data:`PEERS`, then overrides."""
    spec = PEERS[cell.algo]
    entry = cell.env_id if has_settings(spec["yml"], cell.env_id) else spec["fallback"]
    base = settings(spec["yml"], entry) if entry is not None else {}
    return {**base, "n_envs": spec["n_envs"], **spec["kwargs"], **cell.overrides}


def build_model(cell: Cell) -> tuple[Any, Any, int | None]:
    """The untrained model, the object evaluation calls ``predict`` on, and the ``log_interval`` for ``learn``.

    A tuned config (``<config>-tuned``) builds ``<config>`` with its study's best settings (:mod:`benchmarks.tuned`).
    """
    if is_tuned(cell.config):
        cell = tuned_cell(cell)
    if cell.algo == "SarsaAAC":
        _, policy, policy_kwargs, config_kwargs = SARSA_CONFIGS[cell.config]
        overrides = {**config_kwargs, **cell.overrides}
        env = domains.train_env(cell.env_id, overrides.pop("n_envs", SARSA_N_ENVS), cell.seed)
        overrides.setdefault("info_keywords", domains.info_keywords(cell.env_id))
        policy_kwargs = {**policy_kwargs, **overrides.pop("policy_kwargs", {})}
        model = SarsaAAC(policy, env, seed=cell.seed, policy_kwargs=policy_kwargs, **overrides)
        return model, model, 100  # dump the rollout/train keys every 100 episodes
    if cell.algo in PEERS:
        spec, kwargs = PEERS[cell.algo], peer_settings(cell)
        n_envs = kwargs.pop("n_envs")
        if domains.is_dribbling(cell.env_id) or not has_settings(spec["yml"], cell.env_id):
            env = domains.train_env(cell.env_id, n_envs, cell.seed)
        else:  # the env of its own entry: the entry's env_wrapper chain (Goal: the reference's reward scale too)
            env = zoo_env(spec["yml"], cell.env_id, n_envs, cell.seed)
        kwargs.setdefault("info_keywords", domains.info_keywords(cell.env_id))
        policy: Any = "MlpPolicy"
        if cell.env_id in spec.get("reference_start", ()):
            policy, kwargs = with_reference_start(kwargs)
        model = getattr(sb3_aac, cell.algo)(policy, env, seed=cell.seed, device="cpu", **kwargs)
        return model, model, _log_interval(model, cell.algo)
    model = build_baseline(cell.env_id, cell.algo, cell.seed, cell.overrides)
    return model, adapter_for(model, cell.algo, cell.env_id), _log_interval(model, cell.algo)


def _log_interval(model: Any, algo: str) -> int:
    """``learn``'s ``log_interval``: on-policy it counts rollouts (about every 2048 transitions); off-policy episodes."""
    return max(1, 2048 // (model.n_steps * model.n_envs)) if algo in (*ON_POLICY, *ON_POLICY_PEERS) else 100


# ---------------------------------------------------------------- the reference MP-DQN code's start on Goal-v0
#
# The reference MP-DQN code's initial action-parameter policy on Goal-v0, beside the yml settings (the grid's MP-DQN
# on Goal-v0).
#
# cycraig/MP-DQN (``run_goal_pdqn.py``, ``initialise_params=True``) starts the parameter actor at a fixed linear function
# of the scaled observation (``set_action_parameter_passthrough_weights``: a frozen "passthrough" layer added to the
# actor's output): kick-to ``x = -0.375 + 0.5 ball_x + 0.0625 u_x`` and ``y = 0.8333 ball_y + 0.1111 u_y`` (scaled
# units; ``u`` the keeper-to-ball unit vector), shoot ``+/-0.857`` (6.01 m). sb3-aac's policies start at a constant
# (``initial_params``); :class:`PassthroughPolicy` adds the reference's function. Facts from the reference code; the
# code is ours.


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
