"""
rl-zoo3's ``--optimize`` for SarsaAAC and HybridPPO: hyperparameter samplers over the same search spaces as
``sb3-aac tune``.

rl-zoo3 calls a sampler with the trial only (not the policy of the hyperparameter file), so these sample the
policy too, as the trial parameter ``policy``, then that policy's space.
"""

from __future__ import annotations

from typing import Any

import optuna
from optuna.distributions import CategoricalDistribution

from sb3_aac.tune.search_spaces import policies, search_space, suggest


def _sample(algo: str, trial: optuna.Trial) -> dict[str, Any]:
    policy = suggest(trial, "policy", CategoricalDistribution(policies(algo)))
    return _convert(algo, {"policy": policy, **search_space(algo, policy).sample(trial)})


def _convert(algo: str, sampled_params: dict[str, Any]) -> dict[str, Any]:
    settings = dict(sampled_params)
    policy = settings.pop("policy")
    return {"policy": policy, **search_space(algo, policy).to_kwargs(settings)}


def sample_sarsa_aac_params(
    trial: optuna.Trial, n_actions: int, n_envs: int, additional_args: dict[str, Any]
) -> dict[str, Any]:
    """SarsaAAC keyword arguments (``policy`` included) for ``trial``; the signature of rl-zoo3's samplers."""
    return _sample("sarsa_aac", trial)


def convert_sarsa_aac_params(sampled_params: dict[str, Any]) -> dict[str, Any]:
    """A trial's parameters (as :func:`sample_sarsa_aac_params` names them) as SarsaAAC keyword arguments."""
    return _convert("sarsa_aac", sampled_params)


def sample_hppo_params(trial: optuna.Trial, n_actions: int, n_envs: int, additional_args: dict[str, Any]) -> dict[str, Any]:
    """HybridPPO keyword arguments (``policy`` included) for ``trial``; the signature of rl-zoo3's samplers."""
    return _sample("hppo", trial)


def convert_hppo_params(sampled_params: dict[str, Any]) -> dict[str, Any]:
    """A trial's parameters (as :func:`sample_hppo_params` names them) as HybridPPO keyword arguments."""
    return _convert("hppo", sampled_params)


def register_sampler() -> None:
    """Add the samplers and their converters to rl-zoo3's tables under ``sarsa_aac`` and ``hppo`` (rl-zoo3 must be
    installed)."""
    from rl_zoo3 import hyperparams_opt

    hyperparams_opt.HYPERPARAMS_SAMPLER["sarsa_aac"] = sample_sarsa_aac_params
    hyperparams_opt.HYPERPARAMS_CONVERTER["sarsa_aac"] = convert_sarsa_aac_params
    hyperparams_opt.HYPERPARAMS_SAMPLER["hppo"] = sample_hppo_params
    hyperparams_opt.HYPERPARAMS_CONVERTER["hppo"] = convert_hppo_params
