"""A faulty planner fails its own run with a ``planner-error`` and leaves the harness fit for the next run.

Faults: raising, returning something that is not a response, hanging (sleeping or spinning, even while
trying to swallow the timeout) and trying to change the read-only snapshot. After each one the per-call
timer is off, the SIGALRM handler is the one that was there before, and a good planner passes.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import Any

import pytest

import fleetsim
from fleetsim.planners import ReservingPlanner
from fleetsim.scenario import Scenario
from fleetsim.sim import RunResult, run_scenario

SUITE = fleetsim.load_suite(Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml")
CROSSING, NEXT = (fleetsim.load_scenario(spec, SUITE) for spec in SUITE.scenarios[:2])
TIMEOUT = 0.3


class Raising(ReservingPlanner):
    def plan_routes(self, task: Any, fleet: Any, layout: Any) -> Any:
        raise ValueError("the planner's own bug")


class RaisingInFixLegs(ReservingPlanner):
    def fix_legs(self, task: Any, fleet: Any, layout: Any) -> Any:
        raise KeyError("fix_legs bug")


class ReturnsString(ReservingPlanner):
    def plan_routes(self, task: Any, fleet: Any, layout: Any) -> Any:
        return "a plan, honestly"


class ReturnsDictItem(ReservingPlanner):
    def plan_routes(self, task: Any, fleet: Any, layout: Any) -> Any:
        return [{"vehicle_id": task.vehicle_id, "legs": []}]


class ReturnsNone(ReservingPlanner):
    def plan_routes(self, task: Any, fleet: Any, layout: Any) -> Any:
        return None


class Sleeps(ReservingPlanner):
    def plan_routes(self, task: Any, fleet: Any, layout: Any) -> Any:
        time.sleep(60)


class Spins(ReservingPlanner):
    def plan_routes(self, task: Any, fleet: Any, layout: Any) -> Any:
        turns = 0
        while True:  # the fault under test: a call that never returns
            turns += 1


class SwallowsEverything(ReservingPlanner):
    def plan_routes(self, task: Any, fleet: Any, layout: Any) -> Any:
        while True:
            try:
                time.sleep(60)
            except Exception:
                continue


class MutatesPlans(ReservingPlanner):
    def plan_routes(self, task: Any, fleet: Any, layout: Any) -> Any:
        fleet.plans[1] = fleet.plans[2]


class MutatesVehicleState(ReservingPlanner):
    def plan_routes(self, task: Any, fleet: Any, layout: Any) -> Any:
        fleet.vehicles[task.vehicle_id].speed = 10.0


class MutatesLayout(ReservingPlanner):
    def plan_routes(self, task: Any, fleet: Any, layout: Any) -> Any:
        del layout.segments[1]


def _sentinel(signum: int, frame: FrameType | None) -> None:  # pragma: no cover - must never fire
    raise AssertionError("a stray SIGALRM reached the harness")


@pytest.fixture(autouse=True)
def harness_unharmed() -> Iterator[None]:
    """Every test leaves no timer running and our own SIGALRM handler in place."""
    original = signal.signal(signal.SIGALRM, _sentinel)
    try:
        yield
        assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
        assert signal.getsignal(signal.SIGALRM) is _sentinel
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, original)


def run_faulty(planner: object, scenario: Scenario = CROSSING) -> RunResult:
    result = run_scenario(scenario, planner, planner_name=type(planner).__name__, planner_timeout=TIMEOUT)  # type: ignore[arg-type]
    assert result.status == "failed"
    assert [f.kind for f in result.failures] == ["planner-error"]
    assert result.ended == "planner-error"
    return result


def assert_next_run_passes() -> None:
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
    assert signal.getsignal(signal.SIGALRM) is _sentinel
    result = run_scenario(NEXT, ReservingPlanner(), planner_timeout=TIMEOUT)
    assert result.passed, [f.message for f in result.failures]


def test_a_raising_planner_fails_with_its_method_vehicle_and_traceback() -> None:
    failure = run_faulty(Raising()).failures[0]
    assert failure.message == "plan_routes() for vehicle 1 raised ValueError: the planner's own bug"
    assert failure.details["vehicle"] == 1
    traceback = failure.details["traceback"]
    assert 'raise ValueError("the planner\'s own bug")' in traceback
    assert "test_planner_faults.py" in traceback
    assert "fleetsim/sim/guard.py" not in traceback
    assert_next_run_passes()


def test_a_planner_raising_in_fix_legs_is_named_by_that_method() -> None:
    failure = run_faulty(RaisingInFixLegs()).failures[0]
    assert failure.message.startswith("fix_legs() for vehicle 1 raised KeyError")
    assert 'raise KeyError("fix_legs bug")' in failure.details["traceback"]
    assert_next_run_passes()


@pytest.mark.parametrize(
    ("planner", "shown"),
    [
        (ReturnsString(), "returned 'a plan, honestly'"),
        (ReturnsDictItem(), "returned item 0 = {'vehicle_id': 1, 'legs': []}"),
        (ReturnsNone(), "returned None"),
    ],
    ids=["string", "list-with-dict", "none"],
)
def test_a_planner_returning_something_else_than_a_response_fails_naming_the_value(planner: object, shown: str) -> None:
    failure = run_faulty(planner).failures[0]
    assert failure.message.startswith("plan_routes() for vehicle 1 ")
    assert failure.details == {"vehicle": 1}
    assert shown in failure.message
    assert (
        "must be a FleetPlan or a RouteError" in failure.message or "list of FleetPlan or RouteError" in failure.message
    )
    assert_next_run_passes()


@pytest.mark.parametrize(
    "planner", [Sleeps(), Spins(), SwallowsEverything()], ids=["sleeps", "spins", "swallows-exception"]
)
def test_a_hanging_planner_is_stopped_by_the_per_call_timeout(planner: object) -> None:
    started = time.monotonic()
    failure = run_faulty(planner).failures[0]
    assert time.monotonic() - started < 5.0
    assert failure.message == "plan_routes() for vehicle 1 did not return within the per-call timeout of 0.3 s"
    assert_next_run_passes()


@pytest.mark.parametrize(
    ("planner", "error"),
    [
        (MutatesPlans(), "item assignment"),
        (MutatesVehicleState(), "AttributeError"),
        (MutatesLayout(), "item deletion"),
    ],
    ids=["plans", "vehicle-state", "layout-segments"],
)
def test_a_planner_that_tries_to_change_what_it_was_given_fails(planner: object, error: str) -> None:
    failure = run_faulty(planner).failures[0]
    assert failure.message.startswith("plan_routes() for vehicle 1 raised")
    assert error in failure.message
    assert_next_run_passes()


def test_a_fault_leaves_the_scenario_reusable() -> None:
    run_faulty(Raising())
    assert run_scenario(CROSSING, ReservingPlanner()).passed


def test_a_timer_set_by_someone_else_survives_a_run() -> None:
    import signal

    from fleetsim.sim.guard import PlannerGuard

    fired: list[int] = []
    previous = signal.signal(signal.SIGALRM, lambda signum, frame: fired.append(signum))
    try:
        signal.setitimer(signal.ITIMER_REAL, 30.0)
        with PlannerGuard(timeout=1.0) as guard:
            assert guard.calls == 0
        delay, _ = signal.getitimer(signal.ITIMER_REAL)
        assert 29.0 < delay <= 30.0  # put back, less the (tiny) time the guard was active
        assert signal.getsignal(signal.SIGALRM) is not None and not fired
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
