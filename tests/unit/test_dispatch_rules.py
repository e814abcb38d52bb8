"""The dispatcher's rules (fleetsim.dispatch.checks): each code triggered by an answer that breaks it, and a
narrowly different answer that does not; a refused answer is refused whole and the assignments stand."""

from __future__ import annotations

from collections.abc import Sequence

import pytest
from dispatch_support import ORDERS, Scripted, once, run, with_period

from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.planners import ReservingPlanner
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult


def codes(result: RunResult) -> list[str]:
    return [event.rejection.code.value for event in result.rejections]


def held(result: RunResult) -> dict[str, int | None]:
    return {order["id"]: order["vehicle"] for order in result.orders}


def test_an_accepted_answer_gives_each_vehicle_its_orders_and_both_are_completed() -> None:
    result = run(once(Assignment(1, ["a"]), Assignment(2, ["b"])))
    assert codes(result) == []
    by_id = {order["id"]: order for order in result.orders}
    assert by_id["a"]["vehicle"] == 1 and by_id["a"]["completed"] is not None
    assert by_id["b"]["vehicle"] == 2 and by_id["b"]["completed"] is not None
    assert by_id["a"]["served"][0] < by_id["a"]["served"][1]


@pytest.mark.parametrize(
    ("answer", "code"),
    [
        ((Assignment(9, ["a"]),), "assignment-unknown-vehicle"),
        ((Assignment(1, ["a"]), Assignment(1, ["b"])), "assignment-twice"),
        ((Assignment(1, ["nope"]),), "order-unknown"),
        ((Assignment(1, ["late"]),), "order-unreleased"),
        ((Assignment(1, ["a"]), Assignment(2, ["a"])), "order-twice"),
        ((Assignment(1, ["a", "a"]),), "order-twice"),
        ((Assignment(1, ["tug"]),), "order-vehicle-type"),
    ],
)
def test_an_answer_that_breaks_a_rule_is_refused_whole_with_its_code(answer: tuple[Assignment, ...], code: str) -> None:
    result = run(once(*answer, Assignment(2, ["b"])) if code != "assignment-twice" else once(*answer))
    assert code in codes(result)
    assert result.status == "failed" and any(f.kind == "rejection" for f in result.failures)
    # Refused whole: not even the assignments that broke no rule were applied.
    assert all(vehicle is None for vehicle in held(result).values())
    message = next(e.rejection.message for e in result.rejections if e.rejection.code.value == code)
    assert message.startswith("assignment for vehicle ")


@pytest.mark.parametrize(
    "answer",
    [
        (Assignment(2, ["a"]),),  # a vehicle the scenario has
        (Assignment(1, ["a"]), Assignment(2, ["b"])),  # one assignment per vehicle
        (Assignment(1, ["a", "b"]),),  # two orders, each once
        (Assignment(1, []),),  # nothing for a vehicle: allowed
    ],
)
def test_a_narrowly_different_answer_is_accepted(answer: tuple[Assignment, ...]) -> None:
    assert codes(run(once(*answer))) == []


def test_an_order_released_later_may_be_assigned_once_released() -> None:
    def script(board: OrderBoard) -> Sequence[Assignment]:
        return [Assignment(1, ["late"])] if "late" in board.orders and board.orders["late"].vehicle_id is None else []

    result = run(script, (ORDERS[2],))
    assert codes(result) == [] and held(result)["late"] == 1


def test_a_completed_order_is_refused_and_one_still_open_is_not() -> None:
    def script(board: OrderBoard) -> Sequence[Assignment]:
        if board.time == 0.0:
            return [Assignment(2, ["b"]), Assignment(1, ["a"])]
        if "b" not in board.orders:  # completed: naming it again is refused
            return [Assignment(2, ["b"])]
        return []

    # "late" stays open, unassigned, so the dispatcher is asked after "b" is completed.
    result = run(script, ORDERS[:3])
    assert "order-completed" in codes(result)
    assert "order-completed" not in codes(run(once(Assignment(2, ["b"])), ORDERS[:3]))


def test_an_order_may_be_taken_back_and_given_to_another_vehicle_until_its_first_stop() -> None:
    def script(board: OrderBoard) -> Sequence[Assignment]:
        if board.time == 0.0:
            return [Assignment(1, ["a"])]
        order = board.orders.get("a")
        if order is not None and order.vehicle_id == 1 and not order.started and board.time >= 2.0:
            return [Assignment(2, ["a"])]
        return []

    result = run_scenario(with_period(ORDERS[:1], 1.0), ReservingPlanner(), dispatcher=Scripted(script))
    assert codes(result) == []
    record = result.orders[0]
    assert record["vehicle"] == 2 and record["reassigned"] == 1 and record["completed"] is not None


def test_an_order_whose_vehicle_reached_its_first_stop_is_never_given_to_another() -> None:
    def script(board: OrderBoard) -> Sequence[Assignment]:
        if board.time == 0.0:
            return [Assignment(2, ["b"])]
        order = board.orders.get("b")
        if order is not None and order.started:
            return [Assignment(1, ["b"])]
        return []

    result = run_scenario(with_period(ORDERS[1:2], 1.0), ReservingPlanner(), dispatcher=Scripted(script))
    assert "order-started" in codes(result)
    assert result.orders[0]["vehicle"] == 2 and result.orders[0]["completed"] is not None
