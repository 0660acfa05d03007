"""
The C runtime of exported policies: ``aacp.h``, one C99 header (no dependency beyond the C standard library) that
loads and checks a ``.aacp`` file and returns the decisions :meth:`RuntimePolicy.act
<sb3_aac.runtime.policy.RuntimePolicy.act>` returns, for C and C++ agents. See ``docs/c-runtime.md``;
``sb3-aac c-header`` prints its path.
"""

from __future__ import annotations

from pathlib import Path

HEADER_NAME = "aacp.h"


def header_path() -> Path:
    """The installed ``aacp.h`` (compile with ``-I`` its folder, or copy it into the agent's sources)."""
    return Path(__file__).with_name(HEADER_NAME)
