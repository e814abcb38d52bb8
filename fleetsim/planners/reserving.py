"""A practical conflict-free planner: shortest routes, legs fixed only when no other vehicle holds them.

Routing is Dijkstra by length over (segment, traverse, progress) states, honouring the goal direction,
with penalties for turning back at a cusp (the vehicle stops and reverses or turns round), for driving
against another vehicle's plan (head-on) and for going near vehicles that have no tasks left (they will
not move away). A new route is only planned; its legs are fixed from the next call on, once every
vehicle of that planning round has made its route known. Fixing is where safety comes from: a leg is fixed only when its
segment's conflict set holds no other vehicle's fixed leg, so the reservation check never alerts.

Head-on deadlock on two-way stretches is avoided by where a vehicle may stop: the legs fixed in one go
end either at the goal or on a leg that no other vehicle's plan comes near (a place where others can
pass). A vehicle therefore never commits to a stretch it might have to share head-on with a vehicle
coming the other way. A vehicle that cannot fix anything while standing still looks for another route
now and then, with the segments others hold counted as nearly impassable.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import replace

from fleetsim.enums import JointKind, Traverse
from fleetsim.layout.layout import Layout
from fleetsim.planners.routing import legs_along, mark_goal_on_fixed, shortest_route
from fleetsim.planning.protocol import FleetLeg, FleetPlan, Response, RouteError
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Task

__all__ = ["ReservingPlanner"]


class _FleetIndex:
    """Which segments each vehicle's plan fixes and drives, refreshed only for plans that changed.

    Plans are immutable, so an unchanged plan is the very same object: identity tells what to redo.
    """

    def __init__(self) -> None:
        self._seen: dict[int, FleetPlan] = {}
        self._fixed: dict[int, Counter[int]] = {}
        self._route: dict[int, Counter[int]] = {}
        self._drives: dict[int, Counter[tuple[int, Traverse]]] = {}
        self.fixed: Counter[int] = Counter()  # segment -> fixed legs on it, all vehicles
        self.route: Counter[int] = Counter()  # segment -> legs on it, all vehicles
        self.drives: Counter[tuple[int, Traverse]] = Counter()  # (segment, traverse) -> legs, all vehicles

    def refresh(self, plans: Mapping[int, FleetPlan]) -> None:
        for vehicle_id, plan in plans.items():
            if self._seen.get(vehicle_id) is plan:
                continue
            self._seen[vehicle_id] = plan
            fixed = Counter(leg.segment for leg in plan.fixed_legs)
            route = Counter(leg.segment for leg in plan.legs)
            drives = Counter((leg.segment, leg.traverse) for leg in plan.legs)
            self.fixed += fixed
            self.fixed -= self._fixed.get(vehicle_id, Counter())
            self.route += route
            self.route -= self._route.get(vehicle_id, Counter())
            self.drives += drives
            self.drives -= self._drives.get(vehicle_id, Counter())
            self._fixed[vehicle_id], self._route[vehicle_id], self._drives[vehicle_id] = fixed, route, drives

    def others_fix(self, vehicle_id: int, segment: int) -> bool:
        return self.fixed[segment] > self._fixed[vehicle_id][segment]

    def others_drive(self, vehicle_id: int, segment: int) -> bool:
        return self.route[segment] > self._route[vehicle_id][segment]

    def others_drive_way(self, vehicle_id: int, segment: int, traverse: Traverse) -> bool:
        key = (segment, traverse)
        return self.drives[key] > self._drives[vehicle_id][key]


class ReservingPlanner:
    """Shortest routes by length; legs fixed only when their reservations overlap no other vehicle's."""

    turnaround_penalty = 10.0  # metres added for a cusp: stopping to reverse or turn round takes time
    oncoming_penalty = 50.0  # metres added for driving a segment that another plan drives the other way
    parked_penalty = 1_000.0  # metres added near a vehicle with no tasks left
    held_penalty = 200.0  # metres added, when looking for a way round, near legs others have fixed
    replan_interval = 2.0  # seconds a blocked, standing vehicle waits between looking for another route

    def __init__(self) -> None:
        self._index = _FleetIndex()
        self._last_replan: dict[int, float] = {}

    # -- the protocol --------------------------------------------------------------------------------

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self._index.refresh(fleet.plans)
        vehicle_id = task.vehicle_id
        fixed = fleet.plans[vehicle_id].fixed_legs
        marked = mark_goal_on_fixed(fixed, task, check_progress=True)
        if marked is not None:
            return [FleetPlan(vehicle_id, marked)]
        route = self._route(task, fixed[-1], fleet, layout, avoid_held=False)
        if route is None:
            last = fixed[-1]
            arrive = f" arriving {task.goal_progress.value}" if task.goal_progress is not None else ""
            msg = f"no route from segment {last.segment} ({last.traverse.value}) to segment {task.goal_segment}{arrive}"
            return [RouteError(vehicle_id, msg)]
        return [FleetPlan(vehicle_id, (*fixed, *route))]

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self._index.refresh(fleet.plans)
        vehicle_id = task.vehicle_id
        plan = fleet.plans[vehicle_id]
        fixed_count = len(plan.fixed_legs)
        if fixed_count == len(plan.legs):
            return []  # everything up to the goal is committed already
        extended = self._fix(plan, layout)
        if len(extended.fixed_legs) == fixed_count and self._should_look_around(vehicle_id, fleet):
            detour = self._route(task, plan.fixed_legs[-1], fleet, layout, avoid_held=True)
            if detour is not None and detour != plan.legs[fixed_count:]:
                extended = self._fix(FleetPlan(vehicle_id, (*plan.fixed_legs, *detour)), layout)
        return [extended] if extended != plan else []

    # -- routing -------------------------------------------------------------------------------------

    def _route(
        self, task: Task, last: FleetLeg, fleet: FleetSnapshot, layout: Layout, *, avoid_held: bool
    ) -> tuple[FleetLeg, ...] | None:
        vehicle_id = task.vehicle_id
        index = self._index
        parked: set[int] = set()
        for other, queue in fleet.tasks.items():
            if other != vehicle_id and not queue:
                parked |= layout.conflicts(fleet.vehicles[other].segment)

        def cost(segment: int, traverse: Traverse, joint: JointKind) -> float:
            total = layout.segments[segment].length
            if joint is JointKind.OPPOSITE:
                total += self.turnaround_penalty
            if index.others_drive_way(vehicle_id, segment, traverse.reversed):
                total += self.oncoming_penalty
            if segment in parked:
                total += self.parked_penalty
            if avoid_held and any(index.others_fix(vehicle_id, other) for other in layout.conflicts(segment)):
                total += self.held_penalty
            return total

        capability = fleet.vehicles[vehicle_id].type.turn_capability
        start = (last.segment, last.traverse, last.progress)
        path = shortest_route(layout, capability, start, task.goal_segment, task.goal_progress, cost)
        return None if path is None else legs_along(path, task, task.goal_progress)

    def _should_look_around(self, vehicle_id: int, fleet: FleetSnapshot) -> bool:
        """Only a vehicle standing at the end of what it may drive, and not too often."""
        if fleet.vehicles[vehicle_id].speed > 0.0 or len(fleet.plans[vehicle_id].fixed_legs) > 1:
            return False
        last = self._last_replan.get(vehicle_id)
        if last is not None and fleet.time - last < self.replan_interval:
            return False
        self._last_replan[vehicle_id] = fleet.time
        return True

    # -- fixing --------------------------------------------------------------------------------------

    def _free(self, vehicle_id: int, leg: FleetLeg, layout: Layout) -> bool:
        """No other vehicle has a fixed leg that conflicts with this leg's segment."""
        return not any(self._index.others_fix(vehicle_id, other) for other in layout.conflicts(leg.segment))

    def _clear(self, vehicle_id: int, leg: FleetLeg, layout: Layout) -> bool:
        """No other vehicle's plan comes near this leg's segment: a place to wait without blocking."""
        return not any(self._index.others_drive(vehicle_id, other) for other in layout.conflicts(leg.segment))

    def _fix(self, plan: FleetPlan, layout: Layout) -> FleetPlan:
        """Fix the longest run of free planned legs that ends at the goal or where the vehicle may wait."""
        vehicle_id = plan.vehicle_id
        fixed = plan.fixed_legs
        planned = plan.legs[len(fixed):]
        free = 0
        while free < len(planned) and self._free(vehicle_id, planned[free], layout):
            free += 1
        take = free
        if take < len(planned):
            while take > 0 and not self._clear(vehicle_id, planned[take - 1], layout):
                take -= 1
        if take == 0:
            return plan
        committed = tuple(replace(leg, fixed=True) for leg in planned[:take])
        return FleetPlan(vehicle_id, (*fixed, *committed, *planned[take:]))

