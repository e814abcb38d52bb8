"""Cells of a MovingAI grid and the segments between them: which segment joins two neighbouring cells,
and which neighbour a vehicle standing on (or arriving at) a cell is placed toward.

fleetsim's vehicles stand on segments, not on cells, so every format that names cells (a ``.scen`` file's
starts and goals, a League of Robot Runners problem's agents and errands) places a cell on the segment
from it to one of its free neighbours, chosen by :func:`neighbour_toward`.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from fleetsim.enums import Traverse
from fleetsim.errors import Location, ScenarioFileError
from fleetsim.layout.segment import Segment
from fleetsim.load.movingai.grid import Grid

__all__ = ["Cell", "GridCells", "manhattan", "neighbour_toward"]

Cell = tuple[int, int]  # (row, column)
_CELL_NAME = re.compile(r"r([0-9]+)c([0-9]+)")


class GridCells:
    """Which segment joins two neighbouring cells, from the segments' end names (``r3c4``)."""

    def __init__(self, grid: Grid, segments: Sequence[Segment]) -> None:
        self.grid = grid
        self.between: dict[tuple[Cell, Cell], int] = {}
        for segment in segments:
            if segment.ends is not None:
                first, second = (_cell(name) for name in segment.ends)
                self.between[(first, second)] = segment.id

    def leaving(self, cell: Cell, neighbour: Cell) -> tuple[int, Traverse]:
        """The segment from ``cell`` to ``neighbour`` and the traverse that drives it that way."""
        if (cell, neighbour) in self.between:
            return self.between[(cell, neighbour)], Traverse.FORWARD
        return self.between[(neighbour, cell)], Traverse.BACKWARD

    def neighbours(self, cell: Cell) -> tuple[Cell, ...]:
        """The free 4-neighbours of ``cell``: right, below, left, above."""
        row, column = cell
        around = ((row, column + 1), (row + 1, column), (row, column - 1), (row - 1, column))
        return tuple(other for other in around if self.grid.free(*other))


def _cell(name: str) -> Cell:
    found = _CELL_NAME.fullmatch(name)
    assert found is not None  # the reader names every end so
    return int(found.group(1)), int(found.group(2))


def manhattan(a: Cell, b: Cell) -> int:
    return abs(a[0] - b[0]) + abs(a[1] - b[1])


def neighbour_toward(
    cells: GridCells, cell: Cell, toward: Cell, taken: set[Cell] | None, what: str, where: Location
) -> Cell:
    """The neighbour of ``cell`` its segment leads to: not ``taken`` if possible, then nearest ``toward``
    (Manhattan), then right, below, left, above.

    A cell without a free neighbour has no segment to stand on or arrive by: a ScenarioFileError at
    ``where``, naming the cell as ``what`` (``"the start (x=1, y=2)"``)."""
    options = cells.neighbours(cell)
    if not options:
        msg = (
            f"{what} is a free cell without a free neighbour: "
            "no segment reaches it, so no vehicle can stand or arrive there"
        )
        raise ScenarioFileError(msg, where)
    blocked = taken or set()
    ranked = sorted(enumerate(options), key=lambda item: (item[1] in blocked, manhattan(item[1], toward), item[0]))
    return ranked[0][1]
