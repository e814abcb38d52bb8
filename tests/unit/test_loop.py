"""The simulation loop end to end: outcomes, expectations, deadlock, determinism and the trace."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest
from result_document import RESULT_KEYS, schema_errors
from scenario_factory import make_scenario

import fleetsim.sim.loop as loop
from fleetsim import load_scenario, load_suite
from fleetsim.enums import Direction, Shape
from fleetsim.layout import Segment
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.scenario import Expectations, Scenario
from fleetsim.sim.divergence import first_divergence
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.trace import TRACE_FORMAT

SUITE = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"
EXAMPLES = [spec.name for spec in load_suite(SUITE).scenarios]


def example(name: str, **settings: object) -> Scenario:
    suite = load_suite(SUITE)
    scenario = load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)
    return replace(scenario, settings=replace(scenario.settings, **settings)) if settings else scenario


def corridor(tmp_path: Path, **settings: object) -> Scenario:
    """Three straights in a row, one vehicle at each end, each sent to the other end: head-on."""
    segments = tuple(
        Segment(i, Shape.STRAIGHT, Direction.BOTH, ((4.0 * i, 0.0), (4.0 * i + 4.0, 0.0))) for i in (1, 2, 3)
    )
    return make_scenario(tmp_path, segments, "1,1,forward,,\n2,3,backward,,\n", "1,3,\n2,1,\n", **settings)


@pytest.mark.parametrize("name", EXAMPLES)
def test_reserving_planner_passes_every_shipped_example(name: str) -> None:
    result = run_scenario(example(name), ReservingPlanner())
    assert result.status == "passed", [f.message for f in result.failures]
    assert (result.ended, result.tasks_completed, result.collisions, result.rejections) == (
        "completed",
        result.tasks_total,
        (),
        (),
    )
    assert result.metrics.makespan is not None and result.metrics.makespan <= result.sim_time


def test_bfs_planner_fails_the_crossing_with_a_collision() -> None:
    result = run_scenario(example("crossing"), BFSPlanner())
    assert (result.status, result.ended) == ("failed", "collision")
    assert {f.kind for f in result.failures} >= {"collision"}
    assert [c.alert.segment for c in result.collisions] == [2, 3, 6, 7]
    assert "COLLISION ALERT: Possible collision detected on segment '2'" in result.collisions[0].alert.text()


def test_head_on_with_bfs_planner_ends_in_a_collision(tmp_path: Path) -> None:
    result = run_scenario(corridor(tmp_path), BFSPlanner())
    assert (result.status, result.ended) == ("failed", "collision")


def test_head_on_with_reserving_planner_ends_in_a_reported_deadlock(tmp_path: Path) -> None:
    result = run_scenario(corridor(tmp_path, deadlock_after=3.0), ReservingPlanner())
    assert (result.status, result.ended) == ("failed", "deadlock")
    assert result.deadlock is not None and result.deadlock.cycle == (1, 2)
    [failure] = [f for f in result.failures if f.kind == "deadlock"]
    assert failure.message == "vehicles 1 and 2 wait for each other (1 -> 2 -> 1) over segments 1 and 3"
    # Each vehicle first drives its start segment to the end (it is fixed), then nothing moves for 3 s.
    assert failure.time == pytest.approx(6.0 + 3.0, abs=0.11)
    assert schema_errors(result.to_dict()) == []  # a deadlock and its findings, as the schema says


def test_an_expected_deadlock_passes(tmp_path: Path) -> None:
    scenario = replace(corridor(tmp_path, deadlock_after=3.0), expect=Expectations(tasks=0, deadlock=True))
    assert run_scenario(scenario, ReservingPlanner()).status == "passed"


def test_expected_deadlock_that_does_not_happen_fails() -> None:
    scenario = replace(example("crossing"), expect=Expectations(deadlock=True))
    result = run_scenario(scenario, ReservingPlanner())
    assert [f.kind for f in result.failures] == ["expectation"]


def test_time_limit_fails_with_the_pending_tasks_named() -> None:
    result = run_scenario(example("loop-one-way", time_limit=5.0), ReservingPlanner())
    assert (result.status, result.ended, result.sim_time) == ("failed", "time-limit", pytest.approx(5.0))
    [failure] = result.failures
    assert failure.kind == "timeout"
    assert "task 1 (vehicle 1 to segment 7)" in failure.message and "pending" in failure.message


def test_without_stop_on_the_run_goes_on_after_alerts() -> None:
    result = run_scenario(example("crossing", stop_on=()), BFSPlanner())
    assert result.ended == "completed" and result.tasks_completed == 2
    assert len(result.collisions) >= 4  # reported when they appear, not again each step they persist
    assert len({(c.alert.segment, c.time) for c in result.collisions}) == len(result.collisions)


def test_collision_expectations() -> None:
    cases = [
        (Expectations(tasks=0, collisions="any"), []),
        (Expectations(tasks=0, collisions=(2, 6)), []),
        (Expectations(tasks=0, collisions=(4,)), ["expectation"]),
        (Expectations(tasks=0), ["collision"] * 4),
    ]
    for expect, kinds in cases:
        result = run_scenario(replace(example("crossing"), expect=expect), BFSPlanner())
        assert [f.kind for f in result.failures] == kinds, expect


def test_makespan_bound() -> None:
    ok = run_scenario(replace(example("crossing"), expect=Expectations(max_makespan=60)), ReservingPlanner())
    tight = run_scenario(replace(example("crossing"), expect=Expectations(max_makespan=5)), ReservingPlanner())
    assert ok.status == "passed"
    assert [f.kind for f in tight.failures] == ["expectation"] and "exceeds max_makespan 5 s" in tight.failures[
        0
    ].message


class _WrongWay(ReservingPlanner):
    """Plans a leg onto a segment that is not connected: every plan is rejected."""

    def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
        current = fleet.plans[task.vehicle_id].fixed_legs
        return [
            FleetPlan(task.vehicle_id, (*current, FleetLeg(task.goal_segment, "backward", "forward", False, task.id)))
        ]


def test_rejections_fail_the_run_and_stop_it_by_default() -> None:
    result = run_scenario(example("crossing"), _WrongWay())
    assert (result.status, result.ended, result.steps) == ("failed", "rejection", 1)
    assert [r.rejection.code.value for r in result.rejections] == ["not-connected", "not-connected"]
    assert result.failures[0].kind == "rejection" and result.failures[0].details["code"] == "not-connected"


def test_required_rejection_codes_are_expectations() -> None:
    scenario = replace(example("crossing"), expect=Expectations(tasks=0, rejections=("not-connected",)))
    assert run_scenario(scenario, _WrongWay()).status == "passed"
    scenario = replace(example("crossing"), expect=Expectations(tasks=0, rejections=("wrong-way",)))
    assert [f.kind for f in run_scenario(scenario, _WrongWay()).failures] == ["expectation"]


def test_planning_period_consults_the_planner_less_often(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(loop._Run, "quiet", False)  # every vehicle asked in every planning round
    every_step = run_scenario(example("crossing"), ReservingPlanner())
    every_second = run_scenario(example("crossing", planning_period=1.0), ReservingPlanner())
    assert every_second.status == "passed"
    assert every_second.metrics.planner_calls * 5 < every_step.metrics.planner_calls


def test_the_same_run_gives_the_same_trace_and_hash() -> None:
    first, second = (run_scenario(example("corridor-passing-bay"), ReservingPlanner()) for _ in range(2))
    assert first.trace_hash == second.trace_hash
    assert first.trace is not None and second.trace is not None
    assert first.trace.lines == second.trace.lines
    assert json.loads(first.trace.lines[0])["format"] == TRACE_FORMAT
    assert first_divergence(first.trace.lines, second.trace.lines, 0.1) is None


class _Hastier(BFSPlanner):
    fix_horizon = 4  # the one-line behaviour change


def test_a_one_line_planner_change_changes_the_hash_and_the_divergence_is_located() -> None:
    base = run_scenario(example("loop-one-way", stop_on=()), BFSPlanner())
    changed = run_scenario(example("loop-one-way", stop_on=()), _Hastier())
    assert base.trace_hash != changed.trace_hash
    assert base.trace is not None and changed.trace is not None
    divergence = first_divergence(base.trace.lines, changed.trace.lines, 0.1)
    assert divergence is not None and divergence.step == 1  # step 0 routes, step 1 fixes legs
    assert "vehicle 1's plan, leg " in str(divergence) and "t = 0.20 s" in str(divergence)
    assert "[[" not in str(divergence)  # in words, not the trace's encoding


def test_metrics_and_the_json_form() -> None:
    result = run_scenario(example("corridor-passing-bay"), ReservingPlanner())
    data = json.loads(json.dumps(result.to_dict()))
    assert set(data) >= RESULT_KEYS
    assert schema_errors(data) == []
    assert data["planner"] == "ReservingPlanner" and data["tasks"] == {"total": 2, "completed": 2}
    metrics = data["metrics"]
    assert metrics["distance"]["1"] == pytest.approx(36.0, abs=0.01)  # the corridor's main line end to end
    assert metrics["distance"]["2"] > 32.5  # 18 m to -14 m through the passing bay, longer than straight
    assert metrics["planner_calls"] > 0 and 0 <= metrics["harness_share"] <= 1


def test_waiting_time_counts_standing_still_with_tasks_pending() -> None:
    waiting = run_scenario(example("crossing"), ReservingPlanner()).metrics.waiting_time
    assert waiting[1] == 0.0  # vehicle 1 crosses first
    assert waiting[2] > 5.0  # vehicle 2 waits at the junction until vehicle 1 has passed
