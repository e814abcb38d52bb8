"""Assembling a complete :class:`~fleetsim.scenario.Scenario`: map, vehicles, layout, tasks, checks.

The order is forced by the data: the vehicle rows are checked against the map's segments, the layout's
conflict radius depends on the vehicle types those rows use, and the start-conflict check and the task
check (every goal reachable, :mod:`.task_reach`) need the layout.

Errors are collected stage by stage (:class:`~fleetsim.load.common.collect.ErrorCollector`): the map's; then
every row error of ``vehicles.csv`` and of ``tasks.csv`` together (a task naming a vehicle whose row is
bad is not also called unknown); then the layout checks (start conflicts, reachability), which only run
on clean files; ``orders.csv``, when there is one, is read with the other CSV files and its orders checked
for reachability with the tasks (:mod:`.order_checks`). When the map cannot be loaded, the CSV files' rows are still checked for all that needs
no map (ids, words, vehicle types, which vehicles exist), and their errors reported with the map's.
Nothing is returned half loaded: either a whole scenario, or its errors — one raised as itself, several
as one :class:`~fleetsim.errors.LoadErrors`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from types import MappingProxyType

from fleetsim.enums import ConflictModel
from fleetsim.errors import Location, ScenarioFileError, SuiteError, UnreachableTaskError
from fleetsim.layout.layout import Layout, build_layout
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.lorr.fleet import LorrFleet
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.load.suites.disturbances import check_disturbances
from fleetsim.load.suites.lorr_entry import LorrEntry, apply_lorr, lorr_problem_fleet, lorr_settings
from fleetsim.load.suites.order_checks import apply_order_setup, order_reach_errors
from fleetsim.load.suites.scen_entry import ScenSetup, scen_agents
from fleetsim.load.suites.suite import ScenarioSpec, Suite
from fleetsim.load.suites.task_reach import check_tasks_reachable
from fleetsim.load.tables.orders import ORDERS_FILE_NAME, collect_orders
from fleetsim.load.tables.scenario_files import (
    MAP_FILE_NAMES,
    TASKS_FILE_NAME,
    VEHICLE_COLUMNS,
    VEHICLES_FILE_NAME,
    VehicleRows,
    collect_tasks,
    collect_vehicles,
    map_candidates,
)
from fleetsim.load.tables.table import check_table
from fleetsim.scenario import (
    DEFAULT_VEHICLE_TYPE,
    Expectations,
    Scenario,
    ScenarioSettings,
    Task,
    Vehicle,
    VehicleType,
    longest_vehicle,
)

__all__ = ["default_vehicle_type", "load_scenario", "load_scenario_dir"]


def load_scenario(spec: ScenarioSpec, suite: Suite) -> Scenario:
    """Load the files of one suite entry into a complete scenario.

    Every error of its files is reported at once: one is raised as itself (a
    [`ScenarioFileError`][fleetsim.errors.ScenarioFileError], say), several as one
    [`LoadErrors`][fleetsim.errors.LoadErrors], at most 50 per file.
    """
    scenario = _assemble(
        spec.name,
        (spec.map_path, spec.vehicles_path, spec.tasks_path),
        suite.vehicle_types,
        spec.settings,
        spec.expect,
        Location(spec.suite_path, line=spec.line),
        spec.map_options,
        spec.order_setup.orders_path,
        spec.scen,
        spec.lorr,
    )
    scenario = replace(scenario, planner_setup=spec.planner_setup)
    scenario = apply_order_setup(scenario, spec.order_setup)
    scenario = apply_lorr(scenario, spec.order_setup.shift, spec.order_setup.dispatcher)
    if not spec.disturbances and spec.random_disturbances is None:
        return scenario
    # The entry's random stops replace a League problem's delays.
    drawn = spec.random_disturbances or scenario.random_disturbances
    scenario = replace(scenario, disturbances=spec.disturbances, random_disturbances=drawn)
    check_disturbances(scenario, spec.suite_path)
    return scenario


def load_scenario_dir(
    directory: Path | str,
    *,
    vehicle_types: Mapping[str, VehicleType] | None = None,
    settings: ScenarioSettings | None = None,
    map_options: MapOptions | None = None,
) -> Scenario:
    """Load a scenario folder without a suite: a map file (``map.json``, ``map.tmj``, ``map.tmx``,
    ``map.lif.json`` or ``map.building.yaml``), ``vehicles.csv``, ``tasks.csv`` and, if it has one,
    ``orders.csv``.

    The scenario is named after the folder. Without ``vehicle_types`` every vehicle is the built-in
    default type; expectations are the defaults (all tasks, no collisions, no rejections).
    ``map_options`` choose the part of a LIF or RMF map to drive on.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise ScenarioFileError("no such directory", Location(directory))
    candidates = map_candidates(directory)
    if len(candidates) != 1:
        found = " and ".join(c.name for c in candidates) if candidates else "none"
        msg = f"a scenario folder needs exactly one of {', '.join(MAP_FILE_NAMES)}; found {found}"
        raise ScenarioFileError(msg, Location(directory))
    types = dict(vehicle_types) if vehicle_types else {DEFAULT_VEHICLE_TYPE.name: DEFAULT_VEHICLE_TYPE}
    return _assemble(
        directory.resolve().name,
        (candidates[0], directory / VEHICLES_FILE_NAME, directory / TASKS_FILE_NAME),
        MappingProxyType(types),
        settings if settings is not None else ScenarioSettings(),
        Expectations(),
        Location(directory),
        map_options if map_options is not None else MapOptions(),
        directory / ORDERS_FILE_NAME if (directory / ORDERS_FILE_NAME).is_file() else None,
    )


def default_vehicle_type(
    vehicle_types: Mapping[str, VehicleType], settings: ScenarioSettings, where: Location | None = None
) -> VehicleType | None:
    """The type of vehicles whose row names none: ``settings.vehicle_type``, else the only type, else None."""
    if settings.vehicle_type is None:
        return next(iter(vehicle_types.values())) if len(vehicle_types) == 1 else None
    for name, vehicle_type in vehicle_types.items():
        if name.casefold() == settings.vehicle_type.casefold():
            return vehicle_type
    known = ", ".join(vehicle_types)
    msg = f"vehicle_type={settings.vehicle_type!r} is not one of the vehicle types ({known})"
    raise ScenarioFileError(msg, where)


def _assemble(
    name: str,
    paths: tuple[Path, Path, Path],
    vehicle_types: Mapping[str, VehicleType],
    settings: ScenarioSettings,
    expect: Expectations,
    origin: Location,
    map_options: MapOptions,
    orders_path: Path | None = None,
    scen: ScenSetup | None = None,
    lorr: LorrEntry | None = None,
) -> Scenario:
    map_path, vehicles_path, tasks_path = paths
    errors = ErrorCollector()
    site: SiteMap | None = None
    if lorr is None:  # a League problem names its map: it is read with the problem
        with errors.collecting():
            site = load_site_map(map_path, map_options)
    typed = False  # the default vehicle type is known (None is a valid answer: there is none)
    default_type: VehicleType | None = None
    with errors.collecting():
        default_type = default_vehicle_type(vehicle_types, settings, origin)
        typed = True
    # Without the map, the rows are still checked for all that needs no segments (reported with the
    # map's errors); without the default type, vehicles.csv only for its structure (a row naming no type
    # cannot be judged) and tasks.csv without knowing which vehicles exist.
    segments = {segment.id: segment for segment in site.segments} if site is not None else None
    vehicle_rows = VehicleRows((), None)
    located_tasks: tuple[tuple[Task, int], ...] = ()
    fleet: LorrFleet | None = None
    if lorr is not None:  # a League problem: vehicles and orders from its agent and task files
        if typed:
            with errors.collecting():
                given_type = default_type if default_type is not DEFAULT_VEHICLE_TYPE else None
                problem, site, fleet = lorr_problem_fleet(lorr, map_options, given_type)
                map_path, vehicles_path, tasks_path = problem.map_path, problem.agent_path, problem.task_path
                vehicle_rows = VehicleRows(fleet.vehicles, frozenset(vehicle.id for vehicle, _ in fleet.vehicles))
                vehicle_types = MappingProxyType({**vehicle_types, fleet.vehicle_type.name: fleet.vehicle_type})
                settings = lorr_settings(settings, lorr.horizon)
    elif scen is not None:  # a MovingAI scenario: vehicles and tasks from its agents, once the map is loaded
        if site is not None and typed:
            with errors.collecting():
                # A suite that declares no vehicle types gets the MovingAI type, not the built-in default.
                given_type = default_type if default_type is not DEFAULT_VEHICLE_TYPE else None
                agents, located_tasks, agent_type = scen_agents(scen, site, map_options, given_type)
                vehicle_rows = VehicleRows(agents, frozenset(vehicle.id for vehicle, _ in agents))
                vehicle_types = MappingProxyType({**vehicle_types, agent_type.name: agent_type})
    elif typed:
        vehicle_rows = collect_vehicles(
            vehicles_path, segments, vehicle_types, default_type, errors, map_name=map_path.name
        )
    else:
        check_table(vehicles_path, VEHICLE_COLUMNS, errors)
    if (
        scen is None and lorr is None
    ):  # tasks are checked against every vehicle id vehicles.csv names, bad rows' included
        located_tasks = collect_tasks(
            tasks_path, segments, vehicle_rows.ids, errors, map_name=map_path.name, vehicles_name=vehicles_path.name
        )
    orders = collect_orders(orders_path, segments, tuple(vehicle_types), errors) if orders_path is not None else ()
    errors.raise_if_any()
    if fleet is not None:
        orders = fleet.orders
    assert site is not None and typed  # raise_if_any raised the error that left them unset
    located = vehicle_rows.located
    vehicles = tuple(vehicle for vehicle, _ in located)
    layout = build_layout(
        site.segments,
        vehicle_radius=_vehicle_radius(vehicles, default_type, vehicle_types, settings.conflict_model),
        connection_tolerance=settings.connection_tolerance,
        joint_angle_tolerance=settings.joint_angle_tolerance,
        safety_margin=settings.safety_margin,
        conflict_model=settings.conflict_model,
        source=map_path,
    )
    tasks = tuple(task for task, _ in located_tasks)
    if not settings.allow_start_conflicts:
        _reject_start_conflicts(located, layout, vehicles_path, errors)
        errors.raise_if_any()
    try:
        check_tasks_reachable(layout, vehicles, located_tasks, tasks_path)
    except UnreachableTaskError as error:
        # The map's lint often shows the cause (a gap between two ends): hand it to whoever reports.
        length = longest_vehicle(vehicles, vehicle_types.values())
        error.notes = (*site.warnings, *(f"{f.severity} {f.code}: {f.message}" for f in layout.lint(length)))
        raise
    if orders_path is not None or fleet is not None:
        for unserved in order_reach_errors(layout, vehicles, orders, orders_path or tasks_path):
            errors.add(unserved)
        errors.raise_if_any()
    _check_expected_collisions(name, expect, layout, map_path, origin)
    return Scenario(
        name=name,
        layout=layout,
        vehicle_types=vehicle_types,
        vehicles=vehicles,
        tasks=tasks,
        settings=settings,
        expect=expect,
        map_path=map_path,
        vehicles_path=vehicles_path,
        tasks_path=tasks_path,
        warnings=site.warnings,
        orders=orders,
        stations=site.stations,
        orders_path=orders_path,
        order_pool=fleet.pool if fleet is not None else None,
        random_disturbances=fleet.disturbances if fleet is not None else None,
        lorr=fleet.setup if fleet is not None else None,
    )


def _vehicle_radius(
    vehicles: tuple[Vehicle, ...],
    default_type: VehicleType | None,
    vehicle_types: Mapping[str, VehicleType],
    model: ConflictModel,
) -> float:
    """The conflict radius: the largest over the types this scenario's vehicles use.

    With no vehicles the default type counts; with no default either, every type of the suite (a
    conflict set that is too large is safer than one that is too small).
    """
    used = [vehicle.type for vehicle in vehicles]
    if not used:
        used = [default_type] if default_type is not None else list(vehicle_types.values())
    if not used:
        used = [DEFAULT_VEHICLE_TYPE]
    if model is ConflictModel.BBOX:
        return max(vehicle_type.bbox_radius for vehicle_type in used)
    return max(vehicle_type.swept_radius for vehicle_type in used)


def _reject_start_conflicts(
    located: tuple[tuple[Vehicle, int], ...], layout: Layout, vehicles_path: Path, errors: ErrorCollector
) -> None:
    """Two vehicles may not start on conflicting segments: their very first plans would collide.

    Each vehicle that starts in conflict with one above it is an error at its row."""
    placed: dict[int, tuple[Vehicle, int]] = {}  # start segment → first vehicle on it, with its line
    for vehicle, line in located:
        hits = [placed[segment] for segment in layout.conflicts(vehicle.start_segment) if segment in placed]
        if hits:
            other, other_line = min(hits, key=lambda hit: hit[1])
            msg = (
                f"vehicles {other.id} (line {other_line}, segment {other.start_segment}) and "
                f"{vehicle.id} (line {line}, segment {vehicle.start_segment}) start on conflicting "
                "segments; move one, or set allow_start_conflicts: true for this scenario"
            )
            errors.add(ScenarioFileError(msg, Location(vehicles_path, line=line, field="start_segment_id")))
        placed.setdefault(vehicle.start_segment, (vehicle, line))


def _check_expected_collisions(
    name: str, expect: Expectations, layout: Layout, map_path: Path, origin: Location
) -> None:
    # A typo in expect.collisions would make the scenario impossible to pass, for a confusing reason.
    if isinstance(expect.collisions, str):
        return
    unknown = [segment for segment in expect.collisions if segment not in layout.segments]
    if unknown:
        msg = f"scenario {name!r}: expect.collisions names segment {unknown[0]}, which is not in {map_path.name}"
        raise SuiteError(msg, origin)
