"""Saving a scenario as an ordinary scenario folder, and loading it back with the right vehicle types.

A counterexample is only worth keeping if the folder reproduces it exactly: the map is JSON (full float
precision; generated waypoints survive the pixel transform exactly), every CSV row states what the
loader would otherwise default, and task ids are the row numbers the loader assigns.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable
from pathlib import Path

from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.load.tables.scenario_files import TASK_COLUMNS, TASKS_FILE_NAME, VEHICLE_COLUMNS, VEHICLES_FILE_NAME
from fleetsim.load.tiled.writer import write_map
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, ScenarioSettings, VehicleType
from fleetsim.strategies._scenarios import GenerationSpec

__all__ = ["MAP_FILE_NAME", "load_saved", "save_scenario"]

MAP_FILE_NAME = "map.json"


def _csv(rows: Iterable[Iterable[object]]) -> str:
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows(rows)
    return out.getvalue()


def save_scenario(scenario: Scenario, folder: Path) -> Path:
    """Write ``folder/map.json``, ``vehicles.csv`` and ``tasks.csv`` for ``scenario``; returns ``folder``.

    ``vehicles.csv`` gets a ``type`` column unless the scenario knows only the default type: with
    several types a row without one would need a suite default to load at all. Settings, expectations and the
    types themselves belong in a suite entry, not in the folder.
    """
    ids = [task.id for task in scenario.tasks]
    if ids != list(range(1, len(ids) + 1)):
        msg = f"task ids={ids!r} must be 1, 2, ... in order: the loader numbers tasks by their row"
        raise ValueError(msg)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    write_map(folder / MAP_FILE_NAME, scenario.layout.segments.values())
    only_default = dict(scenario.vehicle_types) == {DEFAULT_VEHICLE_TYPE.name: DEFAULT_VEHICLE_TYPE}
    typed = not only_default or any(vehicle.type != DEFAULT_VEHICLE_TYPE for vehicle in scenario.vehicles)
    header = VEHICLE_COLUMNS.all if typed else VEHICLE_COLUMNS.all[:-1]
    vehicles = [
        (v.id, v.start_segment, v.traverse.value, v.progress.value, *((v.type.name,) if typed else ()))
        for v in scenario.vehicles
    ]
    (folder / VEHICLES_FILE_NAME).write_text(_csv([header, *vehicles]), encoding="utf-8")
    tasks = [
        (t.vehicle_id, t.goal_segment, t.goal_progress.value if t.goal_progress is not None else "")
        for t in scenario.tasks
    ]
    (folder / TASKS_FILE_NAME).write_text(_csv([TASK_COLUMNS.all, *tasks]), encoding="utf-8")
    return folder


def load_saved(
    folder: Path,
    spec_or_types: GenerationSpec | Iterable[VehicleType] = (),
    *,
    settings: ScenarioSettings | None = None,
) -> Scenario:
    """Load a folder written by :func:`save_scenario` with the types (and settings) it was generated with.

    Given a :class:`GenerationSpec`, its types and settings; given types, those (``()``: the default
    type) and ``settings`` (default: the defaults). The result equals the saved scenario except for its
    name (the folder's) and file paths.
    """
    if isinstance(spec_or_types, GenerationSpec):
        types = spec_or_types.type_map
        settings = spec_or_types.settings if settings is None else settings
    else:
        types = GenerationSpec(vehicle_types=tuple(spec_or_types)).type_map
    return load_scenario_dir(folder, vehicle_types=types, settings=settings)
