"""The read-only view of the fleet a planner receives on every call (SPEC §6).

Everything in a :class:`FleetSnapshot` is immutable: frozen dataclasses, tuples and read-only mappings,
so a planner that tries to change the fleet fails loudly instead of corrupting the run.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from collections.abc import Set as AbstractSet
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import NamedTuple, TypeVar

from fleetsim.enums import Disturbed, Progress, Traverse
from fleetsim.layout.layout import Layout
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.scenario import Task, Vehicle, VehicleType

__all__ = ["FleetSnapshot", "PlanLog", "VehicleState", "initial_plan", "initial_state", "read_only"]


class PlanLog:
    """Whose plan each of a run's plan changes was, numbered from 1 (``FleetSnapshot.plans_version`` is the
    number of the last), for the most recent ``keep`` changes at least: what :meth:`FleetSnapshot.plans_changed`
    answers from."""

    __slots__ = ("_base", "_keep", "_vehicles")

    def __init__(self, keep: int) -> None:
        self._keep = max(keep, 1)
        self._vehicles: list[int] = []  # change number _base + 1 + i was vehicle _vehicles[i]
        self._base = 0

    def add(self, vehicle: int) -> None:
        self._vehicles.append(vehicle)
        if len(self._vehicles) > 2 * self._keep:
            del self._vehicles[: self._keep]
            self._base += self._keep

    def between(self, since: int, until: int) -> frozenset[int] | None:
        """The vehicles of changes ``since + 1`` to ``until``; None when the log no longer holds them all."""
        if since < self._base or until - self._base > len(self._vehicles) or since > until:
            return None
        return frozenset(self._vehicles[since - self._base : until - self._base])


class VehicleState(NamedTuple):
    """Where a vehicle is and how it moves: on which leg, how far along it, its pose and speed.

    Immutable (a named tuple: made for every moving vehicle on every step, so it must be cheap); use
    ``_replace`` to derive a changed copy.

    Attributes:
        id: The vehicle's id.
        segment: The segment of the leg it is on (its plan's first leg).
        traverse: Which way along that segment's waypoints it drives (``FORWARD``: first to last).
        progress: ``FORWARD`` nose first, ``REVERSE`` backing.
        distance: Metres driven along the current leg (0 at its entry, the segment's length at its exit).
        speed: Metres per second, never negative (the direction is ``traverse``).
        x: Metres, map frame.
        y: Metres, map frame.
        heading: Radians counter-clockwise from +x: where the nose points (the travel direction plus π
            when backing).
        type: Its [`VehicleType`][fleetsim.scenario.VehicleType] (``type.turn_capability``,
            ``type.max_speed``, ...).
        disturbed: [`Disturbed`][fleetsim.enums.Disturbed] ``STOPPED`` or ``SLOWED`` while a disturbance
            holds it, ``None`` while it drives as planned (how long a disturbance lasts is not told, as a
            fleet manager would not know).
    """

    id: int
    segment: int
    traverse: Traverse
    progress: Progress
    distance: float
    speed: float
    x: float
    y: float
    heading: float
    type: VehicleType
    disturbed: Disturbed | None = None


@dataclass(frozen=True, slots=True)
class FleetSnapshot:
    """The fleet at one moment: every vehicle's state, current plan and task queue, and the sim time.

    A planner call gets the snapshot of the moment it is asked at; plans accepted earlier in the same
    planning round are already in it. Its mappings are read-only copies.

    Attributes:
        time: Simulated seconds since the start.
        vehicles: Every vehicle's [`VehicleState`][fleetsim.planning.snapshot.VehicleState], by id.
        plans: Every vehicle's plan in force, by id. At the start a vehicle's plan is its start leg alone,
            fixed (the leg it stands on is always the plan's first, fixed leg).
        tasks: Every vehicle's queue of [`Task`][fleetsim.scenario.Task]s, head first, by id (an empty
            tuple: no tasks left).
        routed: Ids of queued tasks whose goal an accepted plan already marks (``goal_for_task``): the
            harness then asks ``fix_legs`` for them, else ``plan_routes``. A read-only set
            (``collections.abc.Set``: ``in``, ``len``, iteration, ``|``, ``&``, ``-``); its iteration
            order is not meaningful, so sort it where order matters.
        plans_version: A number that changes whenever a plan does, within one run (``None``: not known,
            as in a planner process). Two snapshots of a run with the same number show the same plans, so
            a planner that keeps its own tables of the plans can tell it has nothing to bring up to date
            without holding on to ``plans`` (holding a snapshot's mappings makes every later snapshot copy
            them whole, which costs a large fleet a copy per plan accepted).
    """

    time: float
    vehicles: Mapping[int, VehicleState]
    plans: Mapping[int, FleetPlan]
    tasks: Mapping[int, tuple[Task, ...]]  # each vehicle's queue, head first
    routed: AbstractSet[int]  # ids of queued tasks that an accepted plan already marks as a goal
    plans_version: int | None = None
    _log: PlanLog | None = field(default=None, repr=False, compare=False)

    def plans_changed(self, since: int) -> frozenset[int] | None:
        """The vehicles whose plans changed after version ``since`` (an earlier snapshot's ``plans_version``)
        up to this snapshot's, or ``None`` when that is not known (no versions, or too long ago: then
        compare the plans themselves). A planner's own tables of the plans need bringing up to date for
        these vehicles only."""
        if self._log is None or self.plans_version is None:
            return None
        return self._log.between(since, self.plans_version)

    def head_task(self, vehicle_id: int) -> Task | None:
        """The task the vehicle works on now, or ``None`` when it has no more tasks."""
        queue = self.tasks.get(vehicle_id, ())
        return queue[0] if queue else None

    def routed_tasks(self, vehicle_id: int) -> tuple[Task, ...]:
        """The vehicle's queued tasks whose goal an accepted plan already marks, in queue order."""
        return tuple(task for task in self.tasks.get(vehicle_id, ()) if task.id in self.routed)

    def is_routed(self, task: Task) -> bool:
        """Whether an accepted plan already marks ``task``'s goal."""
        return task.id in self.routed


def initial_state(vehicle: Vehicle, layout: Layout) -> VehicleState:
    """A vehicle at rest at the entry point of its start segment."""
    segment = layout.segments[vehicle.start_segment]
    x, y, travel = segment.pose_at(0.0, vehicle.traverse)
    heading = travel if vehicle.progress is Progress.FORWARD else travel + math.pi
    return VehicleState(
        id=vehicle.id,
        segment=vehicle.start_segment,
        traverse=vehicle.traverse,
        progress=vehicle.progress,
        distance=0.0,
        speed=0.0,
        x=x,
        y=y,
        heading=math.remainder(heading, math.tau),
        type=vehicle.type,
    )


def initial_plan(vehicle: Vehicle) -> FleetPlan:
    """The plan a vehicle starts with: the segment it stands on, fixed (it occupies it)."""
    leg = FleetLeg(vehicle.start_segment, vehicle.traverse, vehicle.progress, fixed=True)
    return FleetPlan(vehicle.id, (leg,))


K = TypeVar("K")
V = TypeVar("V")


def read_only(mapping: Mapping[K, V]) -> Mapping[K, V]:
    """A read-only copy: later changes to ``mapping`` do not show through."""
    return MappingProxyType(dict(mapping))
