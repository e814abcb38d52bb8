"""Generated fleets, with stops and slow-downs drawn on top, run exactly the same whether the cruising
vehicles are stepped together in arrays or each by its driver: the same trace line by line, the same
odometers and waiting times (motion/fleet_cruise.py)."""

from __future__ import annotations

from dataclasses import replace

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fleetsim.sim.loop as loop
from fleetsim.enums import TurnCapability
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Disturbance, Scenario, VehicleType
from fleetsim.sim.loop import run_scenario
from fleetsim.strategies import GenerationSpec, scenarios

AGV = replace(DEFAULT_VEHICLE_TYPE, name="agv")
TUGGER = VehicleType("tugger", 1.4, 0.7, 0.5, 1.2, 0.4, TurnCapability.CURVE)
SPEC = GenerationSpec(layout="any", size=(1, 4), vehicles=(1, 6), tasks=(1, 3), vehicle_types=(AGV, TUGGER))


@st.composite
def disturbed(draw: st.DrawFn) -> Scenario:
    scenario = draw(scenarios(SPEC))
    ids = sorted(v.id for v in scenario.vehicles)
    disturbances = []
    for _ in range(draw(st.integers(0, 3))):
        vehicle = draw(st.sampled_from(ids))
        at = draw(st.integers(0, 300)) / 10.0
        duration = draw(st.integers(1, 100)) / 10.0
        if draw(st.booleans()):
            disturbances.append(Disturbance(vehicle, "stop", duration, at=at))
        else:
            factor = draw(st.sampled_from([0.2, 0.5, 0.9]))
            disturbances.append(Disturbance(vehicle, "slow", duration, at=at, factor=factor))
    return replace(scenario, disturbances=tuple(disturbances))


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
