"""The fleet controller (SPEC §9 steps 1–2): which method it calls, what it applies, what it refuses."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from fleetsim.enums import Direction, Progress, Shape, Traverse
from fleetsim.errors import FleetsimError, PlannerError
from fleetsim.layout import Layout, Segment, build_layout
from fleetsim.planning import FleetController, FleetLeg, FleetPlan, FleetSnapshot, RejectionCode, Response, RouteError
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, Task, Vehicle


def _straight(sid: int, start: tuple[float, float], end: tuple[float, float]) -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, (start, end))


# Two lanes 1 → 2 → 3 and 11 → 12 → 13, ten metres apart, and a lone segment 21 for an idle vehicle.
LAYOUT = build_layout(
    [
        *(_straight(sid, (4.0 * k, 0.0), (4.0 * k + 4.0, 0.0)) for k, sid in enumerate((1, 2, 3))),
        *(_straight(sid, (4.0 * k, 10.0), (4.0 * k + 4.0, 10.0)) for k, sid in enumerate((11, 12, 13))),
        _straight(21, (0.0, 20.0), (4.0, 20.0)),
    ],
    vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius,
)
START = {1: 1, 2: 11, 3: 21}


def _controller(*tasks: Task) -> FleetController:
    vehicles = tuple(
        Vehicle(vid, segment, Traverse.FORWARD, Progress.FORWARD, DEFAULT_VEHICLE_TYPE)
        for vid, segment in START.items()
    )
    types = {DEFAULT_VEHICLE_TYPE.name: DEFAULT_VEHICLE_TYPE}
    return FleetController(Scenario("controller", LAYOUT, types, vehicles, tasks))


def _leg(segment: int, fixed: bool = False, goal: int | None = None) -> FleetLeg:
    return FleetLeg(segment, Traverse.FORWARD, Progress.FORWARD, fixed, goal_for_task=goal)


def _plan(vehicle_id: int, *legs: FleetLeg) -> FleetPlan:
    return FleetPlan(vehicle_id, legs)


Answer = Callable[[Task, FleetSnapshot], Any]  # Any: some tests answer with what is not a response


class Scripted:
    """Answers ``plan_routes`` and ``fix_legs`` from given functions and records every call."""

    def __init__(self, plan_routes: Answer | None = None, fix_legs: Answer | None = None) -> None:
        self._answers = {"plan_routes": plan_routes, "fix_legs": fix_legs}
        self.calls: list[tuple[str, int, int]] = []  # (method, vehicle, task)
        self.seen: list[FleetSnapshot] = []

    def _answer(self, method: str, task: Task, fleet: FleetSnapshot) -> Any:
        self.calls.append((method, task.vehicle_id, task.id))
        self.seen.append(fleet)
        answer = self._answers[method]
        if answer is None:
            pytest.fail(f"unexpected call to {method}() for task {task.id}")
        return answer(task, fleet)

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return self._answer("plan_routes", task, fleet)

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return self._answer("fix_legs", task, fleet)


ROUTE_1 = _plan(1, _leg(1, fixed=True), _leg(2), _leg(3, goal=1))  # task 1: vehicle 1 to segment 3
FIXED_1 = _plan(1, _leg(1, fixed=True), _leg(2, fixed=True), _leg(3, goal=1))


def _raise(error: Exception) -> Answer:
    def answer(task: Task, fleet: FleetSnapshot) -> Any:
        raise error

    return answer


def test_an_unrouted_head_task_is_given_to_plan_routes_and_its_plan_applied() -> None:
    controller = _controller(Task(1, 1, 3))
    planner = Scripted(plan_routes=lambda task, fleet: [ROUTE_1])
    outcome = controller.consult(planner, 1, 0.0)
    assert outcome is not None
    assert (outcome.vehicle_id, outcome.method, outcome.task) == (1, "plan_routes", Task(1, 1, 3))
    assert (outcome.accepted, outcome.rejections, outcome.route_errors, outcome.completed) == ((ROUTE_1,), (), (), ())
    assert controller.plans[1] == ROUTE_1
    assert controller.tasks.is_routed(1)


def test_a_routed_head_task_is_given_to_fix_legs() -> None:
    controller = _controller(Task(1, 1, 3))
    planner = Scripted(plan_routes=lambda task, fleet: [ROUTE_1], fix_legs=lambda task, fleet: [FIXED_1])
    controller.consult(planner, 1, 0.0)
    outcome = controller.consult(planner, 1, 0.1)
    assert outcome is not None and (outcome.method, outcome.accepted) == ("fix_legs", (FIXED_1,))
    assert planner.calls == [("plan_routes", 1, 1), ("fix_legs", 1, 1)]
    assert controller.plans[1] == FIXED_1


def test_the_planner_sees_the_fleet_as_it_is_at_the_call() -> None:
    controller = _controller(Task(1, 1, 3))
    planner = Scripted(plan_routes=lambda task, fleet: [ROUTE_1], fix_legs=lambda task, fleet: [])
    controller.consult(planner, 1, 0.0)
    controller.consult(planner, 1, 0.7)
    first, second = planner.seen
    assert (first.time, second.time) == (0.0, 0.7)
    assert first.plans[1] == _plan(1, _leg(1, fixed=True))
    assert second.plans[1] == ROUTE_1
    assert second.routed_tasks(1) == (Task(1, 1, 3),)


def test_a_raised_route_error_fails_the_whole_request() -> None:
    controller = _controller(Task(1, 1, 3))
    error = RouteError(None, "the planner has no map")
    outcome = controller.consult(Scripted(plan_routes=_raise(error)), 1, 0.0)
    assert outcome is not None
    assert (outcome.accepted, outcome.rejections, outcome.route_errors) == ((), (), (error,))
    assert controller.plans[1] == _plan(1, _leg(1, fixed=True))
    assert not controller.tasks.is_routed(1)


def test_a_returned_route_error_is_reported_and_the_other_items_applied() -> None:
    controller = _controller(Task(1, 1, 3), Task(2, 2, 13))
    other = _plan(2, _leg(11, fixed=True), _leg(12))
    planner = Scripted(plan_routes=lambda task, fleet: [RouteError(1, "segment 3 is blocked"), other])
    outcome = controller.consult(planner, 1, 0.0)
    assert outcome is not None
    assert outcome.route_errors == (RouteError(1, "segment 3 is blocked"),)
    assert outcome.accepted == (other,)
    assert controller.plans[1] == _plan(1, _leg(1, fixed=True))
    assert controller.plans[2] == other


def test_other_exceptions_from_the_planner_propagate() -> None:
    controller = _controller(Task(1, 1, 3))
    with pytest.raises(ZeroDivisionError):
        controller.consult(Scripted(plan_routes=_raise(ZeroDivisionError("oops"))), 1, 0.0)


@pytest.mark.parametrize(
    ("response", "message"),
    [
        (None, "plan_routes() for vehicle 1 returned None; it must return a list of FleetPlan or RouteError items"),
        (ROUTE_1, "plan_routes() for vehicle 1 returned FleetPlan(vehicle_id=1, legs=("),
        ("plan", "plan_routes() for vehicle 1 returned 'plan'; it must return a list"),
        ({1: ROUTE_1}, "plan_routes() for vehicle 1 returned {1: FleetPlan("),
        (
            [ROUTE_1, "3 forward"],
            "plan_routes() for vehicle 1 returned item 1 = '3 forward'; each item must be a FleetPlan or a RouteError",
        ),
        ([ROUTE_1, None], "plan_routes() for vehicle 1 returned item 1 = None; each item must be"),
    ],
)
def test_a_response_that_is_not_a_list_of_plans_and_route_errors_is_a_planner_error(
    response: object, message: str
) -> None:
    controller = _controller(Task(1, 1, 3))
    with pytest.raises(PlannerError) as caught:
        controller.consult(Scripted(plan_routes=lambda task, fleet: response), 1, 0.0)
    assert str(caught.value).startswith(message)
    assert caught.value.vehicle_id == 1
    assert isinstance(caught.value, FleetsimError) and isinstance(caught.value, TypeError)
    assert controller.plans[1] == _plan(1, _leg(1, fixed=True))  # nothing of a bad response is applied


def test_a_bad_fix_legs_response_names_fix_legs_and_the_vehicle() -> None:
    controller = _controller(Task(1, 1, 3))
    planner = Scripted(plan_routes=lambda task, fleet: [ROUTE_1], fix_legs=lambda task, fleet: (FIXED_1, 7))
    controller.consult(planner, 1, 0.0)
    with pytest.raises(PlannerError, match=r"^fix_legs\(\) for vehicle 1 returned item 1 = 7; "):
        controller.consult(planner, 1, 0.1)


def test_a_rejected_plan_leaves_the_old_plan_in_force() -> None:
    controller = _controller(Task(1, 1, 3))
    dropping_a_fixed_leg = _plan(1, _leg(1, fixed=True), _leg(2), _leg(3, goal=1))
    planner = Scripted(plan_routes=lambda task, fleet: [FIXED_1], fix_legs=lambda task, fleet: [dropping_a_fixed_leg])
    controller.consult(planner, 1, 0.0)
    outcome = controller.consult(planner, 1, 0.1)
    assert outcome is not None and outcome.accepted == ()
    assert [(r.code, r.vehicle_id, r.leg_index) for r in outcome.rejections] == [
        (RejectionCode.FIXED_LEGS_CHANGED, 1, 1)
    ]
    assert controller.plans[1] == FIXED_1


def test_a_rejected_first_plan_leaves_the_task_unrouted() -> None:
    controller = _controller(Task(1, 1, 3))
    skipping_segment_2 = _plan(1, _leg(1, fixed=True), _leg(3, goal=1))
    outcome = controller.consult(Scripted(plan_routes=lambda task, fleet: [skipping_segment_2]), 1, 0.0)
    assert outcome is not None and [r.code for r in outcome.rejections] == [RejectionCode.NOT_CONNECTED]
    assert controller.plans[1] == _plan(1, _leg(1, fixed=True))
    assert not controller.tasks.is_routed(1)


def test_a_plan_marking_the_leg_the_vehicle_is_on_completes_the_task_at_once() -> None:
    controller = _controller(Task(1, 1, 1), Task(2, 1, 3))
    here = _plan(1, _leg(1, fixed=True, goal=1))
    onwards = _plan(1, _leg(1, fixed=True), _leg(2), _leg(3, goal=2))
    answers = iter([[here], [onwards]])
    planner = Scripted(plan_routes=lambda task, fleet: next(answers))
    (outcome,) = controller.planning_round(planner, 0.0)
    assert outcome.completed == (1,)
    assert controller.tasks.completed() == {1: 0.0}
    assert controller.tasks.head(1) == Task(1, 1, 1)  # it leaves the queue at the next bookkeeping
    (outcome,) = controller.planning_round(planner, 0.1)
    assert (outcome.task, outcome.method, outcome.accepted) == (Task(2, 1, 3), "plan_routes", (onwards,))
    assert planner.seen[1].tasks[1] == (Task(2, 1, 3),)
    assert planner.seen[1].plans[1] == _plan(1, _leg(1, fixed=True))  # the completed task's marker is gone


def test_a_vehicle_whose_last_task_is_done_is_not_consulted_again() -> None:
    controller = _controller(Task(1, 1, 1))
    planner = Scripted(plan_routes=lambda task, fleet: [_plan(1, _leg(1, fixed=True, goal=1))])
    controller.planning_round(planner, 0.0)
    assert controller.planning_round(planner, 0.1) == ()
    assert controller.consult(planner, 1, 0.2) is None
    assert planner.calls == [("plan_routes", 1, 1)]
    assert controller.tasks.all_done()


def test_plans_for_two_vehicles_in_one_response_are_both_applied() -> None:
    controller = _controller(Task(1, 1, 3), Task(2, 2, 13))
    second = _plan(2, _leg(11, fixed=True), _leg(12, fixed=True))
    outcome = controller.consult(Scripted(plan_routes=lambda task, fleet: [ROUTE_1, second]), 1, 0.0)
    assert outcome is not None and outcome.accepted == (ROUTE_1, second)
    assert dict(controller.plans) == {1: ROUTE_1, 2: second, 3: _plan(3, _leg(21, fixed=True))}
    assert controller.tasks.routed == {1}


def test_a_planning_round_consults_busy_vehicles_by_ascending_id_and_skips_idle_ones() -> None:
    controller = _controller(Task(1, 2, 13), Task(2, 1, 3))  # vehicle 3 has no task
    route_2 = _plan(2, _leg(11, fixed=True), _leg(12), _leg(13, goal=1))
    route_1 = _plan(1, _leg(1, fixed=True), _leg(2), _leg(3, goal=2))
    planner = Scripted(plan_routes=lambda task, fleet: [route_1 if task.vehicle_id == 1 else route_2])
    outcomes = controller.planning_round(planner, 0.0)
    assert planner.calls == [("plan_routes", 1, 2), ("plan_routes", 2, 1)]
    assert [outcome.vehicle_id for outcome in outcomes] == [1, 2]
    assert controller.consult(planner, 3, 0.0) is None
    assert len(planner.calls) == 2


def test_later_calls_in_a_round_see_plans_applied_earlier_in_it() -> None:
    controller = _controller(Task(1, 1, 3), Task(2, 2, 13))
    route_2 = _plan(2, _leg(11, fixed=True), _leg(12), _leg(13, goal=2))
    planner = Scripted(plan_routes=lambda task, fleet: [ROUTE_1] if task.vehicle_id == 1 else [route_2])
    controller.planning_round(planner, 0.0)
    assert planner.seen[1].plans[1] == ROUTE_1
    assert planner.seen[1].routed == {1}


def test_alerts_report_the_plans_in_force() -> None:
    controller = _controller()
    assert controller.alerts() == ()
    controller.set_plan(_plan(2, _leg(11, fixed=True), _leg(12, fixed=True)))
    controller.set_plan(_plan(1, _leg(2, fixed=True)))
    assert controller.alerts() == ()  # the lanes are 10 m apart
    controller.set_plan(_plan(2, _leg(1, fixed=True)))
    assert [(alert.segment, alert.primary, alert.secondary) for alert in controller.alerts()] == [
        (1, (2,), (1,)),
        (2, (1,), (2,)),
    ]
