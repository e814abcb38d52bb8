"""A planner that is safe only while vehicles are on time: it fixes each leg a few seconds before the
vehicle's predicted arrival on it (predicted when the route was planned, at max speed), whoever else
holds it then. A delayed vehicle still holds its legs when the others' fixing times come."""

from __future__ import annotations

from dataclasses import replace

from fleetsim.layout.layout import Layout
from fleetsim.planners import BFSPlanner
from fleetsim.planning.plans import FleetPlan, Response
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Task


class OnTimePlanner:
    lead = 4.0  # seconds before the predicted arrival a leg is fixed

    def __init__(self) -> None:
        self.arrivals: dict[int, dict[int, float]] = {}  # vehicle -> segment -> predicted arrival

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        response = BFSPlanner().plan_routes(task, fleet, layout)
        for plan in response:
            if isinstance(plan, FleetPlan):
                state = fleet.vehicles[plan.vehicle_id]
                vmax, a = state.type.max_speed, state.type.acceleration
                at, ahead = fleet.time + vmax / (2 * a), -state.distance
                arrivals = self.arrivals.setdefault(plan.vehicle_id, {})
                for leg in plan.legs:
                    arrivals[leg.segment] = at + max(ahead, 0.0) / vmax
                    ahead += layout.segments[leg.segment].length
        return response

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        plan = fleet.plans[task.vehicle_id]
        arrivals = self.arrivals.get(task.vehicle_id, {})
        legs = list(plan.legs)
        for index, leg in enumerate(legs):
            if not leg.fixed:
                if arrivals.get(leg.segment, 0.0) > fleet.time + self.lead:
                    break
                legs[index] = replace(leg, fixed=True)
        return [FleetPlan(plan.vehicle_id, tuple(legs))] if legs != list(plan.legs) else []
