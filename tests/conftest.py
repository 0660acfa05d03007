"""Shared fixtures: the recorded rcssserver 19.0.0 cases shipped in ``robocup_dribble/data/golden``."""

from __future__ import annotations

from pathlib import Path

import pytest

from robocup_dribble.validate import GOLDEN_DIR


def golden_file(name: str) -> Path:
    """A file of the recorded server data; the test fails (not skips) if the data is missing."""
    path = GOLDEN_DIR / name
    if not path.is_file():
        pytest.fail(f"{path} is missing: it ships with the package (robocup_dribble/data/golden)")
    return path
