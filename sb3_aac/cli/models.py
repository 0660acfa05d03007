"""The models the commands build and load: the algorithms ``--algo`` names, their keyword arguments from ``--set``, a
saved or exported model (or the hand-coded dribbler) checked to fit a dribbling profile."""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any, NamedTuple

from sb3_aac.cli.arguments import CliError, input_file
from sb3_aac.cli.envs import PROFILE_ENV_IDS

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
    "sarsa_aac": Algorithm("SarsaAAC", "TilePolicy", POLICY_KEYS),  # the recommended policy (docs/sarsa_aac.md)
    "pdqn": Algorithm("PDQN", "MlpPolicy", PDQN_POLICY_KEYS),
    "mpdqn": Algorithm("MPDQN", "MlpPolicy", PDQN_POLICY_KEYS),
    "hppo": Algorithm("HybridPPO", "MlpPolicy", ("net_arch", "ortho_init", "log_std_init")),
}
MODEL_SUFFIXES = (".zip", ".aacp")


def algo_key(value: str) -> str:
    """``--algo``'s value as a key of :data:`ALGOS`: the key itself or the class name (``HybridPPO`` -> ``hppo``)."""
    by_class = {spec.class_name.lower(): key for key, spec in ALGOS.items()}
    return by_class.get(value.lower(), value)


def algorithm(algo: str) -> Any:
    """The class ``--algo`` names."""
    import sb3_aac

    return getattr(sb3_aac, ALGOS[algo].class_name)


def sarsa_keys(algo: str = "sarsa_aac") -> list[str]:
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
            raise CliError(f"unknown --set key {key!r}{hint}; valid keys: {', '.join(sorted([*valid, *policy_keys]))}")
    if policy_kwargs:
        given = kwargs.get("policy_kwargs") or {}
        if not isinstance(given, dict):
            raise CliError(f"policy_kwargs must be a dict literal such as {{'n_rbf': 30}}, got {given!r}")
        kwargs["policy_kwargs"] = {**given, **policy_kwargs}
    return kwargs


def load_policy(model: str, profile: str | None, trust: bool = False) -> tuple[Any, str]:
    """A policy with ``predict`` and the dribbling profile it plays (given, or inferred from its spaces); a model.zip
    is loaded as :func:`load_model` says."""
    if model == "dribbler":
        from robocup_dribble.dribbler import HandCodedDribbler

        profile = profile or "v19"
        return HandCodedDribbler(profile=profile), profile
    path = input_file(model, MODEL_SUFFIXES, "MODEL")
    if path.suffix.lower() == ".aacp":
        from sb3_aac.runtime import RuntimePolicy

        try:
            policy = RuntimePolicy.load(path)
        except (ValueError, OSError) as error:
            raise CliError(f"cannot load {path}: {error}" if isinstance(error, OSError) else str(error)) from None
        matches = [p for p in PROFILE_ENV_IDS if runtime_matches_profile(policy, p)]
    else:
        policy = load_model(path, trust)
        matches = [p for p in PROFILE_ENV_IDS if model_matches_profile(policy, p)]
    if profile is None:
        if not matches:
            raise CliError(
                f"{path} was not trained on a dribbling env (its spaces match neither {list(PROFILE_ENV_IDS)}); "
                "this command runs the dribbling env, so it needs a dribbling model"
            )
        return policy, matches[0]
    if profile not in matches:
        found = f"it matches {matches[0]}" if matches else "it was not trained on a dribbling env"
        raise CliError(f"{path} does not fit --profile {profile} ({found}); drop --profile to infer it")
    return policy, profile


TRUST_HINT = (
    "loading it would run code from the file; pass --trust to load it anyway (only a file you or someone you trust "
    "made), or share the policy as an exported .aacp"
)


def load_model(path: Path, trust: bool = False) -> Any:
    """
    A model.zip saved by ``train``, whichever ``--algo`` trained it, checked first
    (:func:`~sb3_aac.common.model_files.check_model_file`): any damage is one line. Unless ``trust``, nothing of the
    file is unpickled (:func:`~sb3_aac.common.model_files.pickle_free_objects` stands in for every pickled entry,
    with the dribbling envs' spaces as the known ones); a file that needs its pickles is refused, naming the entry.
    """
    from sb3_aac.common.model_files import PickledEntryError, check_model_file, load_checked, pickle_free_objects

    errors = []
    try:
        check_model_file(path)
        for algo, (name, _, _) in ALGOS.items():
            cls = algorithm(algo)
            kwargs: dict[str, Any] = {}
            if not trust:
                try:
                    kwargs["custom_objects"] = pickle_free_objects(path, cls.policy_aliases.values(), dribble_space_list())
                except PickledEntryError as error:
                    if error.entry == "policy_class":  # another algorithm's file
                        errors.append(f"as {name}: {error}")
                        continue
                    raise CliError(f"{path}: {error}; {TRUST_HINT}") from None
            try:
                return load_checked(cls, path, **kwargs)
            except ValueError as error:
                errors.append(f"as {name}: {error}")
    except ValueError as error:
        raise CliError(str(error)) from None
    except OSError as error:
        raise CliError(f"cannot load {path}: {error}") from None
    hint = f" ({TRUST_HINT})" if not trust else ""
    raise CliError(f"cannot load {path}: " + "; ".join(errors) + hint)


def dribble_space_list() -> list[Any]:
    """The observation and action spaces of every dribbling profile."""
    return [space for profile in PROFILE_ENV_IDS for space in dribble_spaces(profile)]


def dribble_spaces(profile: str) -> tuple[Any, Any]:
    from robocup_dribble import DribbleEnv

    env = DribbleEnv(profile=profile)
    return env.observation_space, env.action_space


def model_matches_profile(model: Any, profile: str) -> bool:
    obs_space, action_space = dribble_spaces(profile)
    return bool(model.observation_space == obs_space and model.action_space == action_space)


def runtime_matches_profile(policy: Any, profile: str) -> bool:
    import numpy as np

    from sb3_aac.common.spaces import ParameterizedActionSpec

    obs_space, action_space = dribble_spaces(profile)
    spec = ParameterizedActionSpec.from_space(action_space)
    return bool(
        policy.obs_shape == obs_space.shape
        and np.array_equal(policy.obs_low, obs_space.low.astype(np.float64))
        and np.array_equal(policy.obs_high, obs_space.high.astype(np.float64))
        and policy.layout == spec.layout
        and policy.dims == spec.dims
        and np.array_equal(policy.param_low, spec.low)
        and np.array_equal(policy.param_high, spec.high)
    )
