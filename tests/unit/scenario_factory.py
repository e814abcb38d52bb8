"""Small scenarios written as ordinary scenario folders, for tests that need a loaded Scenario."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from fleetsim.enums import TurnCapability
from fleetsim.layout import Segment
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.load.tiled.writer import write_map
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, ScenarioSettings, VehicleType

VEHICLES_HEADER = "vehicle_id,start_segment_id,segment_orientation,progress_direction,type\n"
TASKS_HEADER = "vehicle_id,goal_segment_id,goal_progress_direction\n"

AGV = replace(DEFAULT_VEHICLE_TYPE, name="agv", turn_capability=TurnCapability.IN_PLACE)
TUGGER = replace(DEFAULT_VEHICLE_TYPE, name="tugger", turn_capability=TurnCapability.CURVE)


def make_scenario(
    folder: Path,
    segments: tuple[Segment, ...],
    vehicles: str,
    tasks: str = "",
    *,
    types: tuple[VehicleType, ...] = (AGV, TUGGER),
    **settings: object,
) -> Scenario:
    """Write ``segments`` and the CSV rows (without headers) into ``folder`` and load it."""
    folder.mkdir(parents=True, exist_ok=True)
    write_map(folder / "map.json", segments)
    (folder / "vehicles.csv").write_text(VEHICLES_HEADER + vehicles, encoding="utf-8")
    (folder / "tasks.csv").write_text(TASKS_HEADER + tasks, encoding="utf-8")
    options = {"vehicle_type": types[0].name, **settings}
    return load_scenario_dir(
        folder,
        vehicle_types={t.name: t for t in types},
        settings=ScenarioSettings(**options),  # type: ignore[arg-type]
    )
