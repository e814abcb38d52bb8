"""The planner protocol (SPEC §6): immutable legs and plans, route errors, the Planner shape."""

from __future__ import annotations

import dataclasses
import re

import pytest

from fleetsim import FleetsimError
from fleetsim.enums import Progress, Traverse
from fleetsim.planning import FleetLeg, FleetPlan, Planner, RouteError


def _leg(segment: int, fixed: bool = True) -> FleetLeg:
    return FleetLeg(segment, Traverse.FORWARD, Progress.FORWARD, fixed)


def test_leg_accepts_enum_members_or_their_string_values() -> None:
    by_string = FleetLeg(3, "backward", "reverse", True, goal_for_task=2)  # type: ignore[arg-type]
    assert by_string.traverse is Traverse.BACKWARD
    assert by_string.progress is Progress.REVERSE
    assert by_string == FleetLeg(3, Traverse.BACKWARD, Progress.REVERSE, True, goal_for_task=2)


@pytest.mark.parametrize(
    ("traverse", "progress", "message"),
    [
        ("sideways", "forward", "traverse='sideways' must be 'forward' or 'backward'"),
        ("forward", "backward", "progress='backward' must be 'forward' or 'reverse'"),
        ("FORWARD", "forward", "traverse='FORWARD' must be 'forward' or 'backward'"),
        ("forward", None, "progress=None must be 'forward' or 'reverse'"),
    ],
)
def test_leg_rejects_a_bad_enum_value_naming_the_field_and_the_choices(
    traverse: object, progress: object, message: str
) -> None:
    with pytest.raises(ValueError, match=f"^{re.escape(message)}$"):
        FleetLeg(1, traverse, progress, True)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"segment": True}, "segment=True must be an int"),
        ({"segment": "3"}, "segment='3' must be an int"),
        ({"segment": 3.0}, "segment=3.0 must be an int"),
        ({"goal_for_task": False}, "goal_for_task=False must be an int"),
        ({"fixed": 1}, "fixed=1 must be True or False"),
    ],
)
def test_leg_rejects_bool_or_non_int_ids_and_a_non_bool_fixed_flag(kwargs: dict[str, object], message: str) -> None:
    fields: dict[str, object] = {"segment": 3, "traverse": "forward", "progress": "forward", "fixed": True}
    with pytest.raises(TypeError, match=f"^{re.escape(message)}$"):
        FleetLeg(**{**fields, **kwargs})  # type: ignore[arg-type]


def test_plan_freezes_a_list_of_legs_into_a_tuple() -> None:
    legs = [_leg(1), _leg(2, fixed=False)]
    plan = FleetPlan(4, legs)  # type: ignore[arg-type]
    legs.append(_leg(3))
    assert plan.legs == (_leg(1), _leg(2, fixed=False))
    assert plan == FleetPlan(4, (_leg(1), _leg(2, fixed=False)))
    assert hash(plan) == hash(FleetPlan(4, (_leg(1), _leg(2, fixed=False))))


@pytest.mark.parametrize(
    ("vehicle_id", "legs", "message"),
    [
        (1, [_leg(1), "2 forward"], "legs[1]='2 forward' must be a FleetLeg"),
        (1, "legs", "legs='legs' must be a sequence of FleetLeg"),
        (1, {_leg(1)}, "must be a sequence of FleetLeg"),
        (True, [_leg(1)], "vehicle_id=True must be an int"),
    ],
)
def test_plan_rejects_items_that_are_not_legs_and_a_bool_vehicle_id(
    vehicle_id: object, legs: object, message: str
) -> None:
    with pytest.raises(TypeError, match=re.escape(message)):
        FleetPlan(vehicle_id, legs)  # type: ignore[arg-type]


def test_legs_and_plans_are_frozen() -> None:
    leg = _leg(1)
    plan = FleetPlan(1, (leg,))
    with pytest.raises(dataclasses.FrozenInstanceError):
        leg.fixed = False  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        plan.legs = ()  # type: ignore[misc]
    with pytest.raises(AttributeError):
        plan.legs.append(leg)  # type: ignore[attr-defined]


def test_fixed_legs_are_the_plans_committed_prefix() -> None:
    assert FleetPlan(1, (_leg(1), _leg(2), _leg(3, False), _leg(4, False))).fixed_legs == (_leg(1), _leg(2))
    assert FleetPlan(1, (_leg(1), _leg(2))).fixed_legs == (_leg(1), _leg(2))
    assert FleetPlan(1, (_leg(1, False), _leg(2))).fixed_legs == ()
    assert FleetPlan(1, ()).fixed_legs == ()


def test_same_drive_ignores_the_fixed_flag_and_goal_marker() -> None:
    leg = FleetLeg(5, Traverse.BACKWARD, Progress.REVERSE, True)
    assert leg.same_drive(FleetLeg(5, Traverse.BACKWARD, Progress.REVERSE, False, goal_for_task=1))
    assert not leg.same_drive(FleetLeg(5, Traverse.FORWARD, Progress.REVERSE, True))
    assert not leg.same_drive(FleetLeg(5, Traverse.BACKWARD, Progress.FORWARD, True))


def test_legs_and_plans_read_as_text() -> None:
    plan = FleetPlan(2, (FleetLeg(5, Traverse.BACKWARD, Progress.REVERSE, True), _leg(6, False)))
    goal = FleetLeg(7, Traverse.FORWARD, Progress.FORWARD, False, goal_for_task=3)
    assert str(plan) == "vehicle 2: 5 backward reverse fixed, 6 forward forward planned"
    assert str(goal) == "7 forward forward planned goal of task 3"


def test_route_error_is_an_exception_that_compares_by_vehicle_and_message() -> None:
    error = RouteError(3, "no route to segment 9")
    assert isinstance(error, Exception) and isinstance(error, FleetsimError)
    assert error == RouteError(3, "no route to segment 9")
    assert hash(error) == hash(RouteError(3, "no route to segment 9"))
    assert error != RouteError(4, "no route to segment 9")
    assert error != RouteError(3, "no route")
    assert error != "no route to segment 9"
    assert (error.vehicle_id, error.message) == (3, "no route to segment 9")


def test_route_error_says_whom_it_is_about() -> None:
    assert str(RouteError(3, "no route")) == "route error (vehicle 3): no route"
    assert str(RouteError(None, "map too large")) == "route error (request): map too large"
    assert repr(RouteError(3, "no route")) == "RouteError(vehicle_id=3, message='no route')"
    with pytest.raises(RouteError, match="no route"):
        raise RouteError(3, "no route")


class BothMethods:
    def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
        return []

    def fix_legs(self, task, fleet, layout):  # type: ignore[no-untyped-def]
        return []


class OnlyPlanRoutes:
    def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
        return []


def test_any_object_with_both_methods_is_a_planner() -> None:
    assert isinstance(BothMethods(), Planner)
    assert not isinstance(OnlyPlanRoutes(), Planner)
    assert not isinstance(object(), Planner)
