"""A study's trials as lines, and its best settings written as an ``sb3-aac train`` command line and as a
``hyperparams/sarsa_aac.yml`` entry."""

from __future__ import annotations

import json
import shlex
from collections.abc import Mapping
from typing import Any

from optuna.trial import FrozenTrial, TrialState

from sb3_aac.tune.study import TuneSettings


def literal(value: Any) -> str:
    """``value`` as a Python literal; floats rounded to 4 significant digits and kept floats (``1.0``, ``0.1235``)."""
    if isinstance(value, float):
        return repr(float(f"{value:.4g}"))
    if isinstance(value, dict):
        return "dict(" + ", ".join(f"{key}={literal(item)}" for key, item in value.items()) + ")"
    if isinstance(value, tuple):
        items = ", ".join(literal(item) for item in value)
        return f"({items},)" if len(value) == 1 else f"({items})"
    if isinstance(value, list):
        return "[" + ", ".join(literal(item) for item in value) + "]"
    return repr(value)


def flat_settings(kwargs: Mapping[str, Any]) -> dict[str, Any]:
    """Keyword arguments with ``policy_kwargs`` spread out, as ``--set`` takes them (it routes policy keys back)."""
    flat = {name: value for name, value in kwargs.items() if name != "policy_kwargs"}
    return {**flat, **(kwargs.get("policy_kwargs") or {})}


def train_command(settings: TuneSettings, kwargs: Mapping[str, Any]) -> str:
    """The ``sb3-aac train`` command that trains with ``kwargs`` on the study's env, budget and ``n_envs``."""
    words = ["sb3-aac", "train", "--env", settings.env_id, "--algo", settings.algo, "--policy", settings.policy]
    words += ["--timesteps", str(settings.timesteps)]
    words += ["--n-envs", str(settings.n_envs)]
    for name, value in flat_settings(kwargs).items():
        words += ["--set", f"{name}={literal(value)}"]
    return shlex.join(words)


def zoo_entry(settings: TuneSettings, kwargs: Mapping[str, Any]) -> str:
    """An rl-zoo3 hyperparameter entry (the format of ``hyperparams/sarsa_aac.yml``) for the study's env."""
    lines = [f"{settings.env_id}:", f"  n_timesteps: {settings.timesteps}", f"  policy: '{settings.policy}'"]
    lines.append(f"  n_envs: {settings.n_envs}")
    for name, value in kwargs.items():
        if name == "policy_kwargs":
            lines.append(f'  policy_kwargs: "{literal(value)}"')  # rl-zoo3 evaluates this string
        elif isinstance(value, tuple | list):
            lines.append(f"  {name}: {json.dumps(list(value))}")
        elif isinstance(value, str):
            lines.append(f"  {name}: '{value}'")
        elif isinstance(value, float) and "e" in literal(value):
            lines.append(f"  {name}: !!float {literal(value)}")  # YAML 1.1 reads 1e-05 as a string
        else:
            lines.append(f"  {name}: {literal(value)}")
    return "\n".join(lines)


def print_trial(trial: FrozenTrial) -> None:
    """One line for a finished trial: its number, its value (or why it was pruned or failed) and its settings."""
    params = ", ".join(f"{name}={literal(value)}" for name, value in trial.params.items())
    if trial.state == TrialState.COMPLETE:
        outcome = f"{trial.value:.4g}"
    elif trial.state == TrialState.PRUNED:
        scores = list(trial.intermediate_values.values())
        outcome = (
            "pruned: diverged"
            if "diverged" in trial.user_attrs
            else f"pruned after {len(scores)} evaluations, last {scores[-1]:.4g}"
        )
    else:
        outcome = "interrupted" if trial.user_attrs.get("interrupted") else "failed"
    print(f"trial {trial.number}: {outcome}  ({params})", flush=True)
