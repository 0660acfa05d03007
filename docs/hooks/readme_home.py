"""mkdocs hook: the site's home page is the repository's README, so the two cannot drift.

``docs/index.md`` holds only :data:`MARKER`; at build time it is replaced by ``README.md`` with its links made
relative to the site (``docs/X`` -> ``X``, ``benchmarks/results/X`` -> ``results/X``, where
``docs/hooks/benchmark_results.py`` publishes the report).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

MARKER = "<!-- README.md -->"
README = Path(__file__).resolve().parents[2] / "README.md"
LINK_PREFIXES = (("docs/", ""), ("benchmarks/results/", "results/"))


def home_markdown(readme: str) -> str:
    """The README as the site's home page: every Markdown link into ``docs/`` or ``benchmarks/results/`` rewritten."""

    def rewrite(match: re.Match[str]) -> str:
        target = match.group(1)
        for prefix, replacement in LINK_PREFIXES:
            if target.startswith(prefix):
                return f"]({replacement}{target[len(prefix) :]})"
        return match.group(0)

    return re.sub(r"\]\(([^)\s]+)\)", rewrite, readme)


def on_page_markdown(markdown: str, page: Any, **kwargs: Any) -> str:
    if markdown.strip() != MARKER:
        return markdown
    return home_markdown(README.read_text())
