"""What a loaded scenario is made of: vehicle types, vehicles, tasks, settings, expectations (SPEC §5, §13)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Literal

from fleetsim.enums import ConflictModel, Progress, Traverse, TurnCapability
from fleetsim.errors import ScenarioError
from fleetsim.orders import LorrSetup, MeasureBound, Order, OrderStream, Shift, Station

if TYPE_CHECKING:
    from fleetsim.layout.layout import Layout

__all__ = [
    "DEFAULT_VEHICLE_TYPE",
    "Checks",
    "Disturbance",
    "Expectations",
    "PlannerSetup",
    "RandomDisturbances",
    "Scenario",
    "ScenarioSettings",
    "Task",
    "Vehicle",
    "VehicleType",
    "longest_vehicle",
]

RGBA = tuple[float, float, float, float]


@dataclass(frozen=True, slots=True)
class VehicleType:
    """A kind of vehicle: its size, how fast it drives and how it turns (``vehicle_types`` in a suite).

    Attributes:
        name: The type's name, as ``vehicles.csv``'s ``type`` column gives it.
        length: Metres, nose to tail.
        width: Metres, side to side.
        height: Metres (drawn in recordings only).
        max_speed: Metres per second, the most it drives at on any leg.
        acceleration: Metres per second squared, both speeding up and braking (the motion model is
            symmetric: a vehicle at ``max_speed`` needs ``max_speed**2 / (2 * acceleration)`` metres to stop).
        turn_capability: ``IN_PLACE`` (it may stop and turn on the spot, so it can take a
            ``TURN_IN_PLACE`` joint and meet any goal direction) or ``CURVE`` (it follows curves only).
        turn_rate: Degrees per second of an in-place turn.
        color: RGBA (0-1 each) for recordings and pictures, or ``None`` for the default palette.
    """

    name: str
    length: float
    width: float
    height: float
    max_speed: float
    acceleration: float
    turn_capability: TurnCapability
    turn_rate: float = 90.0  # deg/s, in-place turning speed
    color: RGBA | None = None

    @property
    def swept_radius(self) -> float:
        """Metres: the radius of the circle that covers the vehicle whatever its heading (half its diagonal).

        Segments conflict when such circles on them could touch (``ConflictModel.SWEPT``); the layout's
        ``vehicle_radius`` is the largest over the vehicle types the scenario's vehicles use.
        """
        return 0.5 * math.hypot(self.length, self.width)

    @property
    def bbox_radius(self) -> float:
        """Metres: the thesis's vehicle circle, half the larger of length and width (``ConflictModel.BBOX``)."""
        return 0.5 * max(self.length, self.width)


DEFAULT_VEHICLE_TYPE = VehicleType(
    name="default",
    length=1.0,
    width=0.6,
    height=0.4,
    max_speed=1.0,
    acceleration=0.5,
    turn_capability=TurnCapability.IN_PLACE,
)


@dataclass(frozen=True, slots=True)
class Vehicle:
    """A vehicle as it starts: at rest at the entry point of its start segment.

    Attributes:
        id: The vehicle's id (``vehicles.csv``), unique in the scenario.
        start_segment: The segment it starts on.
        traverse: Which way along that segment's waypoints it faces (``FORWARD``: first to last).
        progress: ``FORWARD`` nose first, ``REVERSE`` backing.
        type: Its [`VehicleType`][fleetsim.scenario.VehicleType].
    """

    id: int
    start_segment: int
    traverse: Traverse
    progress: Progress
    type: VehicleType


def longest_vehicle(vehicles: Iterable[Vehicle], vehicle_types: Iterable[VehicleType]) -> float:
    """The length of the longest vehicle type in use: over ``vehicles``, else over ``vehicle_types``,
    else the default type's (a gap shorter than this is one no vehicle of the scenario spans)."""
    lengths = [vehicle.type.length for vehicle in vehicles] or [t.length for t in vehicle_types]
    return max(lengths, default=DEFAULT_VEHICLE_TYPE.length)


@dataclass(frozen=True, slots=True)
class Task:
    """Drive ``vehicle_id`` to ``goal_segment``: the task is done when the vehicle enters a leg on that
    segment that its plan marks with the task's id (``FleetLeg.goal_for_task``).

    Attributes:
        id: The 1-based data-row number in ``tasks.csv``; unique in the scenario.
        vehicle_id: The vehicle that must do it. A vehicle's tasks are done in file order: only the head
            of its queue (``FleetSnapshot.head_task``) is asked about.
        goal_segment: The segment to reach.
        goal_progress: ``FORWARD`` (nose first) or ``REVERSE`` (backing) if the vehicle must arrive that
            way (check code ``goal-direction``), ``None`` if either will do.
        order_id: The transport order whose stop this is (a task a dispatcher's assignment made), or
            ``None`` for a task of ``tasks.csv``.
        stop: The index (from 0) of that stop in its order, or ``None``.
        deadline: Seconds of simulated time by which the order's last stop must be served, or ``None``.
    """

    id: int
    vehicle_id: int
    goal_segment: int
    goal_progress: Progress | None = None
    order_id: str | None = None
    stop: int | None = None
    deadline: float | None = None


@dataclass(frozen=True, slots=True)
class Disturbance:
    """A declared disturbance (issue 20): ``vehicle`` stops (stands ``duration`` s once at rest) or is
    slowed to ``factor`` × its max speed for ``duration`` s, from time ``at`` or when it is first on
    segment ``on_segment`` (exactly one of the two is set)."""

    vehicle: int
    kind: Literal["stop", "slow"]
    duration: float
    at: float | None = None
    on_segment: int | None = None
    factor: float = 0.0  # slow only
    line: int | None = field(default=None, compare=False)  # of its entry in the suite, for errors

    def entry(self) -> dict[str, float | int]:
        """The suite entry that declares it (``disturbances:`` list item)."""
        where: dict[str, float | int] = {"at": self.at} if self.at is not None else {"on_segment": self.on_segment or 0}
        what: dict[str, float | int] = (
            {"stop": self.duration} if self.kind == "stop" else {"slow": self.factor, "for": self.duration}
        )
        return {"vehicle": self.vehicle, **where, **what}


@dataclass(frozen=True, slots=True)
class RandomDisturbances:
    """Stops drawn from ``seed`` (fleetsim.sim.disturbances.draw_stops): on average
    ``stops_per_vehicle_hour`` per vehicle, each standing a duration drawn uniformly from ``stop``."""

    seed: int
    stops_per_vehicle_hour: float
    stop: tuple[float, float]


StopOn = Literal["rejection", "collision", "contact"]


@dataclass(frozen=True, slots=True)
class Checks:
    """Which judgements a run gets (a suite's or entry's ``checks``): the thesis's reservation rule, the
    physical contact check, or both (the default).

    Attributes:
        reservations: Collision alerts where one vehicle's primary reservation overlaps another's (a
            planning discipline: drive only on what you hold, exclusively).
        contact: Contacts between the vehicles' footprints, checked continuously between steps, with the
            run's clearance and near misses (the physical outcome).
        safety_margin: Metres added to every side of each footprint for the contact check.
        near_miss: Metres: pairs of footprints that came closer than this without touching are listed.
    """

    reservations: bool = True
    contact: bool = True
    safety_margin: float = 0.0
    near_miss: float = 0.5


@dataclass(frozen=True, slots=True)
class ScenarioSettings:
    """Run and layout settings; suite ``defaults`` and each scenario entry override these.

    Attributes:
        vehicle_type: The name of the vehicle type of ``vehicles.csv`` rows that name none, or ``None``:
            then the suite's only type (without ``vehicle_types``, the built-in default type), and with
            several types every row must name its own.
        time_step: Seconds simulated per step.
        time_limit: Seconds of simulated time after which a run with tasks left fails (``timeout``).
        planning_period: Seconds between planning rounds (rounded to whole steps).
        deadlock_after: Seconds with tasks pending, nothing moving and no plan changing after which the
            run ends in a deadlock.
        stop_on: The events that end a run at once: ``"rejection"``, ``"collision"``, both (the
            default) or none (run on and collect everything).
        connection_tolerance: Metres within which two segment ends meet.
        joint_angle_tolerance: Degrees within which two segments meeting count as smooth (or as a cusp).
        conflict_model: How conflicting segments are found (``SWEPT`` or ``BBOX``).
        safety_margin: Metres added between two vehicles' circles when conflicts are found.
        allow_start_conflicts: Whether vehicles may start on conflicting segments (else a load error).
        checks: Which judgements the run gets ([`Checks`][fleetsim.scenario.Checks]).
    """

    vehicle_type: str | None = None
    time_step: float = 0.1
    time_limit: float = 300.0
    planning_period: float = 0.1
    deadlock_after: float = 30.0
    stop_on: tuple[StopOn, ...] = ("rejection", "collision")
    connection_tolerance: float = 0.05
    joint_angle_tolerance: float = 30.0
    conflict_model: ConflictModel = ConflictModel.SWEPT
    safety_margin: float = 0.0
    allow_start_conflicts: bool = False
    checks: Checks = Checks()


@dataclass(frozen=True, slots=True)
class Expectations:
    """What a scenario's run must show to pass (a scenario entry's ``expect``).

    Attributes:
        tasks: ``"all"``, or how many tasks must be completed.
        collisions: ``"none"``, ``"any"`` (at least one alert), or the segment ids that must be flagged.
        rejections: ``"none"``, ``"any"`` (at least one), or the check codes that must occur.
        deadlock: Whether the run must end in a deadlock.
        max_makespan: Seconds by which the last task must be completed, or ``None``.
        contacts: ``"none"`` (a contact fails the run) or ``"any"`` (the run must have at least one).
        clearance: Metres: the run fails when two footprints came closer than this, or ``None``.
        measures: Bounds on the measures of a run with transport orders (``min_orders_per_hour``,
            ``max_service_time_p95``, ...), in suite order.
        overloaded: ``False``: a run whose backlog grows fails; ``True``: it must grow; ``None``: either.
    """

    tasks: Literal["all"] | int = "all"
    collisions: Literal["none", "any"] | tuple[int, ...] = "none"
    rejections: Literal["none", "any"] | tuple[str, ...] = "none"
    deadlock: bool = False
    max_makespan: float | None = None
    contacts: Literal["none", "any"] = "none"
    clearance: float | None = None
    measures: tuple[MeasureBound, ...] = ()
    overloaded: bool | None = None


@dataclass(frozen=True, slots=True)
class PlannerSetup:
    """What a suite entry gives its planner: ``planner_options`` and the data ``files`` it reads.

    Attributes:
        options: The entry's ``planner_options`` (JSON values, by option name): the planner factory is
            called with them as keyword arguments; an ``exec:`` planner gets them in its init message.
        folder: The scenario's folder: the entry's ``dir``, else the suite file's folder; ``None`` for a
            scenario without one. A factory that declares a ``scenario_dir`` parameter gets it.
        files: The entry's data files (or folders of them), relative to ``folder`` with ``/`` between
            parts: a sweep sends them to its workers, which put them at the same paths in the folder
            their planner gets as ``scenario_dir``.
        where: Where the options are written (``suite.yaml:12:7``), for messages; empty when unknown.
    """

    options: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    folder: Path | None = None
    files: tuple[str, ...] = ()
    where: str = ""


@dataclass(frozen=True, slots=True)
class Scenario:
    """A completely loaded scenario: layout, fleet, tasks, settings and expectations.

    One made in code is checked as loading checks files: every vehicle must start on a segment of the
    layout, every task must be for one of the vehicles and have its goal on a segment of the layout, and
    every order's stops and every station must be on segments of the layout; otherwise
    [`ScenarioError`][fleetsim.errors.ScenarioError] names each task, vehicle, order or station and the segment.

    Attributes:
        name: The scenario's name (its suite entry's, or its folder's).
        layout: The map, built with the scenario's settings.
        vehicle_types: The suite's vehicle types, by name.
        vehicles: The fleet as it starts, in ``vehicles.csv`` order.
        tasks: Every task, in ``tasks.csv`` order (ids 1, 2, ...).
        settings: Run and layout settings.
        expect: What a run must show to pass.
        map_path: The map file it was loaded from, if any.
        vehicles_path: The ``vehicles.csv`` it was loaded from, if any.
        tasks_path: The ``tasks.csv`` it was loaded from, if any.
        disturbances: Declared disturbances (stops and slow-downs), in suite order.
        random_disturbances: Randomly drawn stops, if the entry asks for them.
        warnings: Notes from loading that did not stop it (shapes given to non-polylines, say).
        planner_setup: What the suite entry gives the planner: its options, folder and data files.
        orders: Transport orders (``orders.csv``), in file order; a dispatcher assigns them.
        order_pool: Release ``orders`` as a closed pool of this many open orders (file order; one more
            for each completed, as a League of Robot Runners problem reveals its tasks), or ``None``: each
            at its own release time.
        order_stream: Orders to generate as the run goes, or ``None``.
        stations: The map's and the suite's station sets, by name, each segment once, ascending.
        shift: The run as a shift (its length, warm-up, stalls), or ``None``: a run of fixed tasks.
        orders_path: The ``orders.csv`` it was loaded from, if any.
        dispatcher: The dispatcher spec (``module:attr``) its suite entry names, or ``None``.
        lorr: The League of Robot Runners problem it was loaded from, or ``None``: its runs' results
            also give the competition's counts.
    """

    name: str
    layout: Layout
    vehicle_types: Mapping[str, VehicleType]
    vehicles: tuple[Vehicle, ...]
    tasks: tuple[Task, ...]
    settings: ScenarioSettings = field(default_factory=ScenarioSettings)
    expect: Expectations = field(default_factory=Expectations)
    map_path: Path | None = None
    vehicles_path: Path | None = None
    tasks_path: Path | None = None
    disturbances: tuple[Disturbance, ...] = ()
    random_disturbances: RandomDisturbances | None = None
    warnings: tuple[str, ...] = ()
    planner_setup: PlannerSetup = field(default_factory=PlannerSetup)
    orders: tuple[Order, ...] = ()
    order_pool: int | None = None
    order_stream: OrderStream | None = None
    stations: Mapping[str, tuple[Station, ...]] = field(default_factory=lambda: MappingProxyType({}))
    shift: Shift | None = None
    orders_path: Path | None = None
    dispatcher: str | None = None
    lorr: LorrSetup | None = None

    def __post_init__(self) -> None:
        # A scenario built in code (not loaded from files, whose rows are checked) is refused here,
        # before any run: a goal on a segment the map lacks would otherwise reach the planner and the checks.
        segments = self.layout.segments
        vehicle_ids = {vehicle.id for vehicle in self.vehicles}
        if (
            all(vehicle.start_segment in segments for vehicle in self.vehicles)
            and all(task.goal_segment in segments and task.vehicle_id in vehicle_ids for task in self.tasks)
            and all(stop.segment in segments for order in self.orders for stop in order.stops)
            and all(station.segment in segments for members in self.stations.values() for station in members)
        ):
            return
        problems = _missing_references(self, vehicle_ids)
        shown = "; ".join(problems[:_PROBLEMS_SHOWN])
        more = f"; and {len(problems) - _PROBLEMS_SHOWN} more" if len(problems) > _PROBLEMS_SHOWN else ""
        raise ScenarioError(f"scenario {self.name!r}: {shown}{more}", problems)

    @property
    def vehicle_length(self) -> float:
        """Metres: the length of the longest vehicle type the scenario's vehicles use (lint reports gaps
        up to this long)."""
        return longest_vehicle(self.vehicles, self.vehicle_types.values())


_PROBLEMS_SHOWN = 5  # in a ScenarioError's message; its ``problems`` hold them all


def _missing_references(scenario: Scenario, vehicle_ids: set[int]) -> list[str]:
    """Each vehicle starting, each task ending, each order stop and each station on a segment the layout
    lacks; each task for a vehicle the scenario lacks."""
    from fleetsim.layout.segment_ids import not_in_map  # here, so importing this module stays cheap

    segments = scenario.layout.segments
    problems = [
        f"vehicle {vehicle.id} starts on {not_in_map(vehicle.start_segment, segments)}"
        for vehicle in scenario.vehicles
        if vehicle.start_segment not in segments
    ]
    for task in scenario.tasks:
        if task.vehicle_id not in vehicle_ids:
            known = ", ".join(str(v) for v in sorted(vehicle_ids)) or "none"
            problems.append(
                f"task {task.id} is for vehicle {task.vehicle_id}, which is not in the scenario (vehicles: {known})"
            )
        if task.goal_segment not in segments:
            problems.append(
                f"task {task.id} of vehicle {task.vehicle_id} has its goal on {not_in_map(task.goal_segment, segments)}"
            )
    for order in scenario.orders:
        problems += [
            f"order {order.id!r} has its stop {number} on {not_in_map(stop.segment, segments)}"
            for number, stop in enumerate(order.stops, start=1)
            if stop.segment not in segments
        ]
    for name, members in scenario.stations.items():
        problems += [
            f"station set {name!r} has a station on {not_in_map(station.segment, segments)}"
            for station in members
            if station.segment not in segments
        ]
    return problems
