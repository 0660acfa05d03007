"""The benchmark's learners' search spaces and their tuned settings (``hyperparams/tuned/<env id>/<learner>.yml``).

Search spaces: rl-zoo3's samplers (``rl_zoo3.hyperparams_opt.HYPERPARAMS_SAMPLER``) for SB3's algorithms, which
train through the action wrappers exactly as the grid runs them (:mod:`benchmarks.adapters`; the sampler sees the
wrapped action size), and sb3-aac's (:data:`sb3_aac.tune.search_spaces.SEARCH_SPACES`) for SarsaAAC, P-DQN,
MP-DQN and HybridPPO. A learner is an algorithm and a config of the grid (``("SarsaAAC", "tile")``, ``("TD3", "td3")``).

A tuned file holds the best trial's Optuna parameters (``params``, plain numbers and strings) with the study's
budget. A cell of config ``<config>-tuned`` carries those parameters in ``overrides["tuned_params"]``
(:func:`resolve_tuned`, at the start of a run: the cell file says what it ran with, a study tuned again makes
new cells, and a Ray task needs no file), and :func:`tuned_cell` turns them back into keyword arguments by
replaying them through the same sampler (``optuna.trial.FixedTrial``): one definition of every conversion.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import optuna
import yaml

from benchmarks.adapters import env_action_space
from benchmarks.presets import BASELINES, SARSA_CONFIGS, Cell, base_config, is_tuned
from benchmarks.zoo_hyperparams import HYPERPARAMS

TUNED_DIR_VAR = "SB3_AAC_BENCH_TUNED_DIR"  # another folder of tuned files (tests); forwarded to Ray tasks
TUNED_PARAMS = "tuned_params"  # the key of a tuned cell's overrides holding the best trial's parameters
TUNING_RECORD = "tuning"  # ... and the one holding its study's budget and best value (for the report)

# sb3-aac's search spaces: algo -> its key in sb3_aac.tune's tables (the policy comes from the config).
SB3_AAC_SPACES = {"SarsaAAC": "sarsa_aac", "PDQN": "pdqn", "MPDQN": "mpdqn", "HybridPPO": "hppo"}
NO_HER = {"using_her_replay_buffer": False, "her_kwargs": {}}  # rl-zoo3's additional_args for a sampler


def tuned_dir() -> Path:
    return Path(os.environ.get(TUNED_DIR_VAR) or HYPERPARAMS / "tuned")


def learner_name(algo: str, config: str) -> str:
    """``"TD3"`` for TD3's own config, ``"SarsaAAC-tile"`` for a SarsaAAC config: the tuned file's and study's name."""
    config = base_config(config)
    return algo if config == algo.lower() else f"{algo}-{config}"


def tuned_path(env_id: str, algo: str, config: str, folder: Path | None = None) -> Path:
    return (folder or tuned_dir()) / env_id / f"{learner_name(algo, config)}.yml"


def tunable(algo: str, config: str) -> bool:
    """Whether the learner has a search space here."""
    if algo in SB3_AAC_SPACES:
        return algo != "SarsaAAC" or base_config(config) in SARSA_CONFIGS
    return algo in BASELINES


def _sb3_aac_policy(algo: str, config: str) -> str:
    return SARSA_CONFIGS[base_config(config)][1] if algo == "SarsaAAC" else "MlpPolicy"


def sample_kwargs(trial: optuna.Trial | optuna.trial.FixedTrial, env_id: str, algo: str, config: str) -> dict[str, Any]:
    """The learner's constructor keyword arguments for one point of its search space (asked from ``trial``)."""
    if algo in SB3_AAC_SPACES:
        from sb3_aac.tune.search_spaces import search_space

        space = search_space(SB3_AAC_SPACES[algo], _sb3_aac_policy(algo, config))
        return space.to_kwargs(space.sample(trial))  # type: ignore[arg-type]
    if algo not in BASELINES:
        raise ValueError(f"{algo} has no search space; tunable: {sorted([*SB3_AAC_SPACES, *BASELINES])}")
    from rl_zoo3.hyperparams_opt import HYPERPARAMS_SAMPLER

    from sb3_aac.common.spaces import ParameterizedActionSpec

    spec = ParameterizedActionSpec.from_space(env_action_space(env_id))
    sampler: Callable[..., dict[str, Any]] = HYPERPARAMS_SAMPLER[algo.lower()]
    kwargs = sampler(trial, spec.n_types + spec.n_params, BASELINES[algo]["n_envs"], NO_HER)
    if "action_noise_sigma" in BASELINES[algo]:
        kwargs.setdefault("action_noise", None)  # the sampler's "no noise" holds (not the grid's default noise)
    return kwargs


def read_tuned(env_id: str, algo: str, config: str) -> dict[str, Any]:
    """The tuned file of a learner.

    :raises FileNotFoundError: saying how to make it
    :raises ValueError: naming the file, if it is not YAML (a syntax error, a python tag, NUL bytes) or has no params
    """
    path = tuned_path(env_id, algo, config)
    if not path.is_file():
        raise FileNotFoundError(f"{path} (run the tuning stage: python -m benchmarks.run --tune --preset ...)")
    try:
        data = yaml.safe_load(path.read_text())
    except (yaml.YAMLError, UnicodeDecodeError) as error:  # a syntax error, a python tag, NUL bytes, not UTF-8
        first = " ".join(str(error).split())[:200]
        raise ValueError(
            f"{path} is not a tuned-settings YAML file ({type(error).__name__}: {first}); fix it or run the tuning stage again"
        ) from None
    if not (isinstance(data, dict) and isinstance(data.get("params"), dict)):
        raise ValueError(f"{path} is damaged (no 'params' mapping); run the tuning stage again")
    return data


def resolve_tuned(cells: Sequence[Cell]) -> list[Cell]:
    """The cells with every tuned config's parameters read into ``overrides["tuned_params"]``.

    :raises ValueError: naming every tuned file that is missing or damaged, before any cell runs
    """
    resolved, problems = [], []
    for cell in cells:
        if is_tuned(cell.config) and TUNED_PARAMS not in cell.overrides:
            try:
                tuned = read_tuned(cell.env_id, cell.algo, cell.config)
            except (OSError, ValueError) as error:
                problems.append(str(error))
                continue
            record = {"study": tuned.get("study"), "budget": tuned.get("budget"), "best": tuned.get("best")}
            cell = replace(cell, overrides={**cell.overrides, TUNED_PARAMS: tuned["params"], TUNING_RECORD: record})
        resolved.append(cell)
    if problems:
        raise ValueError("no tuned settings for " + "; ".join(sorted(set(problems))))
    return resolved


def tuned_cell(cell: Cell, kwargs_as_text: bool = False) -> Cell:
    """The cell as its base config with the tuned parameters as constructor keyword arguments (``kwargs_as_text``:
    values that are not JSON, such as classes and noise objects, as their ``repr``, for the cell file)."""
    params = cell.overrides.get(TUNED_PARAMS)
    if params is None:
        raise ValueError(f"cell {cell.cell_id} has no tuned parameters (benchmarks.tuned.resolve_tuned reads them)")
    kwargs = sample_kwargs(optuna.trial.FixedTrial(params), cell.env_id, cell.algo, cell.config)
    extra = {k: v for k, v in cell.overrides.items() if k not in (TUNED_PARAMS, TUNING_RECORD)}
    kwargs = {**kwargs, **extra}
    if kwargs_as_text:
        kwargs = _jsonable(kwargs)
    return replace(cell, config=base_config(cell.config), overrides=kwargs)


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return getattr(value, "__name__", None) or repr(value)
