"""Generated fleets, with stops and slow-downs drawn on top, run exactly the same whether the cruising
vehicles are stepped together in arrays or each by its driver: the same trace line by line, the same
odometers and waiting times (motion/fleet_cruise.py)."""

from __future__ import annotations

from disturbed_fleets import disturbed
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from loop_switches import run_switched, same_run

from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.scenario import Scenario


@settings(
    max_examples=60,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(disturbed(), st.sampled_from(["reserving", "bfs"]))
def test_batched_and_one_by_one_runs_are_identical(scenario: Scenario, planner: str) -> None:
    make = ReservingPlanner if planner == "reserving" else BFSPlanner
    batched = run_switched(scenario, make(), batched=True)
    assert same_run(batched) == same_run(run_switched(scenario, make(), batched=False))
