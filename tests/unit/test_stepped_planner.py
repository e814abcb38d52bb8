"""A planner with ``begin_step`` (fleetsim's VDA 5050 vehicles) is told of every step before its planning,
with every vehicle's state up to date; the messages it refused are rejections the run judges like any."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim.layout.layout import Layout
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import ReservingPlanner
from fleetsim.planning.checks import Rejection, RejectionCode
from fleetsim.planning.plans import Response
from fleetsim.planning.protocol import SteppedPlanner
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Scenario, Task
from fleetsim.sim import loop
from fleetsim.sim.loop import run_scenario

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"


def _crossing() -> Scenario:
    suite = load_suite(SUITES / "examples.fleetsim.yaml")
    return load_scenario(next(s for s in suite.scenarios if s.name == "crossing"), suite)


class Watching(ReservingPlanner):
    """ReservingPlanner that notes what each step's beginning and each call saw; refuses a message at 1 s."""

    def __init__(self, refuse_at: float | None = None, fail_at: float | None = None) -> None:
        super().__init__()
        self.refuse_at, self.fail_at = refuse_at, fail_at
        self.steps: list[tuple[float, dict[int, float]]] = []
        self.calls: list[tuple[float, dict[int, float]]] = []

    def begin_step(self, fleet: FleetSnapshot, layout: Layout) -> Sequence[Rejection]:
        self.steps.append((fleet.time, {v: s.distance for v, s in fleet.vehicles.items()}))
        if self.fail_at is not None and fleet.time >= self.fail_at:
            raise ValueError("the broker went away")
        if self.refuse_at is not None and abs(fleet.time - self.refuse_at) < 1e-9:
            return [Rejection(RejectionCode.ORDER_INVALID, 2, None, None, "nodes[1].sequenceId is 3, expected 2")]
        return []

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self.calls.append((fleet.time, {v: s.distance for v, s in fleet.vehicles.items()}))
        return super().plan_routes(task, fleet, layout)

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self.calls.append((fleet.time, {v: s.distance for v, s in fleet.vehicles.items()}))
        return super().fix_legs(task, fleet, layout)


@pytest.mark.parametrize("batched", [False, True])
def test_every_step_begins_with_the_fleet_as_the_planner_then_sees_it(batched: bool) -> None:
    planner = Watching()
    assert isinstance(planner, SteppedPlanner) and not isinstance(ReservingPlanner(), SteppedPlanner)
    loop._Run.batched = batched  # cruising vehicles stepped together: their states must still be current
    try:
        result = run_scenario(_crossing(), planner)
    finally:
        loop._Run.batched = None
    assert result.passed
    assert [round(t, 6) for t, _ in planner.steps] == [round(k * 0.1, 6) for k in range(result.steps)]
    at_step = dict(planner.steps)
    assert all(at_step[t] == seen for t, seen in planner.calls)  # what the step began with is what calls see
    assert any(d[1] > 0 for _, d in planner.steps)  # and it moves


def test_the_stepped_hook_changes_nothing_of_the_run() -> None:
    plain, watched = run_scenario(_crossing(), ReservingPlanner()), run_scenario(_crossing(), Watching())
    assert watched.trace_hash == plain.trace_hash and watched.steps == plain.steps


def test_a_refused_message_is_an_order_invalid_rejection_the_run_judges() -> None:
    result = run_scenario(_crossing(), Watching(refuse_at=1.0))
    assert not result.passed
    [event] = result.rejections
    assert event.rejection.code is RejectionCode.ORDER_INVALID and event.rejection.vehicle_id == 2
    assert event.time == pytest.approx(1.1)  # stamped with the end of its step, as every event
    assert result.ended == "rejection" and result.failures[0].kind == "rejection"  # stop_on's default ends it
    scenario = _crossing()
    going_on = replace(scenario.settings, stop_on=())
    expected = replace(scenario, settings=going_on, expect=replace(scenario.expect, rejections=("order-invalid",)))
    assert run_scenario(expected, Watching(refuse_at=1.0)).passed  # a suite may expect it and go on


def test_a_begin_step_that_raises_fails_the_run_as_a_planner_error() -> None:
    result = run_scenario(_crossing(), Watching(fail_at=0.5))
    assert result.ended == "planner-error"
    [failure] = result.failures
    assert failure.kind == "planner-error" and "begin_step raised ValueError: the broker went away" in failure.message
    assert "Traceback" in failure.details["traceback"]


class Idle(Watching):
    """Plans nothing, so the fleet stands until the deadlock timer ends the run; explains each wait."""

    def __init__(self, explain: bool = True, broken: bool = False) -> None:
        super().__init__()
        self.explain, self.broken = explain, broken

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return []

    def __getattr__(self, name: str) -> object:
        if name == "explain_wait" and self.explain:
            return self._explain
        raise AttributeError(name)

    def _explain(self, vehicle_id: int, now: float) -> str:
        if self.broken and vehicle_id == 2:
            raise KeyError(vehicle_id)
        return f"no order for vehicle {vehicle_id} by t = {now:.1f} s" if vehicle_id == 1 else ""


def test_a_stepped_planners_word_on_a_wait_ends_that_vehicles_finding_and_its_root_cause() -> None:
    result = run_scenario(_crossing(), Idle())
    assert result.ended == "deadlock" and result.diagnosis is not None
    first, second = result.diagnosis.findings
    said = f"no order for vehicle 1 by t = {result.diagnosis.time:.1f} s"  # asked when the run ended
    assert first.note == said and first.text().endswith("; " + said)
    assert first.to_dict()["note"] == first.note
    assert second.note == "" and "note" not in second.to_dict()  # an empty word adds nothing
    root = next(r for r in result.diagnosis.roots if r.vehicles == (1,))
    assert root.text().endswith("; " + said)


def test_a_planner_without_explain_wait_leaves_the_findings_as_they_were() -> None:
    result = run_scenario(_crossing(), Idle(explain=False))
    assert result.diagnosis is not None
    assert all(f.note == "" and "note" not in f.to_dict() for f in result.diagnosis.findings)


def test_an_explain_wait_that_raises_is_named_in_the_note_and_the_diagnosis_goes_on() -> None:
    result = run_scenario(_crossing(), Idle(broken=True))
    assert result.ended == "deadlock" and result.diagnosis is not None
    first, second = result.diagnosis.findings
    assert first.note.startswith("no order for vehicle 1")
    assert second.note == "(the planner's explain_wait raised KeyError: 2)"
