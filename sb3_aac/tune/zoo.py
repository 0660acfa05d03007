"""
rl-zoo3's ``--optimize`` for SarsaAAC: a hyperparameter sampler over the same search spaces as ``sb3-aac tune``.

rl-zoo3 calls a sampler with the trial only (not the policy of the hyperparameter file), so this one samples the
policy too, as the trial parameter ``policy``, then that policy's space.
"""

from __future__ import annotations

from typing import Any

import optuna
from optuna.distributions import CategoricalDistribution

from sb3_aac.tune.search_spaces import policies, search_space, suggest

ALGO = "sarsa_aac"


def sample_sarsa_aac_params(
    trial: optuna.Trial, n_actions: int, n_envs: int, additional_args: dict[str, Any]
) -> dict[str, Any]:
    """SarsaAAC keyword arguments (``policy`` included) for ``trial``; the signature of rl-zoo3's samplers."""
    policy = suggest(trial, "policy", CategoricalDistribution(policies(ALGO)))
    return convert_sarsa_aac_params({"policy": policy, **search_space(ALGO, policy).sample(trial)})


def convert_sarsa_aac_params(sampled_params: dict[str, Any]) -> dict[str, Any]:
    """A trial's parameters (as :func:`sample_sarsa_aac_params` names them) as SarsaAAC keyword arguments."""
    settings = dict(sampled_params)
    policy = settings.pop("policy")
    return {"policy": policy, **search_space(ALGO, policy).to_kwargs(settings)}


def register_sampler() -> None:
    """Add the sampler and its converter to rl-zoo3's tables under ``sarsa_aac`` (rl-zoo3 must be installed)."""
    from rl_zoo3 import hyperparams_opt

    hyperparams_opt.HYPERPARAMS_SAMPLER[ALGO] = sample_sarsa_aac_params
    hyperparams_opt.HYPERPARAMS_CONVERTER[ALGO] = convert_sarsa_aac_params
