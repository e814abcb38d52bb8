"""The CSV files of a suite entry whose files cannot all be found, checked as far as they can be.

A suite entry whose ``dir`` (or ``map``) is missing cannot be loaded, but the ``vehicles.csv`` and
``tasks.csv`` it names may exist: their own mistakes (header, row widths, ids, words, vehicle types,
which vehicles exist) are reported with the missing folder, so one pass shows every mistake. What needs
the map (a segment exists, an orientation is allowed) waits until the map can be found.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.tables.scenario_files import (
    TASKS_FILE_NAME,
    VEHICLE_COLUMNS,
    VEHICLES_FILE_NAME,
    VehicleRows,
    collect_tasks,
    collect_vehicles,
)
from fleetsim.load.tables.table import check_table
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE

__all__ = ["check_entry_tables"]


def check_entry_tables(
    root: Path,
    entry: Mapping[str, Any],
    default_type: str | None,
    type_names: Collection[str] | None,
    errors: ErrorCollector,
) -> None:
    """Add the errors of the entry's CSV files that exist to ``errors``, checked without a map.

    ``root`` is the suite's folder; ``default_type`` the entry's ``vehicle_type`` setting;
    ``type_names`` the suite's vehicle types (``None`` when they could not be read: then
    ``vehicles.csv`` is checked for its structure only).
    """
    vehicles = _existing(root, entry, "vehicles", VEHICLES_FILE_NAME)
    tasks = _existing(root, entry, "tasks", TASKS_FILE_NAME)
    rows = VehicleRows((), None)
    if vehicles is not None and type_names is None:
        check_table(vehicles, VEHICLE_COLUMNS, errors)
    elif vehicles is not None and type_names is not None:
        # Only the names matter here: without a map no vehicle is made, so each type stands in by name.
        # Rows naming no type are not judged without a default: it may be the suite's mistake, reported.
        types = {name: replace(DEFAULT_VEHICLE_TYPE, name=name) for name in type_names}
        default = types.get(default_type or "", DEFAULT_VEHICLE_TYPE)
        rows = collect_vehicles(vehicles, None, types, default, errors)
    if tasks is not None:
        vehicles_name = vehicles.name if vehicles is not None else VEHICLES_FILE_NAME
        collect_tasks(tasks, None, rows.ids, errors, vehicles_name=vehicles_name)


def _existing(root: Path, entry: Mapping[str, Any], key: str, name: str) -> Path | None:
    """The file the entry names under ``key``, else the one its ``dir`` holds, when it exists."""
    if isinstance(entry.get(key), str):
        path = root / entry[key]
    elif isinstance(entry.get("dir"), str):
        path = root / entry["dir"] / name
    else:
        return None
    return path if path.is_file() else None
