"""Every example the command line's help prints runs: it parses, and a ``train`` example builds its model."""

from __future__ import annotations

import argparse
import re
import shlex

import pytest

from sb3_aac.cli import build_parser
from sb3_aac.cli.train import build_model, model_settings
from sb3_aac.common.algorithms import ALGOS


def help_examples() -> list[str]:
    """The ``sb3-aac ...`` command lines of the top-level epilog and of every command's epilog, without their notes
    (``# ...``, a trailing ``(...)``) and split where a line holds two (``|``)."""
    parser = build_parser()
    subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    texts = [parser.epilog or "", *(sub.epilog or "" for sub in subparsers.choices.values())]
    examples = []
    for text in texts:
        for line in text.splitlines():
            for part in line.split("   |   "):
                command = re.sub(r"\s{2,}(#|\().*$", "", part.split(" # ")[0]).strip()
                if command.startswith("sb3-aac "):
                    examples.append(command)
    return examples


def test_the_help_has_examples_of_every_command() -> None:
    parser = build_parser()
    subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    named = {shlex.split(example)[1] for example in help_examples()}
    assert named == set(subparsers.choices)


@pytest.mark.parametrize("example", sorted(set(help_examples())))
def test_help_example_runs(example: str) -> None:
    args = build_parser().parse_args(shlex.split(example)[1:])
    if args.command == "train":
        model = build_model(args, model_settings(args))
        assert type(model).__name__ == ALGOS[args.algo].class_name
        model.env.close()
