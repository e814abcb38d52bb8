"""``vehicles.csv`` and ``tasks.csv`` of a scenario (SPEC §5), read strictly and with located errors.

Conventions shared by both files:

- The first row that is neither blank nor a comment is the header; it is required even with no data.
- Column names and values are trimmed and case-insensitive; a UTF-8 byte-order mark is tolerated.
- A row whose first cell starts with ``#`` is a comment; a row whose cells are all empty is blank.
  Both are skipped: they keep their file line (error messages quote physical lines) but are not data
  rows, so task ids count data rows only (first data row = task 1).
- An unknown column is an error (a typo would otherwise be silently ignored); so is a row with more or
  fewer cells than the header.
- Every row is read and every bad cell reported, all at once (:mod:`fleetsim.load.common.collect`): fixing a
  file takes one pass, not one run per row. Reading itself is :mod:`fleetsim.load.tables.table`.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import ParamSpec, TypeVar

from fleetsim.enums import Progress, Traverse
from fleetsim.errors import ScenarioFileError
from fleetsim.layout.segment import Segment
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.tables.table import Columns, Row, read_table
from fleetsim.scenario import Task, Vehicle, VehicleType

__all__ = [
    "MAP_FILE_NAMES",
    "TASKS_FILE_NAME",
    "TASK_COLUMNS",
    "VEHICLES_FILE_NAME",
    "VEHICLE_COLUMNS",
    "VehicleRows",
    "collect_tasks",
    "collect_vehicles",
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
T = TypeVar("T")
P = ParamSpec("P")

VEHICLE_COLUMNS = Columns(("vehicle_id", "start_segment_id", "segment_orientation"), ("progress_direction", "type"))
TASK_COLUMNS = Columns(("vehicle_id", "goal_segment_id"), ("goal_progress_direction",))

_WHOLE_NUMBER = re.compile(r"[0-9]+")


def map_candidates(directory: Path) -> tuple[Path, ...]:
    """The map files of the scenario-folder convention present in ``directory`` (want exactly one)."""
    return tuple(directory / name for name in MAP_FILE_NAMES if (directory / name).is_file())


class _Cells:
    """Reads the cells of one row, each on its own: a bad cell is collected and reads as ``None``, so
    the row's other cells are still checked; ``ok`` stays true while every cell was good."""

    def __init__(self, errors: ErrorCollector) -> None:
        self.errors = errors
        self.ok = True

    def read(self, read: Callable[P, T], *args: P.args, **kwargs: P.kwargs) -> T | None:
        try:
            return read(*args, **kwargs)
        except ScenarioFileError as error:
            self.errors.add(error)
            self.ok = False
            return None


# -- values ---------------------------------------------------------------------------------------


def _whole_number(row: Row, column: str) -> int:
    value = row.get(column)
    if not _WHOLE_NUMBER.fullmatch(value):
        raise row.error(column, f"{value!r} is not a whole number >= 0")
    return int(value)


def _choice(row: Row, column: str, enum: type[E]) -> E | None:
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

    def _by_name(self, row: Row, column: str, name: str) -> Segment | None:
        ids = self.names.get(name) or tuple(sorted(self.folded.get(name.casefold(), ())))
        if len(ids) > 1:
            listed = ", ".join(map(str, ids))
            raise row.error(column, f"{name!r} names segments {listed} of {self.map_name}; use the segment id instead")
        return self.segments[ids[0]] if ids else None

    def read(self, row: Row, column: str) -> Segment:
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

    def _by_id(self, row: Row, column: str, segment_id: int) -> Segment:
        if segment_id not in self.segments:
            raise row.error(column, f"segment {segment_id} is not in {self.map_name}")
        return self.segments[segment_id]


def _segment_form(row: Row, column: str) -> None:
    """What a segment cell must be without a map to look it up in: not empty, a number after ``id:``."""
    value = row.get(column)
    if not value:
        raise row.error(column, "missing: a segment id or name is required")
    if value.startswith("id:") and not _WHOLE_NUMBER.fullmatch(value[3:].strip()):
        raise row.error(column, f"{value!r}: after 'id:' comes a whole number >= 0")


def _segment_reader(segments: Mapping[int, Segment] | None, map_name: str) -> Callable[[Row, str], Segment | None]:
    """Reads a segment cell against the map's segments, or only for its form when there is no map (it
    did not load): then the cell gives no segment, and the rows' other cells are still checked."""
    return _segment_form if segments is None else _SegmentCells(segments, map_name).read


# -- vehicles.csv ---------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class VehicleRows:
    """What :func:`collect_vehicles` read: the good rows' vehicles with their lines, and every vehicle
    id a row named (bad rows included), which tasks are checked against; ``None`` when the file could
    not be read as a table (then nothing can be said about which vehicles exist)."""

    located: tuple[tuple[Vehicle, int], ...]
    ids: frozenset[int] | None


def _vehicle_type(row: Row, types_by_key: Mapping[str, VehicleType], default_type: VehicleType | None) -> VehicleType:
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
        msg = (
            f"vehicle type {name!r} is not defined{did_you_mean(name, names)} (known: {', '.join(names)}); "
            "a folder's vehicles.csv only names types: the suite that uses the folder defines them under "
            "vehicle_types"
        )
        raise row.error("type", msg)
    return types_by_key[name.casefold()]


def _orientation(row: Row) -> Traverse:
    traverse = _choice(row, "segment_orientation", Traverse)
    if traverse is None:
        raise row.error("segment_orientation", "missing: must be 'forward' or 'backward'")
    return traverse


def _check_way(row: Row, segment: Segment, traverse: Traverse) -> None:
    if not segment.allows(traverse):
        msg = (
            f"wrong-way start: segment {segment.id} is one-way {segment.direction.value!r}, "
            f"so orientation {traverse.value!r} drives against it"
        )
        raise row.error("segment_orientation", msg)


def collect_vehicles(
    path: Path,
    segments: Mapping[int, Segment] | None,
    vehicle_types: Mapping[str, VehicleType],
    default_type: VehicleType | None,
    errors: ErrorCollector,
    *,
    map_name: str = "the map",
) -> VehicleRows:
    """Every row of ``vehicles.csv`` checked, each bad cell's error added to ``errors`` (see
    :func:`read_vehicles`); the vehicles of the rows without one. Without ``segments`` (the map did not
    load) the rows are checked for all that needs no map, and give no vehicles."""
    rows = read_table(path, VEHICLE_COLUMNS, errors)
    if rows is None:
        return VehicleRows((), None)
    types_by_key = {name.casefold(): vehicle_type for name, vehicle_type in vehicle_types.items()}
    read_segment = _segment_reader(segments, map_name)
    lines: dict[int, int] = {}  # vehicle id → the line of the first row naming it
    located = []
    for row in rows:
        cells = _Cells(errors)
        vehicle_id = cells.read(_whole_number, row, "vehicle_id")
        if vehicle_id is not None and vehicle_id in lines:
            cells.read(_already_used, row, vehicle_id, lines[vehicle_id])
        elif vehicle_id is not None:
            lines[vehicle_id] = row.line
        segment = cells.read(read_segment, row, "start_segment_id")
        traverse = cells.read(_orientation, row)
        if segment is not None and traverse is not None:
            cells.read(_check_way, row, segment, traverse)
        progress = cells.read(_choice, row, "progress_direction", Progress)
        vehicle_type = cells.read(_vehicle_type, row, types_by_key, default_type)
        if (
            cells.ok
            and vehicle_id is not None
            and segment is not None
            and traverse is not None
            and vehicle_type is not None
        ):
            vehicle = Vehicle(vehicle_id, segment.id, traverse, progress or Progress.FORWARD, vehicle_type)
            located.append((vehicle, row.line))
    return VehicleRows(tuple(located), frozenset(lines))


def _already_used(row: Row, vehicle_id: int, first_line: int) -> None:
    raise row.error("vehicle_id", f"vehicle id {vehicle_id} is already used on line {first_line}")


def read_vehicles_with_lines(
    path: Path | str,
    segments: Mapping[int, Segment],
    vehicle_types: Mapping[str, VehicleType],
    default_type: VehicleType | None,
    *,
    map_name: str = "the map",
) -> tuple[tuple[Vehicle, int], ...]:
    """Like :func:`read_vehicles`, each vehicle paired with its line in the file (for later errors)."""
    errors = ErrorCollector()
    rows = collect_vehicles(Path(path), segments, vehicle_types, default_type, errors, map_name=map_name)
    errors.raise_if_any()
    return rows.located


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

    Every row is checked: one bad cell raises its [`ScenarioFileError`][fleetsim.errors.ScenarioFileError],
    several (in one row or many) raise one [`LoadErrors`][fleetsim.errors.LoadErrors] listing each, at
    most 50 of them. A broken header stops the file (rows mean nothing without it), but all of the
    header's own problems are reported.
    """
    rows = read_vehicles_with_lines(path, segments, vehicle_types, default_type, map_name=map_name)
    return tuple(vehicle for vehicle, _ in rows)


# -- tasks.csv ------------------------------------------------------------------------------------


def collect_tasks(
    path: Path,
    segments: Mapping[int, Segment] | None,
    vehicle_ids: frozenset[int] | None,
    errors: ErrorCollector,
    *,
    map_name: str = "the map",
    vehicles_name: str = VEHICLES_FILE_NAME,
) -> tuple[tuple[Task, int], ...]:
    """Every row of ``tasks.csv`` checked, each bad cell's error added to ``errors`` (see
    :func:`read_tasks`); the tasks of the rows without one. ``vehicle_ids`` are the ids a task may
    name; ``None`` (``vehicles.csv`` unreadable) skips that check rather than flag every row. Without
    ``segments`` (the map did not load) the rows are checked for all that needs no map, and give no tasks."""
    rows = read_table(path, TASK_COLUMNS, errors)
    if rows is None:
        return ()
    read_segment = _segment_reader(segments, map_name)
    tasks = []
    for number, row in enumerate(rows, start=1):
        cells = _Cells(errors)
        vehicle_id = cells.read(_whole_number, row, "vehicle_id")
        if vehicle_id is not None and vehicle_ids is not None and vehicle_id not in vehicle_ids:
            cells.read(_unknown_vehicle, row, vehicle_id, vehicles_name)
        segment = cells.read(read_segment, row, "goal_segment_id")
        progress = cells.read(_choice, row, "goal_progress_direction", Progress)
        if cells.ok and vehicle_id is not None and segment is not None:
            tasks.append((Task(number, vehicle_id, segment.id, progress), row.line))
    return tuple(tasks)


def _unknown_vehicle(row: Row, vehicle_id: int, vehicles_name: str) -> None:
    raise row.error("vehicle_id", f"vehicle {vehicle_id} is not in {vehicles_name}")


def read_tasks_with_lines(
    path: Path | str,
    segments: Mapping[int, Segment],
    vehicles: Iterable[Vehicle] | Mapping[int, Vehicle],
    *,
    map_name: str = "the map",
    vehicles_name: str = VEHICLES_FILE_NAME,
) -> tuple[tuple[Task, int], ...]:
    """Like :func:`read_tasks`, each task paired with its line in the file (for later errors)."""
    known = frozenset(vehicles) if isinstance(vehicles, Mapping) else frozenset(v.id for v in vehicles)
    errors = ErrorCollector()
    tasks = collect_tasks(Path(path), segments, known, errors, map_name=map_name, vehicles_name=vehicles_name)
    errors.raise_if_any()
    return tasks


def read_tasks(
    path: Path | str,
    segments: Mapping[int, Segment],
    vehicles: Iterable[Vehicle] | Mapping[int, Vehicle],
    *,
    map_name: str = "the map",
    vehicles_name: str = VEHICLES_FILE_NAME,
) -> tuple[Task, ...]:
    """The tasks of ``tasks.csv`` in file order; task id = 1-based data-row number.

    Every row is checked, as [`read_vehicles`][fleetsim.load.read_vehicles] does: one error is raised as
    itself, several as one [`LoadErrors`][fleetsim.errors.LoadErrors].
    """
    rows = read_tasks_with_lines(path, segments, vehicles, map_name=map_name, vehicles_name=vehicles_name)
    return tuple(task for task, _ in rows)
