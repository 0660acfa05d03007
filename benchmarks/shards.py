"""Splitting one grid between machines: ``python -m benchmarks.run --preset P --shard I/N`` runs shard I of N.

The N shards of a grid (a preset's cells, after ``--only``) are the lists :func:`benchmarks.cost.longest_first`
makes for N cores from the estimated cell seconds: every cell falls in exactly one shard, and the shards' estimated
hours differ by at most the longest cell. The split depends only on the grid and the estimates, so every machine
must run the same preset, ``--only`` and commit (the merge refuses cells of different commits,
:mod:`benchmarks.merge`). Each machine writes into its own results folder; ``python -m benchmarks.merge`` puts them
together.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from benchmarks.cost import cell_seconds, longest_first
from benchmarks.presets import Cell

_SHARD = re.compile(r"^\s*(\d+)\s*/\s*(\d+)\s*$")


@dataclass(frozen=True)
class Shard:
    """Shard ``index`` (1 to ``count``) of a grid split ``count`` ways."""

    index: int
    count: int

    @classmethod
    def parse(cls, text: str) -> Shard:
        """``"2/4"`` -> ``Shard(2, 4)``. :raises ValueError: saying what is allowed, for any other text."""
        match = _SHARD.match(text)
        if match is None:
            raise ValueError(f"expected I/N, shard I of N (e.g. 2/4), got {text!r}")
        index, count = int(match[1]), int(match[2])
        if count < 1 or not 1 <= index <= count:
            raise ValueError(f"shard I/N needs 1 <= I <= N, got {text!r}")
        return cls(index, count)

    def __str__(self) -> str:
        return f"{self.index}/{self.count}"

    def cells(self, grid: list[Cell]) -> list[Cell]:
        """This shard's cells of ``grid``, in the grid's order."""
        mine = {cell.cell_id for cell in longest_first(grid, cell_seconds, lambda c: c.cell_id, self.count)[self.index - 1]}
        return [cell for cell in grid if cell.cell_id in mine]
