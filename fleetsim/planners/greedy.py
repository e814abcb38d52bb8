"""A planner without any coordination: it shows what a stuck fleet looks like, as BFSPlanner shows a collision."""

from __future__ import annotations

from dataclasses import replace

from mypy_extensions import mypyc_attr

from fleetsim.layout.layout import Layout
from fleetsim.planners.bfs import BFSPlanner
from fleetsim.planning.plans import FleetPlan, Response
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Task

__all__ = ["GreedyPlanner"]


# Users subclass the reference planners; the compiled build (fleetsim/compiled.py) must let them.
@mypyc_attr(allow_interpreted_subclasses=True)
class GreedyPlanner(BFSPlanner):
    """BFSPlanner's routes (fewest legs), each next leg fixed as soon as no other vehicle's fixed legs
    conflict with it: never an alert, and helpless when vehicles wait for each other (head-on in a
    corridor, round a block, behind a vehicle that has finished its work). Meant for seeing deadlocks."""

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        plan = fleet.plans[task.vehicle_id]
        index = len(plan.fixed_legs)
        if index >= len(plan.legs):
            return []
        held = {leg.segment for vid, other in fleet.plans.items() if vid != task.vehicle_id for leg in other.fixed_legs}
        if layout.conflicts(plan.legs[index].segment) & held:
            return []
        legs = tuple(replace(leg, fixed=True) if i == index else leg for i, leg in enumerate(plan.legs))
        return [FleetPlan(task.vehicle_id, legs)]
