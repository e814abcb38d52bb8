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
after 2 s, then at doubling intervals (up to 16 s) while it stays blocked, with the segments others hold
counted as nearly impassable. Searches are A* with a straight-line estimate.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from fleetsim.enums import JointKind, Traverse
from fleetsim.layout.layout import Layout
from fleetsim.planners.routing import legs_along, mark_goal_on_fixed, shortest_route, straight_line_estimate
from fleetsim.planning.protocol import FleetLeg, FleetPlan, Response, RouteError
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Task

__all__ = ["ReservingPlanner"]


# Counts by key (a segment, or a (segment, traverse) drive); a key whose count falls to 0 is removed.
Counts = dict[Any, int]


def _add(counts: Counts, key: object, amount: int) -> None:
    total = counts.get(key, 0) + amount
    if total:
        counts[key] = total
    else:
        del counts[key]


class _FleetIndex:
    """What each vehicle's plan holds *near* every segment, refreshed only for plans that changed.

    ``fixed_near[s]`` counts fixed legs whose segment conflicts with ``s`` (conflicts are symmetric and
    include the segment itself), so "does another vehicle hold a fixed leg that conflicts with ``s``" is
    one subtraction. ``route_near`` does the same for all legs, ``drives`` counts (segment, traverse).
    Plans are immutable, so an unchanged plan is the very same object: identity tells what to redo.
    """

    def __init__(self, layout: Layout) -> None:
        self._layout = layout
        self._plans: object = None  # the mapping last refreshed from
        self._seen: dict[int, FleetPlan] = {}
        self._mine: dict[int, tuple[Counts, Counts, Counts]] = {}  # each vehicle's (fixed near, route near, drives)
        self.fixed_near: dict[int, int] = {}
        self.route_near: dict[int, int] = {}
        self.drives: dict[tuple[int, Traverse], int] = {}

    def refresh(self, plans: Mapping[int, FleetPlan]) -> None:
        if plans is self._plans:
            return  # the same snapshot as last call: nothing can have changed
        self._plans = plans
        for vehicle_id, plan in plans.items():
            if self._seen.get(vehicle_id) is not plan:
                self._replace(vehicle_id, plan)

    def _replace(self, vehicle_id: int, plan: FleetPlan) -> None:
        totals: tuple[Counts, Counts, Counts] = (self.fixed_near, self.route_near, self.drives)
        old = self._mine.get(vehicle_id)
        if old is not None:
            for counts, mine in zip(totals, old):
                for key, amount in mine.items():
                    _add(counts, key, -amount)
        fixed: dict[int, int] = {}
        route: dict[int, int] = {}
        drives: dict[tuple[int, Traverse], int] = {}
        fixed_count = len(plan.fixed_legs)
        for index, leg in enumerate(plan.legs):
            drives[(leg.segment, leg.traverse)] = drives.get((leg.segment, leg.traverse), 0) + 1
            for near in self._layout.conflicts(leg.segment):
                route[near] = route.get(near, 0) + 1
                if index < fixed_count:
                    fixed[near] = fixed.get(near, 0) + 1
        new: tuple[Counts, Counts, Counts] = (fixed, route, drives)
        for counts, mine in zip(totals, new):
            for key, amount in mine.items():
                _add(counts, key, amount)
        self._seen[vehicle_id] = plan
        self._mine[vehicle_id] = new

    def mine(self, vehicle_id: int) -> tuple[dict[int, int], dict[int, int], dict[tuple[int, Traverse], int]]:
        """The vehicle's own (fixed near, route near, drives) counts."""
        return self._mine[vehicle_id]

    def others_fix_near(self, vehicle_id: int, segment: int) -> bool:
        """Another vehicle has a fixed leg that conflicts with ``segment``."""
        return self.fixed_near.get(segment, 0) > self._mine[vehicle_id][0].get(segment, 0)

    def others_drive_near(self, vehicle_id: int, segment: int) -> bool:
        """Another vehicle's plan has a leg that conflicts with ``segment``."""
        return self.route_near.get(segment, 0) > self._mine[vehicle_id][1].get(segment, 0)

    def others_drive_way(self, vehicle_id: int, segment: int, traverse: Traverse) -> bool:
        key = (segment, traverse)
        return self.drives.get(key, 0) > self._mine[vehicle_id][2].get(key, 0)


class ReservingPlanner:
    """Shortest routes by length; legs fixed only when their reservations overlap no other vehicle's."""

    turnaround_penalty = 10.0  # metres added for a cusp: stopping to reverse or turn round takes time
    oncoming_penalty = 50.0  # metres added for driving a segment that another plan drives the other way
    parked_penalty = 1_000.0  # metres added near a vehicle with no tasks left
    held_penalty = 200.0  # metres added, when looking for a way round, near legs others have fixed
    replan_interval = 2.0  # seconds a blocked, standing vehicle first waits before looking for another route
    max_replan_interval = 16.0  # the longest wait between looks

    def __init__(self) -> None:
        self._index: _FleetIndex | None = None
        self._next_look: dict[int, tuple[float, float]] = {}  # vehicle -> (next look, current wait)
        self._lengths: dict[int, float] | None = None

    def _refresh(self, fleet: FleetSnapshot, layout: Layout) -> _FleetIndex:
        if self._index is None:
            self._index = _FleetIndex(layout)
        self._index.refresh(fleet.plans)
        return self._index

    # -- the protocol --------------------------------------------------------------------------------

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self._refresh(fleet, layout)
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
        self._refresh(fleet, layout)
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
        index = self._refresh(fleet, layout)
        parked: set[int] = set()
        for other, queue in fleet.tasks.items():
            if other != vehicle_id and not queue:
                parked |= layout.conflicts(fleet.vehicles[other].segment)

        lengths = {sid: segment.length for sid, segment in layout.segments.items()} if self._lengths is None else self._lengths
        self._lengths = lengths
        fixed_near, mine_fixed = index.fixed_near, index.mine(vehicle_id)[0]
        drives, mine_drives = index.drives, index.mine(vehicle_id)[2]
        opposite = {Traverse.FORWARD: Traverse.BACKWARD, Traverse.BACKWARD: Traverse.FORWARD}
        turnaround, oncoming, near_parked, held = (
            self.turnaround_penalty, self.oncoming_penalty, self.parked_penalty, self.held_penalty
        )

        def cost(segment: int, traverse: Traverse, joint: JointKind) -> float:
            total = lengths[segment]
            if joint is JointKind.OPPOSITE:
                total += turnaround
            against = (segment, opposite[traverse])
            if drives.get(against, 0) > mine_drives.get(against, 0):
                total += oncoming
            if segment in parked:
                total += near_parked
            if avoid_held and fixed_near.get(segment, 0) > mine_fixed.get(segment, 0):
                total += held
            return total

        capability = fleet.vehicles[vehicle_id].type.turn_capability
        start = (last.segment, last.traverse, last.progress)
        estimate = straight_line_estimate(layout, task.goal_segment)
        path = shortest_route(layout, capability, start, task.goal_segment, task.goal_progress, cost, estimate)
        return None if path is None else legs_along(path, task, task.goal_progress)

    def _should_look_around(self, vehicle_id: int, fleet: FleetSnapshot) -> bool:
        """Only a vehicle standing at the end of what it may drive, and less often the longer it waits.

        The wait between looks doubles (up to ``max_replan_interval``) while looking finds nothing
        better: a vehicle queued behind others should not search the map every few seconds.
        """
        if fleet.vehicles[vehicle_id].speed > 0.0 or len(fleet.plans[vehicle_id].fixed_legs) > 1:
            self._next_look.pop(vehicle_id, None)  # moving again: start over with a short wait
            return False
        due, interval = self._next_look.get(vehicle_id, (fleet.time + self.replan_interval, self.replan_interval))
        if vehicle_id not in self._next_look:
            self._next_look[vehicle_id] = (due, interval)
        if fleet.time < due - 1e-9:
            return False
        interval = min(2.0 * interval, self.max_replan_interval)
        self._next_look[vehicle_id] = (fleet.time + interval, interval)
        return True

    # -- fixing --------------------------------------------------------------------------------------

    def _free(self, vehicle_id: int, leg: FleetLeg, layout: Layout) -> bool:
        """No other vehicle has a fixed leg that conflicts with this leg's segment."""
        assert self._index is not None
        return not self._index.others_fix_near(vehicle_id, leg.segment)

    def _clear(self, vehicle_id: int, leg: FleetLeg, layout: Layout) -> bool:
        """No other vehicle's plan comes near this leg's segment: a place to wait without blocking."""
        assert self._index is not None
        return not self._index.others_drive_near(vehicle_id, leg.segment)

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

