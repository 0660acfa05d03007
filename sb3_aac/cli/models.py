"""The models the commands load: a saved or exported model (or the hand-coded dribbler) checked to fit a dribbling
profile. The algorithms ``--algo`` names and their keyword arguments from ``--set`` are
:mod:`sb3_aac.common.algorithms`'."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sb3_aac.cli.arguments import CliError, input_file
from sb3_aac.cli.envs import PROFILE_ENV_IDS
from sb3_aac.common.algorithms import ALGOS, algorithm

MODEL_SUFFIXES = (".zip", ".aacp")


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
