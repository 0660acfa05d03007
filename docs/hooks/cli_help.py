"""mkdocs hook: replace ``<!-- cli-help -->`` in a page with the ``--help`` text of ``sb3-aac`` and every command.

The text comes from the parser itself at build time, so the page cannot fall behind the code.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

MARKER = "<!-- cli-help -->"
HELP_WIDTH = "100"  # columns argparse wraps the help text to, fixed so the page does not depend on the terminal


def _block(title: str, parser: argparse.ArgumentParser) -> str:
    return f"## `{title}`\n\n```text\n{parser.format_help().rstrip()}\n```\n"


def cli_reference() -> str:
    """The help text of ``sb3-aac`` and of each of its commands, as Markdown sections."""
    os.environ["COLUMNS"] = HELP_WIDTH
    from sb3_aac.cli import build_parser

    parser = build_parser()
    blocks = [_block(parser.prog, parser)]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            blocks += [_block(command.prog, command) for command in action.choices.values()]
    return "\n".join(blocks)


def on_page_markdown(markdown: str, page: Any, **kwargs: Any) -> str:
    if MARKER not in markdown:
        return markdown
    return markdown.replace(MARKER, cli_reference())
