"""A League problem's agent file and task file, each location checked against the grid map.

Both start with a count and give one item per line after it; lines starting with ``#`` (``# version for
LoRR 2024``) and blank lines are skipped. A location is one whole number, ``row × width + column`` (row 0
the top line of the grid).

- Agent file: the count ``n``, then ``n`` lines of one location each: agent ``i`` (from 0) starts there.
- Task file: the count ``m``, then ``m`` lines: one location each in 2023; from 2024 on, one or more,
  separated by commas (a multi-errand task: its errands in that order).

Every problem is a :class:`~fleetsim.errors.ScenarioFileError` at its line and column: a count that is no
whole number or that disagrees with the lines that follow, a location that is no whole number, off the
map or on a blocked cell, an empty task, several errands in a 2023 task. All of a file's problems are
reported together.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from fleetsim.errors import Location, ScenarioFileError
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.text import read_text_file
from fleetsim.load.movingai.cells import Cell
from fleetsim.load.movingai.grid import Grid

__all__ = ["LorrItem", "location_name", "read_agents", "read_tasks"]


@dataclass(frozen=True, slots=True)
class LorrItem:
    """An agent's start (one cell) or a task's errands (cells in order), with its line in its file."""

    line: int
    cells: tuple[Cell, ...]
    locations: tuple[int, ...]


def location_name(location: int, grid: Grid) -> str:
    """``location 37 (row 1, column 5)``."""
    row, column = divmod(location, grid.width)
    return f"location {location} (row {row}, column {column})"


def read_agents(path: Path, grid: Grid) -> tuple[LorrItem, ...]:
    """Every agent of the agent file at ``path``, in file order."""
    return _read(path, grid, "agent", multi=False)


def read_tasks(path: Path, grid: Grid, *, multi: bool) -> tuple[LorrItem, ...]:
    """Every task of the task file at ``path``, in file order; ``multi``: errands separated by commas
    (2024 on)."""
    return _read(path, grid, "task", multi=multi)


def _read(path: Path, grid: Grid, what: str, *, multi: bool) -> tuple[LorrItem, ...]:
    text = read_text_file(path, ScenarioFileError)
    lines = [
        (number, line.removesuffix("\r"))
        for number, line in enumerate(text.split("\n"), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise ScenarioFileError(f"the {what} file is empty: it starts with the number of {what}s", Location(path))
    count_line, count_text = lines[0]
    word = count_text.strip()
    if not (word.isascii() and word.isdigit()):
        msg = f"the first line must be the number of {what}s (a whole number), not {word[:40]!r}"
        raise ScenarioFileError(msg, Location(path, line=count_line, column=_column(count_text, word)))
    count = int(word)
    rows = lines[1:]
    errors = ErrorCollector()
    if len(rows) != count:
        where = rows[count][0] if len(rows) > count else (rows[-1][0] if rows else count_line)
        problem = f"line {count_line} says {count} {what}(s), but {len(rows)} follow" + (
            f"; line {where} is one too many" if len(rows) > count else ""
        )
        errors.add(ScenarioFileError(problem, Location(path, line=where)))
    items = []
    for number, line in rows[:count]:
        with errors.collecting():
            items.append(_item(path, number, line, grid, what, multi))
    errors.raise_if_any()
    return tuple(items)


def _column(line: str, part: str) -> int:
    return line.find(part) + 1 if part else 1


def _item(path: Path, number: int, line: str, grid: Grid, what: str, multi: bool) -> LorrItem:
    parts = line.split(",")
    if len(parts) > 1 and not multi:
        hint = (
            " (2024 tasks may have several; this problem has no version, so it is a 2023 one)" if what == "task" else ""
        )
        one = "an agent starts at one" if what == "agent" else "a task has one"
        msg = f"the line {line.strip()[:40]!r} has {len(parts)} locations; {one}{hint}"
        raise ScenarioFileError(msg, Location(path, line=number, column=line.find(",") + 1))
    cells, locations = [], []
    position = 0
    for index, part in enumerate(parts):
        word = part.strip()
        column = position + (part.find(word) if word else 0) + 1
        position += len(part) + 1
        where = Location(path, line=number, column=column)
        if not (word.isascii() and word.isdigit()):
            place = f"errand {index + 1} of the task" if what == "task" else "the agent's start"
            shown = repr(word) if word else "empty"
            raise ScenarioFileError(f"{place} is {shown}: a location is a whole number (row × width + column)", where)
        location = int(word)
        cells.append(_cell(location, grid, where))
        locations.append(location)
    return LorrItem(number, tuple(cells), tuple(locations))


def _cell(location: int, grid: Grid, where: Location) -> Cell:
    size = grid.width * grid.height
    if location >= size:
        msg = f"location {location} is off the map ({grid.width} x {grid.height} cells: locations 0 to {size - 1})"
        raise ScenarioFileError(msg, where)
    row, column = divmod(location, grid.width)
    if not grid.free(row, column):
        char = grid.rows[row][column]
        cell = grid.location(row, column)
        msg = (
            f"{location_name(location, grid)} is on a blocked cell {char!r} "
            f"(line {cell.line}, column {cell.column} of {grid.path.name})"
        )
        raise ScenarioFileError(msg, where)
    return (row, column)
