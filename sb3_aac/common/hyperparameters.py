"""The checks of hyperparameters the algorithms share, each raising a ``ValueError`` that names the argument, what is
allowed and what was given (``_check_hyperparameters`` of :class:`~sb3_aac.SarsaAAC`, :class:`~sb3_aac.PDQN` and
:class:`~sb3_aac.HybridPPO`)."""

from __future__ import annotations

from typing import Any

import numpy as np


def is_number(value: Any) -> bool:
    """A real number (Python's or numpy's), not a bool."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _shown(value: Any) -> str:
    return str(value) if is_number(value) else repr(value)


def check_unit_interval(owner: Any, *names: str, note: str = "") -> None:
    """Each ``owner.<name>`` a number in ``[0, 1]``; ``note`` follows the range in the message."""
    for name in names:
        value = getattr(owner, name)
        if not (is_number(value) and 0 <= value <= 1):
            raise ValueError(f"{name} must be in [0, 1]{note}, got {_shown(value)}")


def check_fraction(owner: Any, *names: str) -> None:
    """Each ``owner.<name>`` a number in ``(0, 1]`` (a share of the training that must not be empty)."""
    for name in names:
        value = getattr(owner, name)
        if not (is_number(value) and 0 < value <= 1):
            raise ValueError(f"{name} must be in (0, 1], got {_shown(value)}")


def check_counts(owner: Any, *names: str) -> None:
    """Each ``owner.<name>`` a whole number ``>= 1``."""
    for name in names:
        value = getattr(owner, name)
        if not (isinstance(value, (int, np.integer)) and not isinstance(value, bool) and value >= 1):
            raise ValueError(f"{name} must be an integer >= 1, got {value!r}")


def check_positive(owner: Any, *names: str) -> None:
    """Each ``owner.<name>`` a number ``> 0``."""
    for name in names:
        value = getattr(owner, name)
        if not (is_number(value) and value > 0):
            raise ValueError(f"{name} must be > 0, got {_shown(value)}")


def check_finite(owner: Any, *names: str, minimum: float | None = None) -> None:
    """Each ``owner.<name>`` a finite number (``>= minimum`` if given)."""
    for name in names:
        value = getattr(owner, name)
        if not (is_number(value) and np.isfinite(value) and (minimum is None or value >= minimum)):
            bound = "" if minimum is None else f" >= {minimum:g}"
            raise ValueError(f"{name} must be a finite number{bound}, got {value!r}")
