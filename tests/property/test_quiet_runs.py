"""Generated fleets, with stops and slow-downs drawn on top, run exactly the same whether the reference
planner's quiet hint is honoured (resting vehicles not asked) or ignored: the same trace line by line,
the same odometers, waiting times and ending (fleetsim/planning/quiet.py)."""

from __future__ import annotations

from disturbed_fleets import disturbed
from hypothesis import HealthCheck, given, settings
from loop_switches import run_switched, same_run

from fleetsim.planners import ReservingPlanner
from fleetsim.scenario import Scenario


@settings(
    max_examples=60,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(disturbed())
def test_runs_are_identical_with_the_quiet_hint_honoured_or_ignored(scenario: Scenario) -> None:
    honoured = run_switched(scenario, ReservingPlanner(), quiet=True)
    assert same_run(honoured) == same_run(run_switched(scenario, ReservingPlanner(), quiet=False))
