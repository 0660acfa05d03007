"""The one model builder of the benchmarks: a cell's untrained model, the object evaluation calls ``predict`` on, and
its ``log_interval`` (:func:`build_model`), with the settings a P-DQN / MP-DQN / HybridPPO cell takes from
``hyperparams/*.yml`` (:func:`peer_settings`)."""

from __future__ import annotations

from typing import Any

import sb3_aac
from benchmarks import domains
from benchmarks.adapters import adapter_for, build_baseline
from benchmarks.presets import ON_POLICY, ON_POLICY_PEERS, PEERS, SARSA_CONFIGS, SARSA_N_ENVS, Cell, is_tuned
from benchmarks.reference_init import with_reference_start
from benchmarks.tuned import tuned_cell
from benchmarks.zoo_hyperparams import has_settings, settings, zoo_env
from sb3_aac import SarsaAAC


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
