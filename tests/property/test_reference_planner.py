"""The reference planner finishes what is solvable: every generated scenario ends completed, safely.

Generated scenarios are solvable by construction (the vehicles could do their tasks one after another),
so a deadlock, a timeout, a collision alert or a rejection here is the planner's fault; and a planner
that keeps the reservation rule never lets two footprints touch, so a contact would be the rule's. In CI the
examples are derandomised, so a failure reproduces exactly; elsewhere every run hunts new ones.
"""

from __future__ import annotations

from dataclasses import replace

from hypothesis import HealthCheck, given, settings

from fleetsim.enums import TurnCapability
from fleetsim.planners import ReservingPlanner
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, VehicleType
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.report import failure_report
from fleetsim.strategies import GenerationSpec, scenarios

AGV = replace(DEFAULT_VEHICLE_TYPE, name="agv")
TUGGER = VehicleType("tugger", 1.4, 0.7, 0.5, 1.2, 0.4, TurnCapability.CURVE)
# Every layout kind, up to six vehicles of two types (one turns in place, one only follows curves).
SPEC = GenerationSpec(layout="any", size=(1, 4), vehicles=(1, 6), tasks=(1, 3), vehicle_types=(AGV, TUGGER))


@settings(
    max_examples=300,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(scenarios(SPEC))
def test_the_reference_planner_completes_every_generated_scenario_without_alerts_or_rejections(
    scenario: Scenario,
) -> None:
    result = run_scenario(scenario, ReservingPlanner(), keep_trace=False)
    story = failure_report(
        result,
        heading=f"{len(scenario.vehicles)} vehicles, {len(scenario.tasks)} tasks, {len(scenario.layout.segments)} segments",
    )
    assert result.ended == "completed", story
    assert (result.collisions, result.rejections) == ((), ()), story
    # The reservation rule's own guarantee, judged physically: no two footprints ever touch.
    assert result.contact is not None and result.contact.contacts == (), story
    assert result.metrics.clearance is None or result.metrics.clearance > 0, story
