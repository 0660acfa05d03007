"""The algorithms by their command-line names (``--algo``) and their keyword arguments from ``key=value`` settings
(``--set``), shared by ``sb3-aac train``, ``sb3-aac tune`` and the benchmarks' tuning suite."""

from __future__ import annotations

import argparse
import ast
import inspect
from typing import Any, NamedTuple

import sb3_aac


class SettingsError(ValueError):
    """A ``--set`` setting no algorithm takes, or a malformed one: the message says which keys are valid."""


POLICIES = ("MlpPolicy", "RbfMlpPolicy", "RbfPolicy", "TilePolicy", "DeepPolicy")
# SarsaAAC constructor arguments the CLI sets itself (not through --set).
RESERVED = ("policy", "env", "tensorboard_log", "seed", "device", "verbose", "_init_setup_model")
POLICY_KEYS = (
    *("hidden_units", "n_rbf", "rbf_width", "obs_bounds", "tile_groups", "tiles_per_input", "n_tilings"),
    *("net_arch", "sparsity", "normalize_obs", "kappa"),  # DeepPolicy's
)


class Algorithm(NamedTuple):
    """What ``--algo`` names: the class name in sb3_aac, its default policy, and the policy arguments --set may give."""

    class_name: str
    default_policy: str
    policy_keys: tuple[str, ...]


PDQN_POLICY_KEYS = ("net_arch", "actor_net_arch", "param_bounding", "initial_params")
ALGOS = {
    "sarsa_aac": Algorithm("SarsaAAC", "DeepPolicy", POLICY_KEYS),  # the recommended policy (docs/sarsa_aac.md)
    "pdqn": Algorithm("PDQN", "MlpPolicy", PDQN_POLICY_KEYS),
    "mpdqn": Algorithm("MPDQN", "MlpPolicy", PDQN_POLICY_KEYS),
    "hppo": Algorithm("HybridPPO", "MlpPolicy", ("net_arch", "ortho_init", "log_std_init")),
}


def algo_key(value: str) -> str:
    """``--algo``'s value as a key of :data:`ALGOS`: the key itself or the class name (``HybridPPO`` -> ``hppo``)."""
    by_class = {spec.class_name.lower(): key for key, spec in ALGOS.items()}
    return by_class.get(value.lower(), value)


def algorithm(algo: str) -> Any:
    """The class ``--algo`` names."""
    return getattr(sb3_aac, ALGOS[algo].class_name)


def sarsa_keys(algo: str = "sarsa_aac") -> list[str]:
    """The constructor arguments of ``algo``'s class that ``--set`` may give (all but :data:`RESERVED`)."""
    cls = algorithm(algo)
    return [name for name in inspect.signature(cls.__init__).parameters if name not in ("self", *RESERVED)]


def hyperparameters(pairs: list[tuple[str, Any]], algo: str = "sarsa_aac") -> dict[str, Any]:
    """``--set`` pairs as keyword arguments of ``--algo``'s class; policy arguments go into ``policy_kwargs``."""
    valid = sarsa_keys(algo)
    policy_keys = ALGOS[algo].policy_keys
    kwargs: dict[str, Any] = {}
    policy_kwargs: dict[str, Any] = {}
    for key, value in pairs:
        if key in policy_keys:
            policy_kwargs[key] = value
        elif key in valid:
            kwargs[key] = value
        else:
            hint = " (set it with its own option, e.g. --seed)" if key in RESERVED else ""
            raise SettingsError(f"unknown --set key {key!r}{hint}; valid keys: {', '.join(sorted([*valid, *policy_keys]))}")
    if policy_kwargs:
        given = kwargs.get("policy_kwargs") or {}
        if not isinstance(given, dict):
            raise SettingsError(f"policy_kwargs must be a dict literal such as {{'n_rbf': 30}}, got {given!r}")
        kwargs["policy_kwargs"] = {**given, **policy_kwargs}
    return kwargs


def key_value(text: str) -> tuple[str, Any]:
    """``key=value`` as ``(key, value)``, the value a Python literal or else the bare text (an argparse ``type``)."""
    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected key=value (e.g. gamma=0.95), got {text!r}")
    try:
        value = ast.literal_eval(raw)
    except (ValueError, SyntaxError):
        value = raw  # a bare word such as type_exploration=boltzmann
    return key.strip(), value
