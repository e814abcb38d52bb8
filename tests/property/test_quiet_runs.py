"""Generated fleets, with stops and slow-downs drawn on top, run exactly the same whether the reference
planner's quiet hint is honoured (resting vehicles not asked) or ignored: the same trace line by line,
the same odometers, waiting times and ending (fleetsim/planning/quiet.py)."""

from __future__ import annotations

from disturbed_fleets import disturbed
from hypothesis import HealthCheck, given, settings

import fleetsim.sim.loop as loop
from fleetsim.planners import ReservingPlanner
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario


def _run(scenario: Scenario, quiet: bool) -> tuple[object, ...]:
    loop._Run.quiet = quiet
    try:
        result = run_scenario(scenario, ReservingPlanner(), keep_trace=True)
    finally:
        loop._Run.quiet = True
    assert result.trace is not None
    return result.trace.lines, dict(result.metrics.distance), dict(result.metrics.waiting_time), result.ended


@settings(
    max_examples=60,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(disturbed())
def test_runs_are_identical_with_the_quiet_hint_honoured_or_ignored(scenario: Scenario) -> None:
    assert _run(scenario, quiet=True) == _run(scenario, quiet=False)
