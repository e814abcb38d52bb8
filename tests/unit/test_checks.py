"""Every check code of SPEC §7: a minimal plan that triggers it and a near miss that passes."""

from __future__ import annotations

from dataclasses import replace

import pytest

from fleetsim.enums import Direction, Progress, Shape, Traverse, TurnCapability
from fleetsim.layout import Segment, build_layout
from fleetsim.planning.checks import CheckContext, Rejection, RejectionCode, check_plan, check_plans
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Task

F, B = Traverse.FORWARD, Traverse.BACKWARD
FWD, REV = Progress.FORWARD, Progress.REVERSE
CURVE = replace(DEFAULT_VEHICLE_TYPE, name="tugger", turn_capability=TurnCapability.CURVE)
IN_PLACE = replace(DEFAULT_VEHICLE_TYPE, name="agv", turn_capability=TurnCapability.IN_PLACE)

# 1 and 2 continue smoothly at (4, 0); 3 turns a corner at (8, 0); 4 leaves (4, 0) back towards the west
# at 23° (a cusp after 1); 5 is one-way north; 6 stands apart.
SEGMENTS = (
    Segment(1, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (4.0, 0.0))),
    Segment(2, Shape.STRAIGHT, Direction.BOTH, ((4.0, 0.0), (8.0, 0.0))),
    Segment(3, Shape.STRAIGHT, Direction.BOTH, ((8.0, 0.0), (8.0, 4.0))),
    Segment(4, Shape.STRAIGHT, Direction.BOTH, ((4.0, 0.0), (0.5, 1.5))),
    Segment(5, Shape.STRAIGHT, Direction.FORWARD, ((8.0, 4.0), (8.0, 8.0))),
    Segment(6, Shape.STRAIGHT, Direction.BOTH, ((20.0, 0.0), (24.0, 0.0))),
)
LAYOUT = build_layout(SEGMENTS, vehicle_radius=0.3)
TASKS = {
    1: (Task(1, 1, goal_segment=2, goal_progress=FWD), Task(2, 1, goal_segment=4)),
    2: (Task(3, 2, goal_segment=6),),
}


def leg(
    segment: int, traverse: Traverse = F, progress: Progress = FWD, fixed: bool = False, goal: int | None = None
) -> FleetLeg:
    return FleetLeg(segment, traverse, progress, fixed, goal)


def context(
    current: tuple[FleetLeg, ...] = (leg(1, fixed=True),),
    capability: TurnCapability = TurnCapability.CURVE,
    routed: frozenset[int] = frozenset(),
) -> CheckContext:
    vehicle_type = CURVE if capability is TurnCapability.CURVE else IN_PLACE
    return CheckContext(
        layout=LAYOUT,
        vehicle_types={1: vehicle_type, 2: IN_PLACE},
        plans={1: FleetPlan(1, current), 2: FleetPlan(2, (leg(6, fixed=True),))},
        queues=TASKS,
        routed=routed,
    )


def check(*legs: FleetLeg, ctx: CheckContext | None = None) -> Rejection | None:
    return check_plan(FleetPlan(1, legs), ctx or context())


def assert_rejected(rejection: Rejection | None, code: RejectionCode, leg_index: int | None) -> Rejection:
    assert rejection is not None, f"expected {code.value}"
    assert (rejection.code, rejection.vehicle_id, rejection.leg_index) == (code, 1, leg_index), str(rejection)
    return rejection


# -- response-level codes ------------------------------------------------------------------------------


def test_plan_for_a_vehicle_not_in_the_scenario_is_rejected() -> None:
    [result] = check_plans([FleetPlan(9, (leg(1, fixed=True),))], context())
    assert isinstance(result, Rejection) and result.code is RejectionCode.UNKNOWN_VEHICLE
    assert "vehicle 9 is not in the scenario (vehicles: 1, 2)" in result.message


def test_plan_for_a_known_vehicle_is_not_an_unknown_vehicle() -> None:
    assert check_plans([FleetPlan(2, (leg(6, fixed=True),))], context()) == [FleetPlan(2, (leg(6, fixed=True),))]


def test_two_plans_for_one_vehicle_in_one_response_are_both_rejected() -> None:
    plans = [FleetPlan(1, (leg(1, fixed=True),)), FleetPlan(1, (leg(1, fixed=True), leg(2)))]
    results = check_plans(plans, context())
    assert [r.code for r in results if isinstance(r, Rejection)] == [RejectionCode.DUPLICATE_PLAN] * 2


def test_plans_for_two_different_vehicles_in_one_response_are_not_duplicates() -> None:
    plans = [FleetPlan(1, (leg(1, fixed=True), leg(2))), FleetPlan(2, (leg(6, fixed=True),))]
    assert check_plans(plans, context()) == plans


# -- sanity checks -------------------------------------------------------------------------------------


def test_plan_without_legs_is_rejected() -> None:
    assert_rejected(check(), RejectionCode.EMPTY_PLAN, None)


def test_plan_holding_just_the_current_leg_is_accepted() -> None:
    assert check(leg(1, fixed=True)) is None


def test_leg_on_a_segment_not_in_the_map_is_rejected() -> None:
    rejection = assert_rejected(check(leg(1, fixed=True), leg(99)), RejectionCode.UNKNOWN_SEGMENT, 1)
    assert rejection.segment == 99


def test_leg_on_an_existing_segment_is_not_unknown() -> None:
    assert check(leg(1, fixed=True), leg(2)) is None


def test_unfixing_a_fixed_leg_is_rejected() -> None:
    ctx = context(current=(leg(1, fixed=True), leg(2, fixed=True)))
    assert_rejected(check(leg(1, fixed=True), leg(2), ctx=ctx), RejectionCode.FIXED_LEGS_CHANGED, 1)


def test_changing_a_fixed_legs_progress_is_rejected() -> None:
    ctx = context(current=(leg(1, fixed=True),), capability=TurnCapability.IN_PLACE)
    assert_rejected(check(leg(1, progress=REV, fixed=True), ctx=ctx), RejectionCode.FIXED_LEGS_CHANGED, 0)


def test_dropping_fixed_legs_is_rejected() -> None:
    ctx = context(current=(leg(1, fixed=True), leg(2, fixed=True)))
    assert_rejected(check(leg(1, fixed=True), ctx=ctx), RejectionCode.FIXED_LEGS_CHANGED, None)


def test_keeping_fixed_legs_and_adding_a_goal_marker_to_one_is_accepted() -> None:
    ctx = context(current=(leg(1, fixed=True), leg(2, fixed=True)))
    assert check(leg(1, fixed=True), leg(2, fixed=True, goal=1), leg(2, B, REV), ctx=ctx) is None


def test_fixed_leg_after_a_planned_one_is_rejected() -> None:
    assert_rejected(check(leg(1, fixed=True), leg(2), leg(3, fixed=True)), RejectionCode.FIXED_NOT_CONTIGUOUS, 2)


def test_fixed_legs_forming_a_prefix_are_accepted() -> None:
    ctx = context(capability=TurnCapability.IN_PLACE)
    assert check(leg(1, fixed=True), leg(2, fixed=True), leg(3), ctx=ctx) is None


def test_consecutive_legs_that_do_not_meet_are_rejected() -> None:
    rejection = assert_rejected(check(leg(1, fixed=True), leg(6)), RejectionCode.NOT_CONNECTED, 1)
    assert "segment 1 driven forward does not lead to segment 6 driven forward" in rejection.message


def test_leg_entered_through_the_wrong_end_is_not_connected() -> None:
    assert_rejected(check(leg(1, fixed=True), leg(2, B)), RejectionCode.NOT_CONNECTED, 1)


def test_connected_legs_are_accepted() -> None:
    assert check(leg(1, fixed=True), leg(2)) is None


def test_one_way_segment_driven_backwards_is_rejected() -> None:
    ctx = context(current=(leg(5, fixed=True),))
    rejection = assert_rejected(check(leg(5, fixed=True), leg(5, B, REV), ctx=ctx), RejectionCode.WRONG_WAY, 1)
    assert "one-way forward" in rejection.message


def test_one_way_segment_driven_its_way_is_accepted() -> None:
    ctx = context(capability=TurnCapability.IN_PLACE)
    assert check(leg(1, fixed=True), leg(2), leg(3), leg(5), ctx=ctx) is None


def test_curve_vehicle_flipping_progress_at_a_smooth_joint_is_rejected() -> None:
    assert_rejected(check(leg(1, fixed=True), leg(2, progress=REV)), RejectionCode.ILLEGAL_PROGRESS_CHANGE, 1)


def test_curve_vehicle_keeping_progress_at_a_cusp_is_rejected() -> None:
    assert_rejected(check(leg(1, fixed=True), leg(4)), RejectionCode.ILLEGAL_PROGRESS_CHANGE, 1)


def test_curve_vehicle_flipping_progress_at_a_cusp_is_accepted() -> None:
    assert check(leg(1, fixed=True), leg(4, progress=REV)) is None


def test_curve_vehicle_taking_a_corner_is_rejected() -> None:
    rejection = assert_rejected(check(leg(1, fixed=True), leg(2), leg(3)), RejectionCode.ILLEGAL_PROGRESS_CHANGE, 2)
    assert "cannot turn in place" in rejection.message


def test_in_place_vehicle_may_take_a_corner_and_change_progress_anywhere() -> None:
    ctx = context(capability=TurnCapability.IN_PLACE)
    assert check(leg(1, fixed=True), leg(2, progress=REV), leg(3), ctx=ctx) is None


# -- task checks ---------------------------------------------------------------------------------------


def test_goal_marker_for_another_vehicles_task_is_rejected() -> None:
    rejection = assert_rejected(check(leg(1, fixed=True), leg(6, goal=3)), RejectionCode.GOAL_NOT_ASSIGNED, 1)
    assert "task 3" in rejection.message and "queued: 1, 2" in rejection.message


def test_goal_marker_for_an_own_task_is_assigned() -> None:
    assert check(leg(1, fixed=True), leg(2, goal=1)) is None


def test_goal_markers_out_of_queue_order_are_rejected() -> None:
    plan = (leg(1, fixed=True), leg(2), leg(2, B, REV), leg(4, progress=REV, goal=2))
    assert_rejected(check(*plan), RejectionCode.GOAL_ORDER, 3)


def test_goal_markers_in_queue_order_are_accepted() -> None:
    plan = (leg(1, fixed=True), leg(2, goal=1), leg(2, B, REV), leg(4, progress=REV, goal=2))
    assert check(*plan) is None


def test_dropping_the_marker_of_a_routed_task_is_rejected() -> None:
    rejection = assert_rejected(
        check(leg(1, fixed=True), leg(2), ctx=context(routed=frozenset({1}))), RejectionCode.GOAL_ORDER, None
    )
    assert "task 1, which is routed" in rejection.message


def test_keeping_the_marker_of_a_routed_task_is_accepted() -> None:
    assert check(leg(1, fixed=True), leg(2, goal=1), ctx=context(routed=frozenset({1}))) is None


def test_goal_marker_on_another_segment_than_the_tasks_goal_is_rejected() -> None:
    rejection = assert_rejected(check(leg(1, fixed=True, goal=1)), RejectionCode.GOAL_SEGMENT_MISMATCH, 0)
    assert "its goal is segment 2" in rejection.message


def test_goal_marker_on_the_tasks_goal_segment_is_accepted() -> None:
    assert check(leg(1, fixed=True), leg(2, goal=1)) is None


def test_arriving_with_the_wrong_progress_is_rejected() -> None:
    ctx = context(capability=TurnCapability.IN_PLACE)
    rejection = assert_rejected(
        check(leg(1, fixed=True), leg(2, progress=REV, goal=1), ctx=ctx), RejectionCode.GOAL_DIRECTION, 1
    )
    assert "requires arriving forward" in rejection.message


def test_arriving_with_the_required_progress_is_accepted() -> None:
    ctx = context(capability=TurnCapability.IN_PLACE)
    assert check(leg(1, fixed=True), leg(2, progress=FWD, goal=1), ctx=ctx) is None


def test_task_with_no_required_direction_accepts_either() -> None:
    plan = (leg(1, fixed=True), leg(2, goal=1), leg(2, B, REV), leg(4, progress=REV, goal=2))
    assert check(*plan) is None


# -- order and form ------------------------------------------------------------------------------------


def test_task_checks_run_before_sanity_checks() -> None:
    # Not connected (sanity) and a foreign goal marker (task): the task check reports.
    assert_rejected(check(leg(1, fixed=True), leg(6, goal=3)), RejectionCode.GOAL_NOT_ASSIGNED, 1)


def test_wrong_way_is_reported_rather_than_not_connected() -> None:
    ctx = context(capability=TurnCapability.IN_PLACE)
    assert_rejected(check(leg(1, fixed=True), leg(2), leg(3), leg(5, B), ctx=ctx), RejectionCode.WRONG_WAY, 3)


def test_rejection_reads_as_code_vehicle_leg_segment_and_message() -> None:
    rejection = check(leg(1, fixed=True), leg(99))
    where = "unknown-segment: vehicle 1, leg 1 (segment 99)"
    assert str(rejection) == f"{where}: segment 99 is not in the map (segments 1–6)"


def test_there_are_exactly_the_thirteen_codes_of_the_spec_the_vda5050_one_and_the_dispatchers() -> None:
    assert {code.value for code in RejectionCode} == {
        "unknown-vehicle",
        "duplicate-plan",
        "empty-plan",
        "unknown-segment",
        "fixed-legs-changed",
        "fixed-not-contiguous",
        "not-connected",
        "wrong-way",
        "illegal-progress-change",
        "goal-not-assigned",
        "goal-order",
        "goal-segment-mismatch",
        "goal-direction",
        "order-invalid",  # made by the VDA 5050 vehicles for a message no plan shows (issue 33)
        # The rules of a dispatcher's answers (issue 45), each also a test in test_dispatch_rules.py.
        "assignment-unknown-vehicle",
        "assignment-twice",
        "order-unknown",
        "order-unreleased",
        "order-completed",
        "order-twice",
        "order-started",
        "order-vehicle-type",
    }


@pytest.mark.parametrize("code", list(RejectionCode))
def test_every_code_is_the_string_a_suite_names(code: RejectionCode) -> None:
    assert code == code.value and str(code) == code.value
