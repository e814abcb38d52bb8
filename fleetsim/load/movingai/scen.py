"""A MovingAI scenario file (``*.scen``) read into agents, each checked against its grid map.

The format (https://movingai.com/benchmarks/formats.html): a ``version 1`` line, then one agent per line,
nine tab-separated fields ``bucket map width height start_x start_y goal_x goal_y optimal_length``, with
``x`` the column and ``y`` the row (0 = the map's top row). Every problem is a
:class:`~fleetsim.errors.ScenarioFileError` at its line, column and field: a missing version, a row with
the wrong number of fields, a value that is no number, a map name or size that is not the map's, a start
or goal off the map or on a blocked cell. All rows are checked and their problems reported together.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from fleetsim.errors import Location, ScenarioFileError
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.text import read_text_file
from fleetsim.load.movingai.grid import Grid

__all__ = ["SCEN_FIELDS", "ScenAgent", "read_scen", "scen_map_name"]

SCEN_FIELDS = ("bucket", "map", "width", "height", "start_x", "start_y", "goal_x", "goal_y", "optimal_length")
Cell = tuple[int, int]


@dataclass(frozen=True, slots=True)
class ScenAgent:
    """One agent of a ``.scen`` file: its line, and its start and goal as ``(row, column)`` cells."""

    line: int
    start: Cell
    goal: Cell
    optimal_length: float


@dataclass(frozen=True, slots=True)
class _Row:
    path: Path
    line: int
    fields: tuple[str, ...]
    columns: tuple[int, ...]  # 1-based character column of each field

    def error(self, index: int, problem: str) -> ScenarioFileError:
        where = Location(self.path, line=self.line, column=self.columns[index], field=SCEN_FIELDS[index])
        return ScenarioFileError(problem, where)

    def whole(self, index: int) -> int:
        text = self.fields[index]
        if not (text.isascii() and text.isdigit()):
            raise self.error(index, f"{SCEN_FIELDS[index]}={text!r} must be a whole number >= 0")
        return int(text)


def scen_map_name(path: Path) -> tuple[str, Location] | None:
    """The map the file's first agent names, with where (``None`` when no row names one)."""
    for row in _rows(read_text_file(path, ScenarioFileError), path):
        if len(row.fields) > 1 and row.fields[1]:
            return row.fields[1], Location(path, line=row.line, column=row.columns[1], field="map")
    return None


def read_scen(path: Path, grid: Grid) -> tuple[ScenAgent, ...]:
    """Every agent of the file at ``path``, each checked against ``grid`` (see the module docstring)."""
    text = read_text_file(path, ScenarioFileError)
    errors = ErrorCollector()
    agents = []
    for row in _rows(text, path):
        with errors.collecting():
            agents.append(_agent(row, grid))
    errors.raise_if_any()
    if not agents:
        raise ScenarioFileError("the scenario file has no agents (rows after 'version 1')", Location(path))
    return tuple(agents)


def _rows(text: str, path: Path) -> list[_Row]:
    """The agent rows after the version line (blank lines skipped)."""
    lines = [line.removesuffix("\r") for line in text.split("\n")]
    first = next((number for number, line in enumerate(lines, start=1) if line.strip()), None)
    if first is None:
        raise ScenarioFileError("the file is empty; a scenario file starts with 'version 1'", Location(path))
    words = lines[first - 1].split()
    if len(words) != 2 or words[0].lower() != "version" or words[1] not in ("1", "1.0"):
        shown = repr(lines[first - 1][:40])
        msg = f"the first line must be 'version 1' (the MovingAI scenario format), not {shown}"
        raise ScenarioFileError(msg, Location(path, line=first, column=1))
    rows = []
    for number in range(first + 1, len(lines) + 1):
        line = lines[number - 1]
        if line.strip():
            rows.append(_split(line, path, number))
    return rows


def _split(line: str, path: Path, number: int) -> _Row:
    """The row's fields and where each starts: tab-separated, or separated by spaces when it has no tab."""
    fields, columns = [], []
    position = 0
    parts = line.split("\t") if "\t" in line else line.split(" ")
    for part in parts:
        if part or "\t" in line:
            stripped = part.strip()
            fields.append(stripped)
            columns.append(position + len(part) - len(part.lstrip()) + 1)
        position += len(part) + 1
    return _Row(path, number, tuple(fields), tuple(columns))


def _agent(row: _Row, grid: Grid) -> ScenAgent:
    if len(row.fields) != len(SCEN_FIELDS):
        msg = f"the row has {len(row.fields)} field(s); an agent has {len(SCEN_FIELDS)}: {' '.join(SCEN_FIELDS)}"
        raise ScenarioFileError(msg, Location(row.path, line=row.line, column=1))
    row.whole(0)
    map_name = Path(row.fields[1].replace("\\", "/")).name
    if map_name != grid.path.name:
        msg = f"map={row.fields[1]!r} is not the scenario's map {grid.path.name!r}"
        raise row.error(1, msg)
    for index, side, actual in ((2, "width", grid.width), (3, "height", grid.height)):
        if row.whole(index) != actual:
            raise row.error(index, f"{side}={row.fields[index]} is not the map's {side}, {actual}")
    start = _cell(row, 4, grid)
    goal = _cell(row, 6, grid)
    try:
        optimal = float(row.fields[8])
    except ValueError:
        optimal = math.nan
    if not math.isfinite(optimal) or optimal < 0:
        raise row.error(8, f"optimal_length={row.fields[8]!r} must be a number >= 0")
    return ScenAgent(row.line, start, goal, optimal)


def _cell(row: _Row, index: int, grid: Grid) -> Cell:
    """The ``(row, column)`` of the ``x``, ``y`` pair at field ``index``: on the map and free."""
    x, y = row.whole(index), row.whole(index + 1)
    what = "start" if index == 4 else "goal"
    if not (x < grid.width and y < grid.height):
        msg = f"the {what} (x={x}, y={y}) is off the map ({grid.width} x {grid.height}: x < {grid.width}, y < {grid.height})"
        raise row.error(index if x >= grid.width else index + 1, msg)
    if not grid.free(y, x):
        char = grid.rows[y][x]
        where = grid.location(y, x)
        msg = f"the {what} (x={x}, y={y}) is on a blocked cell {char!r} (line {where.line}, column {where.column} of {grid.path.name})"
        raise row.error(index, msg)
    return (y, x)
