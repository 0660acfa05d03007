"""
rl-zoo3's ``--optimize`` for every algorithm of :data:`~sb3_aac.tune.search_spaces.ALGORITHMS`: a hyperparameter
sampler and its converter over the same search spaces as ``sb3-aac tune``. :func:`sb3_aac.zoo.register` adds them to
rl-zoo3's tables.

rl-zoo3 calls a sampler with the trial only (not the policy of the hyperparameter file), so the sampler samples the
policy too, as the trial parameter ``policy`` (a single choice for an algorithm with one policy), then that policy's
space. The sampled keyword arguments replace the file's (``policy_kwargs`` too, when the space samples a policy
argument).
"""

from __future__ import annotations

from typing import Any

import optuna
from optuna.distributions import CategoricalDistribution

from sb3_aac.tune.search_spaces import policies, search_space, suggest


def sample_params(
    algo: str, trial: optuna.Trial, n_actions: int = 0, n_envs: int = 1, additional_args: dict[str, Any] | None = None
) -> dict[str, Any]:
    """
    ``algo``'s keyword arguments (``policy`` included) for ``trial``. With ``algo`` bound (``functools.partial``) this
    is rl-zoo3's sampler signature; ``n_actions``, ``n_envs`` and ``additional_args`` are not used.
    """
    policy = suggest(trial, "policy", CategoricalDistribution(policies(algo)))
    return convert_params(algo, {"policy": policy, **search_space(algo, policy).sample(trial)})


def convert_params(algo: str, sampled_params: dict[str, Any]) -> dict[str, Any]:
    """
    A trial's parameters (as :func:`sample_params` names them) as ``algo``'s keyword arguments: what rl-zoo3 trains
    a stored trial with (``--storage``, ``--study-name``, ``--trial-id``).
    """
    settings = dict(sampled_params)
    policy = settings.pop("policy")
    return {"policy": policy, **search_space(algo, policy).to_kwargs(settings)}
