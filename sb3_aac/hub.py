"""
Share a trained model on the Hugging Face Hub: a folder holding the model, its exported policy, the evaluation and a
model card that says what the model is and how to load it with sb3-aac, uploaded as one commit.

:func:`hub_folder` writes the folder (no network); :func:`push_folder` uploads it through ``huggingface_hub``'s
``HfApi`` (``pip install sb3-aac[hub]``; log in with ``huggingface-cli login`` or pass a token). ``sb3-aac push`` does
both. The card's metadata (``library_name``, tags, a ``model-index`` with the evaluation) is what the Hub indexes.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any

from sb3_aac.common.output_files import RunFolder
from sb3_aac.version import __version__

CARD = "README.md"
MODEL = "model.zip"
POLICY = "policy.aacp"
RESULTS = "results.json"
LIBRARY = "sb3-aac"


@dataclass(frozen=True)
class Evaluation:
    """
    What the card reports: ``metrics`` (name -> value, e.g. ``{"mean_distance": 25.3}``) measured greedily on
    ``episodes`` episodes of ``env_id``, with a line saying how (``protocol``).
    """

    env_id: str
    episodes: int
    metrics: dict[str, float]
    protocol: str = "greedy (deterministic) actions"
    units: dict[str, str] = field(default_factory=dict)


def card_metadata(algorithm: str, policy: str, evaluation: Evaluation) -> str:
    """The card's YAML metadata, as the Hub indexes it (``library_name``, ``tags``, a ``model-index`` with the
    evaluation); written here, so that a card needs no ``huggingface_hub``. Strings are JSON-quoted (valid YAML)."""
    q = json.dumps
    tags = ["reinforcement-learning", "stable-baselines3", LIBRARY, "parameterized-actions", evaluation.env_id, algorithm]
    metrics = "".join(
        f"    - type: {q(name)}\n      value: {round(float(value), 4)!r}\n      name: {q(name)}\n"
        for name, value in evaluation.metrics.items()
    )
    return (
        f"library_name: {q(LIBRARY)}\ntags:\n"
        + "".join(f"- {q(tag)}\n" for tag in tags)
        + f"model-index:\n- name: {q(f'{algorithm}-{policy}-{evaluation.env_id}')}\n  results:\n"
        + f"  - task:\n      type: reinforcement-learning\n    dataset:\n      name: {q(evaluation.env_id)}\n"
        + f"      type: {q(evaluation.env_id)}\n    metrics:\n{metrics}"
    )


def env_import(env_id: str) -> str:
    """The line that registers ``env_id``: an import of its entry point's top package (a comment if not registered)."""
    import gymnasium as gym

    spec = gym.registry.get(env_id)
    if spec is None:
        return f"# import the package that registers {env_id}"
    module = spec.entry_point if isinstance(spec.entry_point, str) else spec.entry_point.__module__
    return f"import {module.split(':')[0].split('.')[0]}  # registers {env_id}"


def model_card(algorithm: str, policy: str, evaluation: Evaluation, has_policy_file: bool, repo_id: str) -> str:
    """The model card: YAML metadata the Hub indexes, then what the model is, its figures, how to install sb3-aac (it
    is not on PyPI: its wheel) and a snippet that loads the model, makes its env and decides."""
    figures = "\n".join(
        f"| {name} | {value:.4g}{' ' + evaluation.units[name] if name in evaluation.units else ''} |"
        for name, value in evaluation.metrics.items()
    )

    def snippet(loader: str, load: str, decide: str) -> str:
        return f"""```python
import gymnasium as gym
{env_import(evaluation.env_id)}
from huggingface_hub import hf_hub_download
{loader}

{load}
env = gym.make("{evaluation.env_id}")
obs, info = env.reset(seed=0)
{decide}
```"""

    model_snippet = snippet(
        f"from sb3_aac import {algorithm}",
        f'model = {algorithm}.load(hf_hub_download("{repo_id}", "{MODEL}"))',
        "action, _ = model.predict(obs, deterministic=True)\nobs, reward, terminated, truncated, info = env.step(action)",
    )
    runtime_snippet = snippet(
        "from sb3_aac.runtime import RuntimePolicy",
        f'policy = RuntimePolicy.load(hf_hub_download("{repo_id}", "{POLICY}"))',
        "action_type, params = policy.act(obs)",
    )
    runtime = (
        "\nOr decide with numpy alone (no torch; e.g. inside a RoboCup agent) from the exported policy:\n\n"
        f"{runtime_snippet}\n"
        if has_policy_file
        else ""
    )
    policy_line = f" `{POLICY}`: the exported policy (plain JSON and float64 arrays);" if has_policy_file else ""
    wheel = f"sb3_aac-{__version__}-py3-none-any.whl"
    body = f"""
# {algorithm} ({policy}) on {evaluation.env_id}

A parameterized-action agent (pick one of K action types, then a real-valued parameter vector for it) trained with
**{algorithm}** and the `{policy}` policy of sb3-aac {__version__}, the Stable-Baselines3 home for hybrid-action
reinforcement learning, on `{evaluation.env_id}`.

## Evaluation

{evaluation.episodes} episodes, {evaluation.protocol}:

| metric | value |
|---|---|
{figures}

## Usage

sb3-aac is not on PyPI: install its wheel (`python -m build --wheel` in a clone of the sb3-aac repository writes
`dist/{wheel}`), or `pip install "./sb3-aac[hub]"` from beside the clone:

```bash
pip install "./dist/{wheel}[hub]"
```

{model_snippet}

A `model.zip` holds pickled entries that SB3's `load` runs: load it only from people you trust. `sb3-aac evaluate` and
`sb3-aac export` load it without unpickling anything.
{runtime}
## Files

- `{MODEL}`: the model (`{algorithm}.load`);{policy_line}
  `{RESULTS}`: the evaluation above.
"""
    return f"---\n{card_metadata(algorithm, policy, evaluation)}---\n{body}"


def hub_folder(
    model: Any,
    folder: str | os.PathLike[str],
    evaluation: Evaluation,
    repo_id: str,
    overwrite: bool = False,
) -> list[str]:
    """
    Write ``folder`` (created if missing; nothing else in it is touched) with ``model.zip``, ``policy.aacp`` where
    :func:`sb3_aac.export_policy` can carry the model, ``results.json`` and the model card ``README.md``.

    :return: the names of the files written (what :func:`push_folder` uploads)
    :raises ValueError: if ``folder`` cannot be written or already holds those files without ``overwrite``
    """
    from sb3_aac.export import export_policy

    algorithm, policy = type(model).__name__, type(model.policy).__name__
    names = (MODEL, POLICY, RESULTS, CARD)
    out = RunFolder(folder, names, "the Hub folder", overwrite=overwrite)
    with out.file(MODEL) as tmp:
        model.save(tmp)
    has_policy_file = True
    try:
        with out.file(POLICY) as tmp:
            export_policy(model, tmp, metadata={"env_id": evaluation.env_id})
    except ValueError:  # the format does not carry this algorithm's networks
        has_policy_file = False
    results = {"env_id": evaluation.env_id, "episodes": evaluation.episodes, "protocol": evaluation.protocol,
               **evaluation.metrics}  # fmt: skip
    with out.file(RESULTS) as tmp:
        tmp.write_text(json.dumps(results, indent=2) + "\n")
    with out.file(CARD) as tmp:
        tmp.write_text(model_card(algorithm, policy, evaluation, has_policy_file, repo_id))
    return [MODEL, *([POLICY] if has_policy_file else []), RESULTS, CARD]


def push_folder(
    folder: str | os.PathLike[str],
    files: list[str],
    repo_id: str,
    api: Any = None,
    private: bool = False,
    commit_message: str = "Upload sb3-aac model",
) -> str:
    """
    Upload ``files`` of ``folder`` (nothing else in it) to the Hub model repository ``repo_id``, created if missing,
    as one commit.

    :param api: a ``huggingface_hub.HfApi`` (None: one with the logged-in token)
    :return: the repository's URL
    """
    if api is None:
        from huggingface_hub import HfApi

        api = HfApi()
    url = api.create_repo(repo_id=repo_id, repo_type="model", private=private, exist_ok=True)
    api.upload_folder(
        repo_id=repo_id, repo_type="model", folder_path=str(folder), allow_patterns=files, commit_message=commit_message
    )
    return str(url)
