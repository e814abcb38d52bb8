"""The read-only view of the fleet a planner receives on every call (SPEC §6).

Everything in a :class:`FleetSnapshot` is immutable: frozen dataclasses, tuples and read-only mappings,
so a planner that tries to change the fleet fails loudly instead of corrupting the run.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import NamedTuple, TypeVar

from fleetsim.enums import Disturbed, Progress, Traverse
from fleetsim.layout.layout import Layout
from fleetsim.planning.protocol import FleetLeg, FleetPlan
from fleetsim.scenario import Task, Vehicle, VehicleType

__all__ = ["FleetSnapshot", "VehicleState", "initial_plan", "initial_state", "read_only"]


class VehicleState(NamedTuple):
    """Where a vehicle is and how it moves: on which leg, how far along it, its pose and speed.

    ``distance`` is metres driven along the current leg; ``heading`` (radians, counter-clockwise from +x)
    is where the vehicle's nose points, the travel direction plus π when it is backing. ``disturbed``:
    whether a disturbance stops or slows it now (``None``: it drives as planned). Immutable (a
    named tuple: made for every moving vehicle on every step, so it must be cheap); use ``_replace`` to
    derive a changed copy.
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
    """The fleet at one moment: every vehicle's state, current plan and task queue, and the sim time."""

    time: float
    vehicles: Mapping[int, VehicleState]
    plans: Mapping[int, FleetPlan]
    tasks: Mapping[int, tuple[Task, ...]]  # each vehicle's queue, head first
    routed: frozenset[int]  # ids of queued tasks that an accepted plan already marks as a goal

    def head_task(self, vehicle_id: int) -> Task | None:
        """The task the vehicle works on now, or ``None`` when it has no more tasks."""
        queue = self.tasks.get(vehicle_id, ())
        return queue[0] if queue else None

    def routed_tasks(self, vehicle_id: int) -> tuple[Task, ...]:
        """The vehicle's queued tasks whose goal an accepted plan already marks, in queue order."""
        return tuple(task for task in self.tasks.get(vehicle_id, ()) if task.id in self.routed)

    def is_routed(self, task: Task) -> bool:
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
