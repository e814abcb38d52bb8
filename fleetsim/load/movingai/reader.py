"""A MovingAI grid map as a lane graph: a two-way straight segment between every two 4-neighbouring free
cells, from cell centre to cell centre, so that the joints are the cell centres and a vehicle turns in
place at a corner.

Geometry. A cell is ``cell_size`` metres square (``map_options: {cell_size: S}``, default 1 m). The grid
lies in fleetsim's frame as a Tiled map of ``width × height`` tiles would: origin at the map's centre, y
up, row 0 the top row of the file. The centre of the cell in row ``r`` and column ``c`` (MovingAI ``x =
c``, ``y = r``) is ``X = (c + ½ − width/2)·S``, ``Y = (height/2 − r − ½)·S``.

Ids and names. Segments are numbered 1, 2, ... over the free cells in file order (row by row, left to
right), each cell's segment to its right neighbour before the one to the cell below. A segment is named
after its cells, ``r3c4-r3c5`` (the first cell in file order first), and answers to ``r3c5-r3c4`` too;
its ends are the cells ``r3c4`` and ``r3c5`` (VDA 5050 node ids). Its waypoints run from the first cell
to the second.
"""

from __future__ import annotations

import math
from pathlib import Path

from fleetsim.enums import Direction, Shape
from fleetsim.errors import Location, MapError
from fleetsim.layout.segment import Segment
from fleetsim.load.common.import_notes import ImportNotes
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.movingai.grid import FREE, Grid, cell_name, read_grid

__all__ = ["DEFAULT_CELL_SIZE", "cell_size_of", "grid_segments", "load_movingai"]

DEFAULT_CELL_SIZE = 1.0


def cell_size_of(options: MapOptions, path: Path) -> float:
    """The map option ``cell_size`` (metres), checked; :data:`DEFAULT_CELL_SIZE` when it is not given."""
    size = options.cell_size
    if size is None:
        return DEFAULT_CELL_SIZE
    if isinstance(size, bool) or not isinstance(size, (int, float)) or not math.isfinite(size) or size <= 0:
        raise MapError(f"cell_size={size!r} must be a positive number of metres", Location(path, field="cell_size"))
    return float(size)


def grid_segments(grid: Grid, cell_size: float) -> tuple[Segment, ...]:
    """The grid's segments (see the module docstring)."""
    segments: list[Segment] = []
    size, half_w, half_h = cell_size, grid.width / 2, grid.height / 2
    rows = grid.rows
    for row, text in enumerate(rows):
        below = rows[row + 1] if row + 1 < grid.height else ""
        y = (half_h - row - 0.5) * size
        for column, char in enumerate(text):
            if char not in FREE:
                continue
            x = (column + 0.5 - half_w) * size
            name = cell_name(row, column)
            if column + 1 < grid.width and text[column + 1] in FREE:
                other = cell_name(row, column + 1)
                sid = len(segments) + 1
                segments.append(_lane(sid, (x, y), (x + size, y), name, other))
            if below and below[column] in FREE:
                other = cell_name(row + 1, column)
                sid = len(segments) + 1
                segments.append(_lane(sid, (x, y), (x, y - size), name, other))
    return tuple(segments)


def _lane(sid: int, start: tuple[float, float], end: tuple[float, float], first: str, second: str) -> Segment:
    names = (f"{first}-{second}", f"{second}-{first}")
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, (start, end), names, ends=(first, second))


def load_movingai(path: Path, options: MapOptions) -> SiteMap:
    """The lane graph of the MovingAI map at ``path``; ``options.cell_size`` in metres (default 1)."""
    size = cell_size_of(options, path)
    grid = read_grid(path)
    segments = grid_segments(grid, size)
    if not segments:
        msg = "the map has no two neighbouring free cells, so no segment (free cells are . G S E)"
        raise MapError(msg, Location(path))
    notes = ImportNotes(path)
    for name in options.given():
        if name != "cell_size":
            notes.note("option-ignored", f"map option {name!r} (for LIF and RMF maps)", "map_options")
    part = f"{grid.width} x {grid.height} cells of {size:g} m"
    return SiteMap(path, "movingai", segments, notes.warnings(), part=part)
