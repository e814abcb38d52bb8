"""A run with a switch of the simulation loop set for it alone (``_Run.batched``: cruising vehicles in
arrays; ``_Run.quiet``: a planner's quiet hint honoured), for tests that run a fleet two ways that must
give the same run, and what such runs are compared by."""

from __future__ import annotations

import fleetsim.sim.loop as loop
from fleetsim.planning.protocol import Planner
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult


def run_switched(scenario: Scenario, planner: Planner, **switches: bool | None) -> RunResult:
    """``scenario`` run by ``planner`` with its trace kept, the loop's ``switches`` set meanwhile."""
    saved = {name: getattr(loop._Run, name) for name in switches}
    for name, value in switches.items():
        setattr(loop._Run, name, value)
    try:
        result = run_scenario(scenario, planner, keep_trace=True)
    finally:
        for name, value in saved.items():
            setattr(loop._Run, name, value)
    assert result.trace is not None
    return result


def same_run(result: RunResult) -> tuple[object, ...]:
    """What two runs that must be the same are compared by: the trace line by line, odometers, waiting
    times and the ending."""
    assert result.trace is not None
    return result.trace.lines, dict(result.metrics.distance), dict(result.metrics.waiting_time), result.ended
