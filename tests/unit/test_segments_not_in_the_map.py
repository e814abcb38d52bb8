"""A segment the map does not have is named as such whichever check rejects the plan, and a scenario
made in code with a task or vehicle on one is refused before any run (issue: reports that say where the
trouble is, point 7). The first failing check still gives the code."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim.enums import Progress, Traverse, TurnCapability
from fleetsim.errors import ScenarioError
from fleetsim.layout.segment_ids import id_runs, not_in_map, segment_ids
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.planning.checks import CheckContext, Rejection, RejectionCode, check_plan
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Scenario, Task, Vehicle
from fleetsim.sim.loop import run_scenario
from tests.unit.test_checks import TASKS, context, leg

CROSSING = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples" / "crossing"
MISSING = "segment 99, which is not in the map (segments 1–6)"  # LAYOUT has segments 1 to 6
NOT_IN_MAP = "not in the map"


def rejected(*legs: FleetLeg, ctx: CheckContext | None = None) -> Rejection:
    rejection = check_plan(FleetPlan(1, legs), ctx or context())
    assert rejection is not None
    return rejection


# -- the words ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("ids", "text"),
    [
        ([3, 1, 2, 4], "1–4"),
        ([1, 2, 3, 5, 7, 8, 12], "1–3, 5, 7, 8, 12"),
        (range(1, 200, 2), "1, 3, 5, 7, 9, ..., 199 (100 ids)"),
        ([42], "42"),
    ],
)
def test_ids_read_as_runs_and_a_long_list_is_cut_short(ids: list[int], text: str) -> None:
    assert id_runs(ids) == text


def test_a_missing_segment_is_named_with_the_segments_the_map_has() -> None:
    assert not_in_map(999, range(1, 43)) == "segment 999, which is not in the map (segments 1–42)"
    assert segment_ids([7]) == "segment 7"
    assert segment_ids([]) == "no segments"


# -- a plan leg on a segment the map lacks, whichever check fires first ---------------------------


def test_a_goal_marker_on_a_missing_segment_is_a_mismatch_that_says_the_segment_does_not_exist() -> None:
    rejection = rejected(leg(1, fixed=True), leg(99, goal=1))
    assert rejection.code is RejectionCode.GOAL_SEGMENT_MISMATCH  # the first failing check's code
    assert rejection.message == (
        f"marks the goal of task 1 on segment 99, but its goal is segment 2; besides, leg 1 names {MISSING}"
    )


def test_a_goal_marker_on_an_existing_wrong_segment_does_not_say_not_in_the_map() -> None:
    rejection = rejected(leg(1, fixed=True), leg(2), leg(3, goal=1))
    assert rejection.code is RejectionCode.GOAL_SEGMENT_MISMATCH
    assert NOT_IN_MAP not in rejection.message


def test_a_foreign_goal_marker_before_a_missing_segment_says_both() -> None:
    rejection = rejected(leg(1, fixed=True), leg(2, goal=3), leg(99))
    assert rejection.code is RejectionCode.GOAL_NOT_ASSIGNED
    assert rejection.message.endswith(f"; besides, leg 2 names {MISSING}")
    narrow = rejected(leg(1, fixed=True), leg(2, goal=3), leg(3))
    assert narrow.code is RejectionCode.GOAL_NOT_ASSIGNED and NOT_IN_MAP not in narrow.message


def test_goal_markers_out_of_order_with_missing_segments_name_each_leg() -> None:
    rejection = rejected(leg(1, fixed=True), leg(99), leg(4, goal=2), leg(98))
    assert rejection.code is RejectionCode.GOAL_ORDER
    assert rejection.message.endswith(
        "; besides, legs 1, 3 name segments 99, 98, which are not in the map (segments 1–6)"
    )


def test_a_task_whose_goal_is_missing_is_named_by_the_check_that_fires() -> None:
    # Checks made directly (CheckContext is public) with a queue no scenario would accept.
    queues = {**TASKS, 1: (Task(1, 1, goal_segment=99, goal_progress=Progress.FORWARD),)}
    ctx = replace(context(), queues=queues)
    mismatch = rejected(leg(1, fixed=True), leg(2, goal=1), ctx=ctx)
    assert mismatch.code is RejectionCode.GOAL_SEGMENT_MISMATCH
    assert mismatch.message == f"marks the goal of task 1 on segment 2, but its goal is {MISSING}"
    direction = rejected(leg(1, fixed=True), leg(99, progress=Progress.REVERSE, goal=1), ctx=ctx)
    assert direction.code is RejectionCode.GOAL_DIRECTION
    assert direction.message.endswith(f"; besides, leg 1 names {MISSING}")


def test_unknown_segment_itself_lists_the_segments_of_the_map() -> None:
    rejection = rejected(leg(1, fixed=True), leg(99))
    assert rejection.code is RejectionCode.UNKNOWN_SEGMENT
    assert rejection.message == "segment 99 is not in the map (segments 1–6)"  # said once, not twice


def test_checks_after_unknown_segment_never_see_a_missing_segment() -> None:
    # fixed-legs-changed and not-connected come after unknown-segment (SPEC §7): the code is unknown-segment.
    assert rejected(leg(99, fixed=True)).code is RejectionCode.UNKNOWN_SEGMENT
    ctx = context(capability=TurnCapability.IN_PLACE)
    assert rejected(leg(1, fixed=True), leg(99), leg(3), ctx=ctx).code is RejectionCode.UNKNOWN_SEGMENT


# -- through a run ---------------------------------------------------------------------------------


class _MarksTheGoalOnSegment:
    """Plans the vehicle's current leg, then a leg on ``segment`` marked as the head task's goal."""

    def __init__(self, segment: int) -> None:
        self.segment = segment

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: object) -> list[FleetPlan]:
        current = fleet.plans[task.vehicle_id].legs[0]
        goal = FleetLeg(self.segment, Traverse.FORWARD, Progress.FORWARD, False, task.id)
        return [FleetPlan(task.vehicle_id, (current, goal))]

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: object) -> list[FleetPlan]:
        return []


def test_a_run_reports_a_planners_goal_on_a_missing_segment_as_not_in_the_map() -> None:
    scenario = load_scenario_dir(CROSSING)
    stop_at_first = replace(scenario.settings, stop_on=("rejection",))
    result = run_scenario(replace(scenario, settings=stop_at_first), _MarksTheGoalOnSegment(999))
    event = result.rejections[0]  # vehicle 1's; vehicle 2's plan is rejected in the same step
    assert event.rejection.code is RejectionCode.GOAL_SEGMENT_MISMATCH
    assert "segment 999, which is not in the map (segments 1–8)" in str(event.rejection)
    assert "segment 999, which is not in the map" in result.failures[0].message
    existing = run_scenario(replace(scenario, settings=stop_at_first), _MarksTheGoalOnSegment(3))
    assert existing.rejections[0].rejection.code is RejectionCode.GOAL_SEGMENT_MISMATCH
    assert NOT_IN_MAP not in str(existing.rejections[0].rejection)


# -- a scenario made in code ----------------------------------------------------------------------


def test_a_scenario_made_with_a_task_on_a_missing_segment_is_refused_naming_task_and_segment() -> None:
    scenario = load_scenario_dir(CROSSING)
    with pytest.raises(ScenarioError) as caught:
        replace(scenario, tasks=(scenario.tasks[0], Task(2, 2, 999)))
    assert isinstance(caught.value, ValueError)
    assert str(caught.value) == (
        "scenario 'crossing': task 2 of vehicle 2 has its goal on segment 999, which is not in the map (segments 1–8)"
    )
    assert caught.value.problems == (
        "task 2 of vehicle 2 has its goal on segment 999, which is not in the map (segments 1–8)",
    )


def test_a_scenario_made_with_a_vehicle_on_a_missing_segment_or_a_task_for_no_vehicle_is_refused() -> None:
    scenario = load_scenario_dir(CROSSING)
    lost = Vehicle(3, 77, Traverse.FORWARD, Progress.FORWARD, scenario.vehicles[0].type)
    with pytest.raises(ScenarioError) as caught:
        Scenario("made", scenario.layout, scenario.vehicle_types, (*scenario.vehicles, lost), (Task(1, 9, 2),))
    assert caught.value.problems == (
        "vehicle 3 starts on segment 77, which is not in the map (segments 1–8)",
        "task 1 is for vehicle 9, which is not in the scenario (vehicles: 1, 2, 3)",
    )


def test_a_scenario_made_with_tasks_on_existing_segments_is_accepted() -> None:
    scenario = load_scenario_dir(CROSSING)
    made = Scenario("made", scenario.layout, scenario.vehicle_types, scenario.vehicles, (Task(1, 1, 8), Task(2, 2, 4)))
    assert [task.goal_segment for task in made.tasks] == [8, 4]
