"""The thesis's initial planner: breadth-first routes, three legs fixed at a time, blind to the fleet."""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

from mypy_extensions import mypyc_attr

from fleetsim.layout.layout import Layout
from fleetsim.planners.routing import breadth_first_route, legs_along, mark_goal_on_fixed
from fleetsim.planning.plans import FleetPlan, Response, RouteError
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Task

__all__ = ["BFSPlanner"]


# Users subclass the reference planners; the compiled build (fleetsim/compiled.py) must let them.
@mypyc_attr(allow_interpreted_subclasses=True)
class BFSPlanner:
    """Breadth-first route over the connection graph, honouring segment direction and progress rules.

    ``fix_legs`` fixes at most the first three legs of the plan. It ignores other vehicles and the
    task's goal direction, exactly like the thesis's ``InitialRoutePlanner``: it is meant to collide,
    so that suites can show what a caught planner bug looks like.
    """

    fix_horizon: ClassVar[int] = 3  # a class variable, so that a subclass may change it (compiled too)

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        vehicle_id = task.vehicle_id
        fixed = fleet.plans[vehicle_id].fixed_legs
        marked = mark_goal_on_fixed(fixed, task, check_progress=False)
        if marked is not None:
            return [FleetPlan(vehicle_id, marked)]
        last = fixed[-1]
        capability = fleet.vehicles[vehicle_id].type.turn_capability
        path = breadth_first_route(layout, capability, (last.segment, last.traverse, last.progress), task.goal_segment)
        if path is None:
            return [RouteError(vehicle_id, f"no route from segment {last.segment} to segment {task.goal_segment}")]
        return [FleetPlan(vehicle_id, (*fixed, *legs_along(path, task, None)))]

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        plan = fleet.plans[task.vehicle_id]
        legs = tuple(
            replace(leg, fixed=True) if index < self.fix_horizon else leg for index, leg in enumerate(plan.legs)
        )
        return [FleetPlan(plan.vehicle_id, legs)]
