"""The dispatcher's optional hooks: ``wants_call()`` asks for a call this step (why ``"request"``, even with
no order open), and ``refused(rejections)`` is told the rules a refused answer broke."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from dispatch_support import ORDERS, scenario

from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.orders import Order, Stop
from fleetsim.planners import ReservingPlanner
from fleetsim.planning.checks import Rejection
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario


def _short(orders: tuple[Order, ...], seconds: float) -> Scenario:
    base = scenario(orders)
    return dataclasses.replace(base, settings=dataclasses.replace(base.settings, time_limit=seconds))


class Hooked:
    """Asks for a call at the steps (counted from 0) in ``wanted``; answers ``answers`` at its first calls."""

    def __init__(self, wanted: set[int], answers: Sequence[Sequence[Assignment]] = ()) -> None:
        self.wanted = wanted
        self.answers = list(answers)
        self.steps = 0
        self.boards: list[OrderBoard] = []
        self.told: list[list[Rejection]] = []

    def wants_call(self) -> bool:
        self.steps += 1
        return self.steps - 1 in self.wanted

    def dispatch(self, board: OrderBoard, fleet: object, layout: object) -> Sequence[Assignment]:
        self.boards.append(board)
        return self.answers.pop(0) if self.answers else []

    def refused(self, rejections: Sequence[Rejection]) -> None:
        self.told.append(list(rejections))


def test_a_dispatcher_that_wants_a_call_is_called_that_step_and_told_why() -> None:
    late = (Order("late", (Stop(4),), release=5.0),)
    hooked = Hooked({3, 7})
    run_scenario(_short(late, 8.0), ReservingPlanner(), dispatcher=hooked)
    # Steps 3 and 7 (t = 0.3 s, 0.7 s): asked with no order open; the release at 5 s asks it as before.
    assert [(round(b.time, 6), b.why, len(b.orders)) for b in hooked.boards[:3]] == [
        (0.3, ("request",), 0),
        (0.7, ("request",), 0),
        (5.0, ("release",), 1),
    ]
    assert hooked.steps == 80  # asked at every step


def test_a_dispatcher_without_the_hook_is_not_called_when_nothing_happens() -> None:
    late = (Order("late", (Stop(4),), release=5.0),)
    calls: list[OrderBoard] = []

    class Plain:
        def dispatch(self, board: OrderBoard, fleet: object, layout: object) -> Sequence[Assignment]:
            calls.append(board)
            return []

    run_scenario(_short(late, 8.0), ReservingPlanner(), dispatcher=Plain())
    assert [b.why for b in calls][:1] == [("release",)] and all("request" not in b.why for b in calls)


def test_a_refused_answer_is_told_to_the_dispatcher_and_an_accepted_one_is_not() -> None:
    hooked = Hooked({1}, answers=[[Assignment(1, ["tug"])], [Assignment(1, ["a"])]])
    result = run_scenario(_short(ORDERS, 2.0), ReservingPlanner(), dispatcher=hooked)
    [told] = hooked.told
    assert [r.code.value for r in told] == ["order-vehicle-type"]
    assert [r.rejection.code.value for r in result.rejections] == ["order-vehicle-type"]
    # The refused answer took nothing; the one asked for at step 1 was taken, and nothing was told.
    assert hooked.boards[1].why == ("request",) and hooked.boards[1].sequences[1] == ()
    assert [o["vehicle"] for o in result.orders if o["id"] == "a"] == [1]
