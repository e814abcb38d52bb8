"""A suite entry that runs a MovingAI scenario file: ``scen: FILE.scen`` (with ``agents: N``, the file's
first N agents; default all of them) instead of ``vehicles``/``tasks``.

Its map is the entry's ``map`` when it names one, else the map the ``.scen`` file's first agent names,
looked up relative to the ``.scen`` file's folder as written, then by its file name alone (MovingAI's
files name their map with a folder the downloads do not keep).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fleetsim.errors import Location, ScenarioFileError
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.common.yaml_source import Locate
from fleetsim.load.movingai.agents import agent_vehicles, movingai_vehicle_type
from fleetsim.load.movingai.grid import read_grid
from fleetsim.load.movingai.reader import cell_size_of
from fleetsim.load.movingai.scen import read_scen, scen_map_name
from fleetsim.load.suites.schema import raise_suite_errors, suite_error
from fleetsim.scenario import Task, Vehicle, VehicleType

__all__ = ["ScenSetup", "scen_agents", "scen_files"]


@dataclass(frozen=True, slots=True)
class ScenSetup:
    """A suite entry's MovingAI scenario: the ``.scen`` file, how many of its agents (``None``: all) and
    where the entry's ``agents`` key is (for an error when the file has fewer)."""

    path: Path
    agents: int | None = None
    where: Location | None = None


def scen_files(
    root: Path, entry: Mapping[str, Any], locate: Locate, where: tuple[Any, ...]
) -> tuple[tuple[Path, Path, Path], ScenSetup]:
    """The map, vehicles and tasks paths of a ``scen`` entry (the ``.scen`` file gives both vehicles and
    tasks), and its setup; every problem is raised (several as one SuiteErrors)."""
    errors = ErrorCollector()
    scen = root / entry["scen"]
    map_path = root
    if not scen.is_file():
        errors.add(suite_error(f"no such file: {str(scen)!r}", (*where, "scen"), locate((*where, "scen"))))
    elif "map" in entry:
        map_path = root / entry["map"]
        if not map_path.is_file():
            errors.add(suite_error(f"no such file: {str(map_path)!r}", (*where, "map"), locate((*where, "map"))))
    else:
        with errors.collecting():
            map_path = _named_map(scen)
    raise_suite_errors(errors)
    agents = entry.get("agents")
    setup = ScenSetup(scen, agents, locate((*where, "agents")) if agents is not None else None)
    return (map_path, scen, scen), setup


def _named_map(scen: Path) -> Path:
    named = scen_map_name(scen)
    if named is None:
        msg = "the scenario file names no map (it has no agents); name one with 'map' in the suite entry"
        raise ScenarioFileError(msg, Location(scen))
    name, where = named
    relative = Path(name.replace("\\", "/"))
    for candidate in (scen.parent / relative, scen.parent / relative.name):
        if candidate.is_file():
            return candidate
    msg = (
        f"map {name!r} is not beside the scenario file (looked for {str(scen.parent / relative)!r} and "
        f"{str(scen.parent / relative.name)!r}); put it there, or name it with 'map' in the suite entry"
    )
    raise ScenarioFileError(msg, where)


def scen_agents(
    setup: ScenSetup,
    site: SiteMap,
    options: MapOptions,
    vehicle_type: VehicleType | None,
) -> tuple[tuple[tuple[Vehicle, int], ...], tuple[tuple[Task, int], ...], VehicleType]:
    """The vehicles and tasks of the entry's first ``agents`` agents on ``site`` (its MovingAI map), each
    with its line in the ``.scen`` file, and the vehicle type they have: ``vehicle_type`` (the scenario's
    default type, when the suite declares vehicle types), else the MovingAI type for the map's cell size."""
    if site.format != "movingai":
        msg = f"a MovingAI scenario file runs on a MovingAI grid map (.map), not on {site.path.name!r}"
        raise ScenarioFileError(msg, Location(setup.path))
    grid = read_grid(site.path)
    agents = read_scen(setup.path, grid)
    if setup.agents is not None:
        if setup.agents > len(agents):
            msg = f"agents={setup.agents}, but {setup.path.name} has {len(agents)} agent(s)"
            raise ScenarioFileError(msg, setup.where or Location(setup.path))
        agents = agents[: setup.agents]
    kind = vehicle_type or movingai_vehicle_type(cell_size_of(options, site.path))
    vehicles, tasks = agent_vehicles(agents, grid, site.segments, kind, setup.path)
    return vehicles, tasks, kind
