"""
What ``sb3-aac tune`` and rl-zoo3's ``--optimize`` can tune: the algorithm classes by key, and one search space per
(algorithm, policy), as data.

Adding an algorithm takes an entry in :data:`ALGORITHMS` and one :class:`SearchSpace` per policy in
:data:`SEARCH_SPACES`; the tuner, the report, rl-zoo3's registration and sampler (:mod:`sb3_aac.zoo`) and the
benchmark's tuning stage (``benchmarks/tuning.py``) read only these two tables.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass, field
from typing import Any

import optuna
from optuna.distributions import BaseDistribution, CategoricalDistribution, FloatDistribution, IntDistribution
from stable_baselines3.common.base_class import BaseAlgorithm

from sb3_aac.hppo import HybridPPO
from sb3_aac.pdqn import MPDQN, PDQN
from sb3_aac.sarsa_aac import SarsaAAC


def suggest(trial: optuna.Trial, name: str, distribution: BaseDistribution) -> Any:
    """Ask ``trial`` for a value of ``name`` drawn from ``distribution`` (float, int or categorical)."""
    if isinstance(distribution, FloatDistribution):
        return trial.suggest_float(name, distribution.low, distribution.high, log=distribution.log, step=distribution.step)
    if isinstance(distribution, IntDistribution):
        return trial.suggest_int(name, distribution.low, distribution.high, log=distribution.log, step=distribution.step)
    if isinstance(distribution, CategoricalDistribution):
        return trial.suggest_categorical(name, distribution.choices)
    raise TypeError(f"{name}: unsupported distribution {distribution!r} (use Float-, Int- or CategoricalDistribution)")


@dataclass(frozen=True)
class SearchSpace:
    """
    The hyperparameters tuned for one algorithm with one policy. Trial parameters carry the plain argument names
    (``gamma``, ``n_rbf``), so a best trial reads as ``--set`` pairs.

    :param hyperparameters: keyword arguments of the algorithm's constructor, each with its distribution
    :param policy_kwargs: keyword arguments of the policy (passed in ``policy_kwargs``), each with its distribution
    """

    hyperparameters: Mapping[str, BaseDistribution]
    policy_kwargs: Mapping[str, BaseDistribution] = field(default_factory=dict)

    def __post_init__(self) -> None:
        shared = set(self.hyperparameters) & set(self.policy_kwargs)
        if shared:
            raise ValueError(f"{sorted(shared)} are both algorithm and policy arguments; a name must mean one thing")

    def sample(self, trial: optuna.Trial, fixed: Collection[str] = ()) -> dict[str, Any]:
        """One point of the space as ``{name: value}``; the names in ``fixed`` are left out (not sampled)."""
        distributions = {**self.hyperparameters, **self.policy_kwargs}
        return {name: suggest(trial, name, d) for name, d in distributions.items() if name not in fixed}

    def to_kwargs(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """Flat ``{name: value}`` as constructor keyword arguments, the policy's inside ``policy_kwargs``."""
        kwargs = {name: value for name, value in params.items() if name not in self.policy_kwargs}
        policy_kwargs = {name: value for name, value in params.items() if name in self.policy_kwargs}
        if policy_kwargs:
            kwargs["policy_kwargs"] = {**kwargs.get("policy_kwargs", {}), **policy_kwargs}
        return kwargs


ALGORITHMS: dict[str, type[BaseAlgorithm]] = {"sarsa_aac": SarsaAAC, "pdqn": PDQN, "mpdqn": MPDQN, "hppo": HybridPPO}

# SarsaAAC's rates are normalised (1 moves a linear approximator onto its target), so they are searched on (0, 1].
# A 40-trial study of RbfPolicy on RoboCupDribblePaper-v0 (50k steps, 3 seeds a trial) put its best trials at the
# edges of gamma >= 0.8, exploration_fraction >= 0.1 and n_rbf <= 50, so those ranges reach further.
_SARSA_AAC = {
    "learning_rate": FloatDistribution(0.01, 1.0, log=True),
    "q_learning_rate": FloatDistribution(0.01, 1.0, log=True),
    "param_learning_rate": FloatDistribution(0.01, 1.0, log=True),
    "gamma": FloatDistribution(0.7, 0.99),
    "exploration_fraction": FloatDistribution(0.05, 1.0),
    "exploration_initial_eps": FloatDistribution(0.05, 0.5),
    "exploration_final_eps": FloatDistribution(0.0, 0.1),
    "param_noise_initial": FloatDistribution(0.05, 0.6),
    "param_noise_final": FloatDistribution(0.0, 0.1),
}
_RBF_WIDTH = FloatDistribution(0.5, 2.0)
# The MLP families replay recent transitions by default (2 per live one); 0 is the paper's update.
_SARSA_AAC_REPLAY = {**_SARSA_AAC, "replay_ratio": IntDistribution(0, 4)}

# P-DQN / MP-DQN: the ranges span the reference MP-DQN code's settings (Bester et al. 2019: Adam 1e-3 / 1e-4, Polyak
# 0.1 / 0.001, gamma 0.9 on Platform, minibatch 128) and hyperparams/<algo>.yml's dribbling settings by a factor of
# about 10 each way; the nets stay those of the hyperparameter file (a list is no Optuna parameter).
_PDQN = {
    "learning_rate": FloatDistribution(1e-4, 1e-2, log=True),
    "actor_learning_rate": FloatDistribution(1e-5, 1e-3, log=True),
    "batch_size": CategoricalDistribution((32, 64, 128, 256)),
    "tau": FloatDistribution(0.005, 0.5, log=True),
    "actor_tau": FloatDistribution(1e-4, 0.01, log=True),
    "gamma": FloatDistribution(0.9, 0.999),
    "exploration_fraction": FloatDistribution(0.02, 0.5),
    "exploration_final_eps": FloatDistribution(0.0, 0.1),
    "param_noise_std": FloatDistribution(1e-4, 0.5, log=True),
}

# HybridPPO: the ranges rl-zoo3 searches for PPO (its sample_ppo_params), with the parameter actor's clip range and
# entropy coefficient beside the discrete actor's. Not yet run as a study.
_HPPO = {
    "learning_rate": FloatDistribution(1e-5, 3e-3, log=True),
    "n_steps": CategoricalDistribution([64, 128, 256, 512, 1024]),
    "batch_size": CategoricalDistribution([64, 128, 256, 512]),
    "n_epochs": IntDistribution(3, 20),
    "gamma": FloatDistribution(0.9, 0.9999),
    "gae_lambda": FloatDistribution(0.8, 1.0),
    "clip_range": FloatDistribution(0.05, 0.4),
    "clip_range_params": FloatDistribution(0.05, 0.4),
    "ent_coef": FloatDistribution(1e-5, 0.1, log=True),
    "param_ent_coef": FloatDistribution(1e-6, 1e-2, log=True),
    "vf_coef": FloatDistribution(0.2, 1.0),
    "max_grad_norm": FloatDistribution(0.3, 5.0, log=True),
}

SEARCH_SPACES: dict[tuple[str, str], SearchSpace] = {
    ("pdqn", "MlpPolicy"): SearchSpace(_PDQN),
    ("mpdqn", "MlpPolicy"): SearchSpace(_PDQN),
    ("sarsa_aac", "MlpPolicy"): SearchSpace(_SARSA_AAC_REPLAY, {"hidden_units": IntDistribution(2, 40, log=True)}),
    ("sarsa_aac", "RbfMlpPolicy"): SearchSpace(
        _SARSA_AAC_REPLAY,
        {"n_rbf": IntDistribution(5, 30), "hidden_units": IntDistribution(2, 20, log=True), "rbf_width": _RBF_WIDTH},
    ),
    ("sarsa_aac", "RbfPolicy"): SearchSpace(_SARSA_AAC, {"n_rbf": IntDistribution(5, 80), "rbf_width": _RBF_WIDTH}),
    ("sarsa_aac", "TilePolicy"): SearchSpace(
        _SARSA_AAC, {"tiles_per_input": IntDistribution(4, 16), "n_tilings": IntDistribution(4, 16)}
    ),
    # DeepPolicy learns best with traces (docs/sarsa_aac_results.md: trace_lambda=0.8), on CatchPoint with replay
    # (ibid.; the parameter critic did worse there, and is searched, not assumed); ObGD's kappa around the paper's 2.
    ("sarsa_aac", "DeepPolicy"): SearchSpace(
        {
            **_SARSA_AAC_REPLAY,
            "trace_lambda": FloatDistribution(0.0, 0.95),
            "parameter_update": CategoricalDistribution(("cacla", "critic")),
        },
        {"kappa": FloatDistribution(1.0, 4.0)},
    ),
    ("hppo", "MlpPolicy"): SearchSpace(_HPPO, {"log_std_init": FloatDistribution(-2.0, 0.5)}),
}


def policies(algo: str) -> list[str]:
    """The policies with a search space for ``algo``."""
    return [policy for key, policy in SEARCH_SPACES if key == algo]


def search_space(algo: str, policy: str) -> SearchSpace:
    """The search space of ``algo`` with ``policy``; a ``ValueError`` names the known ones otherwise."""
    if algo not in ALGORITHMS:
        raise ValueError(f"unknown algorithm {algo!r}; tunable algorithms: {sorted(ALGORITHMS)}")
    if (algo, policy) not in SEARCH_SPACES:
        raise ValueError(f"no search space for {algo} with policy {policy!r}; tunable policies: {policies(algo)}")
    return SEARCH_SPACES[(algo, policy)]
