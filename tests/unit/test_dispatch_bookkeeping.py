"""The dispatch bookkeeping kept up to date by what changed (fleetsim.sim.dispatching, fleetsim.dispatch.book)
gives, step by step, what looking at every vehicle every step gives."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from functools import cache
from typing import Any

import pytest
from dispatch_support import run

from fleetsim import load_scenario, load_suite
from fleetsim.dispatch.book import OrderBook
from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.orders import Order, Stop
from fleetsim.planners import ReservingPlanner
from fleetsim.scenario import Scenario
from fleetsim.sim.dispatching import Dispatching
from fleetsim.sim.loop import run_scenario


@cache
def _warehouse_shift() -> Scenario:
    """The shipped warehouse's shift, ten minutes of it: dwells, idle vehicles and blocked ones."""
    suite = load_suite("scenario_suites/warehouse.fleetsim.yaml")
    shipped = load_scenario(next(s for s in suite.scenarios if s.name == "shift"), suite)
    assert shipped.shift is not None
    return dataclasses.replace(shipped, shift=dataclasses.replace(shipped.shift, duration=600.0, warmup=60.0))


@pytest.fixture
def every_vehicle_every_step(monkeypatch: pytest.MonkeyPatch) -> Iterator[dict[str, Any]]:
    """After each step's start, the idle vehicles and the standing seconds as counting every vehicle gives
    them (the bookkeeping before it was kept up to date by changes), beside what the run keeps."""
    seen: dict[str, Any] = {"steps": 0, "idle_sets": set(), "dwell": 0.0, "blocked": 0.0, "run": None}
    begin_step, count_standing = Dispatching.begin_step, Dispatching._count_standing

    def idle_now(self: Dispatching) -> frozenset[int]:
        heads = self.controller.tasks.heads()
        plans = self.controller.plans
        return frozenset(v for v in plans if v not in heads and not self.book.has_orders(v) and not self.is_dwelling(v))

    def counted(self: Dispatching, idle: frozenset[int]) -> None:  # before the dispatcher is asked
        assert idle == idle_now(self)
        for vehicle in self.controller.plans:
            if self.is_dwelling(vehicle):
                seen["dwell"] += self._dt
            elif vehicle not in idle and self.controller.state_of(vehicle).speed == 0.0:
                seen["blocked"] += self._dt
        count_standing(self, idle)

    def checked(self: Dispatching, step: int, now: float, stamp: float, events: list[list[Any]]) -> Any:
        refused = begin_step(self, step, now, stamp, events)
        idle = idle_now(self)  # after its answer, if it was asked
        assert idle == self._idle, f"step {step}: idle {sorted(idle)} but kept {sorted(self._idle)}"
        seen["steps"] += 1
        seen["idle_sets"].add(idle)
        seen["run"] = self
        return refused

    monkeypatch.setattr(Dispatching, "_count_standing", counted)
    monkeypatch.setattr(Dispatching, "begin_step", checked)
    yield seen


def test_idle_dwelling_and_blocked_vehicles_are_those_of_counting_every_vehicle_every_step(
    every_vehicle_every_step: dict[str, Any],
) -> None:
    result = run_scenario(_warehouse_shift(), ReservingPlanner())
    seen = every_vehicle_every_step
    assert seen["steps"] == result.steps and len(seen["idle_sets"]) > 5  # vehicles went idle and got work
    run: Dispatching = seen["run"]
    assert seen["dwell"] > 0.0 and seen["blocked"] > 0.0  # the shift has both, so both sums were compared
    assert (run.dwell_time, run.blocked_time) == (seen["dwell"], seen["blocked"])  # bit for bit


def test_orders_taken_back_and_given_again_leave_the_idle_vehicles_right(
    every_vehicle_every_step: dict[str, Any],
) -> None:
    calls: list[OrderBoard] = []

    def script(board: OrderBoard) -> list[Assignment]:
        calls.append(board)
        if len(calls) == 1:
            return [Assignment(1, ("a",))]
        if len(calls) == 2:  # b released: a goes to vehicle 2, b to vehicle 1
            return [Assignment(2, ("a",)), Assignment(1, ("b",))]
        return []

    orders = (Order("a", (Stop(7), Stop(2)), release=0.0), Order("b", (Stop(4),), release=5.0))
    result = run(script, orders)
    assert [o["reassigned"] for o in result.orders] == [1, 0] and [o["vehicle"] for o in result.orders] == [2, 1]
    assert result.tasks_completed == 3 and every_vehicle_every_step["steps"] == result.steps


def test_the_book_knows_which_vehicles_hold_orders_and_counts_each_change_of_a_sequence() -> None:
    book = OrderBook((), {1: "agv", 2: "agv"}, first_task_id=1)
    book.release(Order("a", (Stop(3),)), 0.0)
    book.release(Order("b", (Stop(4),)), 0.0)
    assert book.holding() == frozenset() and book.version == 0
    book.apply([Assignment(1, ("a", "b"))], 1.0)
    assert book.holding() == {1} and book.version == 1
    book.apply([Assignment(2, ("b",))], 2.0)  # taken from 1 and given to 2: both sequences change
    assert book.holding() == {1, 2} and book.version == 3
    assert book.served("a", 0, 3.0)  # its only stop: completed, vehicle 1 holds nothing now
    assert book.holding() == {2} and book.version == 4
    book.apply([Assignment(2, ())], 4.0)
    assert book.holding() == frozenset() and book.version == 5
