"""A MovingAI grid map (``*.map``) read into a :class:`Grid` of free and blocked cells, with located errors.

The format (https://movingai.com/benchmarks/formats.html)::

    type octile
    height H
    width W
    map
    H rows of W characters

Passability, as the format defines it for a vehicle on regular ground: ``.`` and ``G`` (ground) are free,
``@`` and ``O`` (out of bounds) and ``T`` (trees) are blocked; ``S`` (swamp) is passable from regular
terrain and so free; ``W`` (water) is passable only from water, which no vehicle of a lane graph drives
on, so it is blocked. The League of Robot Runners' maps add ``E`` (an emitter) and use ``S`` (a service
point): both free. Rows may end in ``\\r\\n``; trailing blank lines are fine.

Every problem is a :class:`~fleetsim.errors.MapError` at its line (and column, for a grid row): a missing
or garbled header, a row of the wrong width, an unknown character, too few or too many rows. The rows'
problems are reported together (at most 50, :class:`~fleetsim.load.common.collect.ErrorCollector`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from fleetsim.errors import Location, MapError
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.text import read_text_file

__all__ = ["BLOCKED", "FREE", "Grid", "cell_name", "parse_grid", "read_grid"]

FREE = ".GSE"
BLOCKED = "@OTW"
_BAD_CHARACTER = re.compile(f"[^{re.escape(FREE + BLOCKED)}]")
_HEADER_LINES = 4  # type, height, width, map
_MAX_SIDE = 100_000  # a side this long is a typo, not a map (and would exhaust memory)


def cell_name(row: int, column: int) -> str:
    """``r3c4``: the name of the cell in row 3 (from the top, 0 first) and column 4 (0 first)."""
    return f"r{row}c{column}"


@dataclass(frozen=True, slots=True)
class Grid:
    """A MovingAI map's cells: ``rows[r][c]`` is the character at row ``r`` (0 = the top line of the grid)
    and column ``c``; ``first_line`` is the file line of row 0 (for errors that point into the grid)."""

    path: Path
    height: int
    width: int
    rows: tuple[str, ...]
    first_line: int = _HEADER_LINES + 1

    def free(self, row: int, column: int) -> bool:
        """Whether the cell exists and a vehicle may stand on it."""
        return 0 <= row < self.height and 0 <= column < self.width and self.rows[row][column] in FREE

    def location(self, row: int, column: int) -> Location:
        """Where the cell is written in the map file (1-based line and column)."""
        return Location(self.path, line=self.first_line + row, column=column + 1)


def read_grid(path: Path) -> Grid:
    """Read and check the map at ``path`` (see the module docstring)."""
    return parse_grid(read_text_file(path, MapError), path)


def parse_grid(text: str, path: Path) -> Grid:
    """Check ``text``, the contents of the map at ``path``, and give its grid."""
    lines = text.split("\n")
    lines = [line.removesuffix("\r") for line in lines]
    height, width = _header(lines, path)
    errors = ErrorCollector()
    rows: list[str] = []
    for index in range(height):
        number = _HEADER_LINES + 1 + index
        if number > len(lines) or (number == len(lines) and not lines[-1]):
            found = len(rows)
            msg = f"the grid has {found} row(s) but the header says height {height}: the file ends here"
            errors.add(MapError(msg, Location(path, line=min(number, len(lines)))))
            break
        row = lines[number - 1]
        with errors.collecting():
            _check_row(row, width, Location(path, line=number))
        rows.append(row)
    for number in range(_HEADER_LINES + height + 1, len(lines) + 1):
        if lines[number - 1].strip():
            msg = f"a line after the grid's {height} rows (height {height}); the grid must end here"
            errors.add(MapError(f"{msg}: {_shown(lines[number - 1])}", Location(path, line=number, column=1)))
            break
    errors.raise_if_any()
    return Grid(path, height, width, tuple(rows))


def _header(lines: list[str], path: Path) -> tuple[int, int]:
    """``(height, width)`` from the four header lines, in the order the format gives them."""
    expected = ("type", "height", "width", "map")
    values: dict[str, int] = {}
    for number, key in enumerate(expected, start=1):
        line = lines[number - 1] if number <= len(lines) else None
        where = Location(path, line=min(number, len(lines)))
        if line is None:
            raise MapError(f"the header ends early: line {number} must be {_form(key)!r}", where)
        words = line.split()
        if not words or words[0].lower() != key:
            found = f"{_shown(line)}" if line.strip() else "an empty line"
            raise MapError(f"header line {number} must be {_form(key)!r}, not {found}", where)
        if key == "type":
            if len(words) != 2 or words[1].lower() != "octile":
                raise MapError(f"the map type is {_shown(line)}; fleetsim reads 'type octile' maps", where)
        elif key == "map":
            if len(words) != 1:
                raise MapError(f"header line 4 must be 'map' alone, not {_shown(line)}", where)
        else:
            values[key] = _side(words, key, line, where)
    return values["height"], values["width"]


def _side(words: list[str], key: str, line: str, where: Location) -> int:
    if len(words) != 2 or not words[1].isdigit() or not words[1].isascii():
        raise MapError(f"header line {_shown(line)} must be {_form(key)!r} with a whole number", where)
    value = int(words[1])
    if not 1 <= value <= _MAX_SIDE:
        raise MapError(f"{key}={value} must be from 1 to {_MAX_SIDE}", where)
    return value


def _check_row(row: str, width: int, where: Location) -> None:
    bad = _BAD_CHARACTER.search(row)
    if bad is not None and bad.start() < width:
        column = bad.start() + 1
        msg = (
            f"unknown cell character {bad.group()!r}; a MovingAI map cell is one of "
            f"{' '.join(FREE)} (free) or {' '.join(BLOCKED)} (blocked)"
        )
        raise MapError(msg, Location(where.path, line=where.line, column=column))
    if len(row) != width:
        column = min(len(row), width) + 1
        msg = f"the row is {len(row)} cell(s) wide; the header says width {width}"
        raise MapError(msg, Location(where.path, line=where.line, column=column))


def _form(key: str) -> str:
    return {"type": "type octile", "height": "height H", "width": "width W", "map": "map"}[key]


def _shown(value: str) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."
