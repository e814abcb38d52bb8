"""Planning (SPEC §6–7): the planner protocol, plan checks, reservations and task bookkeeping."""

from fleetsim.planning.checks import CheckContext, Rejection, RejectionCode, check_plan, check_plans
from fleetsim.planning.controller import CallOutcome, FleetController, validate_response
from fleetsim.planning.plans import FleetLeg, FleetPlan, Response, ResponseItem, RouteError
from fleetsim.planning.protocol import Planner, QuietPlanner
from fleetsim.planning.quiet import Quiet
from fleetsim.planning.reservations import CollisionAlert, ConflictTable, find_alerts
from fleetsim.planning.snapshot import FleetSnapshot, VehicleState
from fleetsim.planning.tasks import TaskBook

__all__ = [
    "CallOutcome",
    "CheckContext",
    "CollisionAlert",
    "ConflictTable",
    "FleetController",
    "FleetLeg",
    "FleetPlan",
    "FleetSnapshot",
    "Planner",
    "Quiet",
    "QuietPlanner",
    "Rejection",
    "RejectionCode",
    "Response",
    "ResponseItem",
    "RouteError",
    "TaskBook",
    "VehicleState",
    "check_plan",
    "check_plans",
    "find_alerts",
    "validate_response",
]
