"""Simulation (SPEC §8–10): the loop, the trace and its hash, run results and their judgement."""

from fleetsim.sim.divergence import Divergence, first_divergence
from fleetsim.sim.guard import PlannerFault, PlannerGuard
from fleetsim.sim.loop import RunProgress, run_scenario
from fleetsim.sim.result import AlertEvent, DeadlockReport, Failure, Metrics, RejectionEvent, RunResult
from fleetsim.sim.trace import TRACE_FORMAT, Trace

__all__ = [
    "TRACE_FORMAT",
    "AlertEvent",
    "DeadlockReport",
    "Divergence",
    "Failure",
    "Metrics",
    "PlannerFault",
    "PlannerGuard",
    "RejectionEvent",
    "RunProgress",
    "RunResult",
    "Trace",
    "first_divergence",
    "run_scenario",
]
