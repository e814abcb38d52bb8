"""Generated fleets, with stops and slow-downs drawn on top, run exactly the same whether the cruising
vehicles are stepped together in arrays or each by its driver: the same trace line by line, the same
odometers and waiting times (motion/fleet_cruise.py)."""

from __future__ import annotations

from disturbed_fleets import disturbed
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fleetsim.sim.loop as loop
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario


def _run(scenario: Scenario, planner: ReservingPlanner | BFSPlanner, batched: bool) -> tuple[object, ...]:
    loop._Run.batched = batched
    try:
        result = run_scenario(scenario, planner, keep_trace=True)
    finally:
        loop._Run.batched = None
    assert result.trace is not None
    return result.trace.lines, dict(result.metrics.distance), dict(result.metrics.waiting_time), result.ended


@settings(
    max_examples=60,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(disturbed(), st.sampled_from(["reserving", "bfs"]))
def test_batched_and_one_by_one_runs_are_identical(scenario: Scenario, planner: str) -> None:
    make = ReservingPlanner if planner == "reserving" else BFSPlanner
    assert _run(scenario, make(), batched=True) == _run(scenario, make(), batched=False)
