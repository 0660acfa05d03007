"""Shared fixtures: the recorded rcssserver cases in ../shared/golden (cloned beside the repository)."""

from __future__ import annotations

from pathlib import Path

import pytest

GOLDEN = Path(__file__).resolve().parents[1].parent / "shared" / "golden"


def golden_file(name: str) -> Path:
    """A file of the recorded server data; the test fails (not skips) if the data is missing."""
    path = GOLDEN / name
    if not path.is_file():
        pytest.fail(f"{path} is missing: clone the repository with shared/ beside it (see README)")
    return path
