"""A suite entry that runs a League of Robot Runners problem: ``lorr: PROBLEM.json``, with ``horizon`` (the
timesteps to simulate, one second each; default 5000, the Start-Kit's), ``agents`` (robots to run
instead of the problem's ``teamSize``) and ``task_rounds`` (the task file this many times over; default 1).

The problem file is read when the scenario loads (its mistakes are the scenario's, not the suite's); the
suite only looks into it for the map it names, so that ``fleetsim inspect`` and friends find the map.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from fleetsim.errors import Location, ScenarioFileError
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.common.yaml_source import Locate
from fleetsim.load.lorr.fleet import LorrFleet, lorr_fleet
from fleetsim.load.lorr.problem import LorrProblem, read_problem
from fleetsim.load.movingai.grid import read_grid
from fleetsim.load.movingai.reader import cell_size_of
from fleetsim.load.suites.schema import raise_suite_errors, suite_error
from fleetsim.orders import Shift
from fleetsim.scenario import Scenario, ScenarioSettings, VehicleType

__all__ = [
    "DEFAULT_DISPATCHER",
    "DEFAULT_HORIZON",
    "LorrEntry",
    "apply_lorr",
    "is_lorr_problem",
    "lorr_files",
    "lorr_problem_fleet",
    "lorr_settings",
    "problem_map",
    "problem_name",
]

DEFAULT_HORIZON = 5000  # timesteps: the Start-Kit's default simulationTime
DEFAULT_DISPATCHER = "fleetsim.dispatchers:NearestVehicleDispatcher"
_PROBLEM_KEYS = {"mapFile", "agentFile", "robotFile", "taskFile", "teamSize"}


@dataclass(frozen=True, slots=True)
class LorrEntry:
    """A suite entry's League problem: the file, the horizon in timesteps, how many robots (``None``: the
    problem's ``teamSize``), where the entry's ``agents`` is (for an error when the file has fewer) and
    how many times over its tasks are revealed (the Start-Kit starts over when they run out)."""

    path: Path
    horizon: int = DEFAULT_HORIZON
    agents: int | None = None
    where: Location | None = None
    task_rounds: int = 1


def lorr_files(
    root: Path, entry: Mapping[str, Any], locate: Locate, where: tuple[Any, ...]
) -> tuple[tuple[Path, Path, Path], LorrEntry]:
    """The map, vehicles and tasks paths of a ``lorr`` entry (the problem file for all three when the map
    it names cannot be found yet: the scenario's load says why), and its setup."""
    errors = ErrorCollector()
    problem = root / entry["lorr"]
    if not problem.is_file():
        errors.add(suite_error(f"no such file: {str(problem)!r}", (*where, "lorr"), locate((*where, "lorr"))))
    raise_suite_errors(errors)
    agents = entry.get("agents")
    setup = LorrEntry(
        problem,
        entry.get("horizon", DEFAULT_HORIZON),
        agents,
        locate((*where, "agents")) if agents is not None else None,
        entry.get("task_rounds", 1),
    )
    return (problem_map(problem), problem, problem), setup


def is_lorr_problem(path: Path) -> bool:
    """Whether ``path`` is a League problem file rather than a suite: a ``.json`` file holding an object
    with a key of a problem (``teamSize``, ``mapFile``, ...) and none of a suite (``fleetsim``, ``scenarios``)."""
    if path.suffix.lower() != ".json" or not path.is_file():
        return False
    try:
        raw = json.loads(path.read_text(encoding="utf-8-sig"))
    except (OSError, ValueError):
        return False
    return isinstance(raw, dict) and not {"fleetsim", "scenarios"} & raw.keys() and bool(_PROBLEM_KEYS & raw.keys())


def problem_name(path: Path) -> str:
    """A scenario name for a problem file run on its own: its stem, in the characters names may hold."""
    name = re.sub(r"[^A-Za-z0-9_.-]+", "-", path.stem).strip("-.")
    return name or "lorr"


def problem_map(problem: Path) -> Path:
    """The map a problem file names when it can be found (else the problem file: its load says why)."""
    try:
        raw = json.loads(problem.read_text(encoding="utf-8-sig"))
    except (OSError, ValueError):
        return problem
    name = raw.get("mapFile") if isinstance(raw, dict) else None
    if isinstance(name, str) and (problem.parent / name).is_file():
        return problem.parent / name
    return problem


def lorr_problem_fleet(
    entry: LorrEntry, options: MapOptions, given_type: VehicleType | None
) -> tuple[LorrProblem, SiteMap, LorrFleet]:
    """Read the entry's problem, its map (a MovingAI grid, as a lane graph) and its fleet and orders."""
    from fleetsim.load.movingai.reader import load_movingai

    problem = read_problem(entry.path)
    if problem.map_path.suffix.lower() != ".map":
        msg = f"mapFile {problem.map_path.name!r} must be a MovingAI grid map (.map)"
        raise ScenarioFileError(msg, problem.places.at("mapFile"))
    site = load_movingai(problem.map_path, options)
    grid = read_grid(problem.map_path)
    fleet = lorr_fleet(
        problem,
        grid,
        site.segments,
        cell_size_of(options, problem.map_path),
        agents=entry.agents,
        agents_where=entry.where,
        horizon=entry.horizon,
        given_type=given_type,
        rounds=entry.task_rounds,
    )
    return problem, site, fleet


def lorr_settings(settings: ScenarioSettings, horizon: int) -> ScenarioSettings:
    """The run's settings: its time limit is the horizon (random stops are drawn up to it)."""
    return replace(settings, time_limit=float(horizon))


def apply_lorr(scenario: Scenario, shift: Shift | None, dispatcher: str | None) -> Scenario:
    """A League ``scenario`` with its horizon as its shift (the suite's other shift keys kept) and the
    reference dispatcher unless the suite names one."""
    if scenario.lorr is None:
        return scenario
    horizon = float(scenario.lorr.horizon)
    return replace(
        scenario,
        shift=Shift(horizon) if shift is None else replace(shift, duration=horizon),
        dispatcher=dispatcher or DEFAULT_DISPATCHER,
    )
