"""``vehicles.csv`` and ``tasks.csv`` of a scenario (SPEC §5), read strictly and with located errors.

Conventions shared by both files:

- The first row that is neither blank nor a comment is the header; it is required even with no data.
- Column names and values are trimmed and case-insensitive; a UTF-8 byte-order mark is tolerated.
- A row whose first cell starts with ``#`` is a comment; a row whose cells are all empty is blank.
  Both are skipped: they keep their file line (error messages quote physical lines) but are not data
  rows, so task ids count data rows only (first data row = task 1).
- An unknown column is an error (a typo would otherwise be silently ignored); so is a row with more or
  fewer cells than the header.
"""

from __future__ import annotations

import csv
import difflib
import io
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import TypeVar

from fleetsim.enums import Progress, Traverse
from fleetsim.errors import Location, ScenarioFileError
from fleetsim.layout.segment import Segment
from fleetsim.load.text import read_text_file
from fleetsim.scenario import Task, Vehicle, VehicleType

__all__ = [
    "MAP_FILE_NAMES",
    "TASKS_FILE_NAME",
    "TASK_COLUMNS",
    "VEHICLES_FILE_NAME",
    "VEHICLE_COLUMNS",
    "did_you_mean",
    "map_candidates",
    "read_tasks",
    "read_tasks_with_lines",
    "read_vehicles",
    "read_vehicles_with_lines",
]

MAP_FILE_NAMES = ("map.json", "map.tmj", "map.tmx", "map.lif.json", "map.building.yaml")
VEHICLES_FILE_NAME = "vehicles.csv"
TASKS_FILE_NAME = "tasks.csv"

E = TypeVar("E", bound=Enum)


@dataclass(frozen=True, slots=True)
class _Columns:
    required: tuple[str, ...]
    optional: tuple[str, ...]

    @property
    def all(self) -> tuple[str, ...]:
        return self.required + self.optional

    @property
    def header(self) -> str:
        """The header as documented, optional columns in brackets."""
        return ",".join(self.required) + "".join(f"[,{name}]" for name in self.optional)


VEHICLE_COLUMNS = _Columns(("vehicle_id", "start_segment_id", "segment_orientation"), ("progress_direction", "type"))
TASK_COLUMNS = _Columns(("vehicle_id", "goal_segment_id"), ("goal_progress_direction",))

_WHOLE_NUMBER = re.compile(r"[0-9]+")


@dataclass(frozen=True, slots=True)
class _Row:
    path: Path
    line: int
    cells: Mapping[str, str]  # column → trimmed value; absent optional columns read as ""

    def get(self, column: str) -> str:
        return self.cells.get(column, "")

    def error(self, column: str, problem: str) -> ScenarioFileError:
        return ScenarioFileError(problem, Location(self.path, line=self.line, field=column))


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """``"; did you mean 'x'?"`` for the closest choice, or ``""`` when nothing is close."""
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f"; did you mean {close[0]!r}?" if close else ""


def map_candidates(directory: Path) -> tuple[Path, ...]:
    """The map files of the scenario-folder convention present in ``directory`` (want exactly one)."""
    return tuple(directory / name for name in MAP_FILE_NAMES if (directory / name).is_file())


# -- reading a table ------------------------------------------------------------------------------


def _records(path: Path) -> list[tuple[int, list[str]]]:
    """(first file line, trimmed cells) of every row that is neither blank nor a comment."""
    text = read_text_file(path, ScenarioFileError)
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    records: list[tuple[int, list[str]]] = []
    line = 1
    try:
        for cells in reader:
            trimmed = [cell.strip() for cell in cells]
            if any(trimmed) and not trimmed[0].startswith("#"):
                records.append((line, trimmed))
            line = reader.line_num + 1  # a quoted cell may span lines: the next row starts after it
    except csv.Error as exc:
        # Point at the row that started it: an unclosed quote only fails at the end of the file.
        raise ScenarioFileError(f"malformed CSV row: {exc}", Location(path, line=line)) from None
    return records


def _header(path: Path, line: int, cells: list[str], columns: _Columns) -> tuple[str, ...]:
    if cells[0].isdigit():
        # A data row where the header belongs: say that, not "unknown column '1'".
        msg = f"missing header: the first row must be {columns.header}, found data {','.join(cells)!r}"
        raise ScenarioFileError(msg, Location(path, line=line))
    names = tuple(cell.lower() for cell in cells)
    for index, name in enumerate(names):
        where = Location(path, line=line, field=name or None)
        if not name:
            msg = f"header column {index + 1} has no name (a stray comma?); the header is {columns.header}"
            raise ScenarioFileError(msg, where)
        if name not in columns.all:
            msg = f"unknown column {name!r}{did_you_mean(name, columns.all)} (the header is {columns.header})"
            raise ScenarioFileError(msg, where)
        if name in names[:index]:
            raise ScenarioFileError(f"column {name!r} appears twice in the header", where)
    for name in columns.required:
        if name not in names:
            msg = f"missing required column {name!r} (the header is {columns.header})"
            raise ScenarioFileError(msg, Location(path, line=line, field=name))
    return names


def _read_rows(path: Path, columns: _Columns) -> tuple[_Row, ...]:
    records = _records(path)
    if not records:
        msg = f"no header: the first row must be {columns.header} (required even with no data rows)"
        raise ScenarioFileError(msg, Location(path, line=1))
    header_line, header_cells = records[0]
    names = _header(path, header_line, header_cells, columns)
    rows = []
    for line, cells in records[1:]:
        if len(cells) != len(names):
            msg = f"row has {len(cells)} values but the header has {len(names)} columns: {cells!r}"
            raise ScenarioFileError(msg, Location(path, line=line))
        rows.append(_Row(path, line, dict(zip(names, cells, strict=True))))
    return tuple(rows)


# -- values ---------------------------------------------------------------------------------------


def _whole_number(row: _Row, column: str) -> int:
    value = row.get(column)
    if not _WHOLE_NUMBER.fullmatch(value):
        raise row.error(column, f"{value!r} is not a whole number >= 0")
    return int(value)


def _choice(row: _Row, column: str, enum: type[E]) -> E | None:
    """The enum member a cell names, or ``None`` for an empty cell."""
    value = row.get(column).lower()
    if not value:
        return None
    try:
        return enum(value)
    except ValueError:
        allowed = " or ".join(repr(member.value) for member in enum)
        raise row.error(column, f"{value!r} is not {allowed}") from None


def _names(segments: Mapping[int, Segment]) -> dict[str, tuple[int, ...]]:
    """Every segment name → the ids of the segments that carry it (more than one: ambiguous)."""
    holders: dict[str, list[int]] = {}
    for segment in segments.values():
        for name in segment.names:
            ids = holders.setdefault(name, [])
            if segment.id not in ids:
                ids.append(segment.id)
    return {name: tuple(sorted(ids)) for name, ids in holders.items()}


class _SegmentCells:
    """Reads a segment cell: a segment's id, or one of its names (a LIF edge id, an RMF lane, a Tiled name).

    ``id:N`` and ``name:TEXT`` force one reading when a number is both an id and another segment's name.
    """

    def __init__(self, segments: Mapping[int, Segment], map_name: str) -> None:
        self.segments = segments
        self.map_name = map_name
        self.names = _names(segments)
        self.folded: dict[str, set[int]] = {}
        for name, ids in self.names.items():
            self.folded.setdefault(name.casefold(), set()).update(ids)

    def _by_name(self, row: _Row, column: str, name: str) -> Segment | None:
        ids = self.names.get(name) or tuple(sorted(self.folded.get(name.casefold(), ())))
        if len(ids) > 1:
            listed = ", ".join(map(str, ids))
            raise row.error(column, f"{name!r} names segments {listed} of {self.map_name}; use the segment id instead")
        return self.segments[ids[0]] if ids else None

    def read(self, row: _Row, column: str) -> Segment:
        value = row.get(column)
        if value.startswith("id:"):
            digits = value[3:].strip()
            if not _WHOLE_NUMBER.fullmatch(digits):
                raise row.error(column, f"{value!r}: after 'id:' comes a whole number >= 0")
            return self._by_id(row, column, int(digits))
        if value.startswith("name:"):
            found = self._by_name(row, column, value[5:].strip())
            if found is None:
                raise row.error(column, f"no segment of {self.map_name} is named {value[5:].strip()!r}")
            return found
        if not self.names:  # a map without names: the cell must be an id
            return self._by_id(row, column, _whole_number(row, column))
        if not value:
            raise row.error(column, "missing: a segment id or name is required")
        named = self._by_name(row, column, value)
        if _WHOLE_NUMBER.fullmatch(value):
            number = int(value)
            if named is not None and named.id != number and number in self.segments:
                msg = (
                    f"{value!r} is both the id of segment {number} and the name of segment {named.id}; "
                    f"write 'id:{number}' or 'name:{value}'"
                )
                raise row.error(column, msg)
            if number in self.segments or named is None:
                return self._by_id(row, column, number)
        if named is None:
            hint = did_you_mean(value, self.names)
            raise row.error(column, f"segment {value!r} is not in {self.map_name} (neither an id nor a name){hint}")
        return named

    def _by_id(self, row: _Row, column: str, segment_id: int) -> Segment:
        if segment_id not in self.segments:
            raise row.error(column, f"segment {segment_id} is not in {self.map_name}")
        return self.segments[segment_id]


# -- vehicles.csv ---------------------------------------------------------------------------------


def _vehicle_type(row: _Row, types_by_key: Mapping[str, VehicleType], default_type: VehicleType | None) -> VehicleType:
    name = row.get("type")
    if not name:
        if default_type is None:
            known = ", ".join(t.name for t in types_by_key.values())
            msg = (
                f"this row names no vehicle type and no default type is set (types: {known}); "
                "fill in the 'type' column or set vehicle_type in the suite's defaults"
            )
            raise row.error("type", msg)
        return default_type
    if name.casefold() not in types_by_key:
        names = [t.name for t in types_by_key.values()]
        msg = f"vehicle type {name!r} is not defined{did_you_mean(name, names)} (known: {', '.join(names)})"
        raise row.error("type", msg)
    return types_by_key[name.casefold()]


def _vehicle(
    row: _Row,
    segments: _SegmentCells,
    types_by_key: Mapping[str, VehicleType],
    default_type: VehicleType | None,
) -> Vehicle:
    vehicle_id = _whole_number(row, "vehicle_id")
    segment = segments.read(row, "start_segment_id")
    traverse = _choice(row, "segment_orientation", Traverse)
    if traverse is None:
        raise row.error("segment_orientation", "missing: must be 'forward' or 'backward'")
    if not segment.allows(traverse):
        msg = (
            f"wrong-way start: segment {segment.id} is one-way {segment.direction.value!r}, "
            f"so orientation {traverse.value!r} drives against it"
        )
        raise row.error("segment_orientation", msg)
    progress = _choice(row, "progress_direction", Progress) or Progress.FORWARD
    vehicle_type = _vehicle_type(row, types_by_key, default_type)
    return Vehicle(vehicle_id, segment.id, traverse, progress, vehicle_type)


def read_vehicles_with_lines(
    path: Path | str,
    segments: Mapping[int, Segment],
    vehicle_types: Mapping[str, VehicleType],
    default_type: VehicleType | None,
    *,
    map_name: str = "the map",
) -> tuple[tuple[Vehicle, int], ...]:
    """Like :func:`read_vehicles`, each vehicle paired with its line in the file (for later errors)."""
    path = Path(path)
    types_by_key = {name.casefold(): vehicle_type for name, vehicle_type in vehicle_types.items()}
    lines: dict[int, int] = {}
    result = []
    cells = _SegmentCells(segments, map_name)
    for row in _read_rows(path, VEHICLE_COLUMNS):
        vehicle = _vehicle(row, cells, types_by_key, default_type)
        if vehicle.id in lines:
            msg = f"vehicle id {vehicle.id} is already used on line {lines[vehicle.id]}"
            raise row.error("vehicle_id", msg)
        lines[vehicle.id] = row.line
        result.append((vehicle, row.line))
    return tuple(result)


def read_vehicles(
    path: Path | str,
    segments: Mapping[int, Segment],
    vehicle_types: Mapping[str, VehicleType],
    default_type: VehicleType | None,
    *,
    map_name: str = "the map",
) -> tuple[Vehicle, ...]:
    """The vehicles of ``vehicles.csv`` in file order.

    ``default_type`` is the type of rows without one; ``None`` (a suite with several types and no
    ``vehicle_type`` default) makes such rows an error. ``map_name`` names the map in messages.
    """
    rows = read_vehicles_with_lines(path, segments, vehicle_types, default_type, map_name=map_name)
    return tuple(vehicle for vehicle, _ in rows)


# -- tasks.csv ------------------------------------------------------------------------------------


def read_tasks_with_lines(
    path: Path | str,
    segments: Mapping[int, Segment],
    vehicles: Iterable[Vehicle] | Mapping[int, Vehicle],
    *,
    map_name: str = "the map",
    vehicles_name: str = VEHICLES_FILE_NAME,
) -> tuple[tuple[Task, int], ...]:
    """Like :func:`read_tasks`, each task paired with its line in the file (for later errors)."""
    path = Path(path)
    known = set(vehicles) if isinstance(vehicles, Mapping) else {vehicle.id for vehicle in vehicles}
    tasks = []
    cells = _SegmentCells(segments, map_name)
    for number, row in enumerate(_read_rows(path, TASK_COLUMNS), start=1):
        vehicle_id = _whole_number(row, "vehicle_id")
        if vehicle_id not in known:
            raise row.error("vehicle_id", f"vehicle {vehicle_id} is not in {vehicles_name}")
        segment = cells.read(row, "goal_segment_id")
        progress = _choice(row, "goal_progress_direction", Progress)
        tasks.append((Task(number, vehicle_id, segment.id, progress), row.line))
    return tuple(tasks)


def read_tasks(
    path: Path | str,
    segments: Mapping[int, Segment],
    vehicles: Iterable[Vehicle] | Mapping[int, Vehicle],
    *,
    map_name: str = "the map",
    vehicles_name: str = VEHICLES_FILE_NAME,
) -> tuple[Task, ...]:
    """The tasks of ``tasks.csv`` in file order; task id = 1-based data-row number."""
    rows = read_tasks_with_lines(path, segments, vehicles, map_name=map_name, vehicles_name=vehicles_name)
    return tuple(task for task, _ in rows)
