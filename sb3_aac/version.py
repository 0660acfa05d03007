"""The package's version, read from ``version.txt`` (the same as ``pyproject.toml``'s): one floor below everything that
writes it (the exporters' ``writer``, the CLI's ``--version``, the Hub's model card)."""

from __future__ import annotations

from pathlib import Path

__version__ = (Path(__file__).parent / "version.txt").read_text().strip()
