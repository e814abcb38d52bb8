"""Runs with transport orders: dwell, the trace and its hash, a planner that dispatches too, and a
dispatcher that raises, hangs, answers garbage or is missing (the planner guard's treatment)."""

from __future__ import annotations

import dataclasses
import json
import os
import signal
import time
from collections.abc import Sequence
from pathlib import Path

import pytest
from dispatch_support import ORDERS, FirstIdle, Scripted, once, scenario

from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.orders import Order, Shift, Stop
from fleetsim.planners import ReservingPlanner
from fleetsim.sim.interrupt import StopSignals
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result_schema import result_problem
from fleetsim.sim.trace_schema import trace_problem

DWELLING = (Order("a", (Stop(7, dwell=4.0), Stop(2)), release=0.0), Order("b", (Stop(2),), release=6.0))


def test_a_vehicle_dwells_at_a_stop_before_it_drives_on() -> None:
    result = run_scenario(scenario(DWELLING), ReservingPlanner(), dispatcher=FirstIdle())
    a = next(order for order in result.orders if order["id"] == "a")
    assert a["served"][0] >= a["started"] + 4.0  # it stood at least its dwell (from rest) at the first stop
    assert a["completed"] is not None and result.status == "passed"
    # Standing there, it did not move: its distance grew by nothing between arrival and the dwell's end.
    assert result.trace is not None
    steps = [json.loads(line) for line in result.trace.lines[1:]]
    first, last = round(a["served"][0] * 10) - 40, round(a["served"][0] * 10) - 1
    moved = [vehicle for step in steps[first:last] for vehicle in step[1] if vehicle[0] == 1]
    assert moved == []


def test_a_shorter_dwell_serves_the_stop_sooner() -> None:
    short = (dataclasses.replace(DWELLING[0], stops=(Stop(7, dwell=1.0), Stop(2))), DWELLING[1])
    long_run = run_scenario(scenario(DWELLING), ReservingPlanner(), dispatcher=FirstIdle())
    short_run = run_scenario(scenario(short), ReservingPlanner(), dispatcher=FirstIdle())
    assert short_run.orders[0]["served"][0] < long_run.orders[0]["served"][0]


def test_releases_assignments_and_services_are_in_the_trace_and_its_hash() -> None:
    first = run_scenario(scenario(DWELLING), ReservingPlanner(), dispatcher=FirstIdle())
    again = run_scenario(scenario(DWELLING), ReservingPlanner(), dispatcher=FirstIdle())
    assert first.trace_hash == again.trace_hash
    assert first.trace is not None
    assert trace_problem(list(first.trace.lines)) is None
    assert result_problem(first.to_dict()) is None
    kinds = {event[0] for line in first.trace.lines[1:] for event in json.loads(line)[3]}
    assert {"release", "assign", "served", "order-done", "complete"} <= kinds
    assert json.loads(first.trace.lines[0])["orders"]["orders"][0][0] == "a"
    # Another dwell is another behaviour, and another hash.
    other = (dataclasses.replace(DWELLING[0], stops=(Stop(7, dwell=5.0), Stop(2))), DWELLING[1])
    assert run_scenario(scenario(other), ReservingPlanner(), dispatcher=FirstIdle()).trace_hash != first.trace_hash


class DispatchingPlanner(ReservingPlanner):
    """One object, both jobs."""

    def dispatch(self, board: OrderBoard, fleet: object, layout: object) -> list[Assignment]:
        return FirstIdle().dispatch(board, fleet, layout)


def test_a_planner_with_a_dispatch_method_is_the_dispatcher_too() -> None:
    result = run_scenario(scenario(DWELLING), DispatchingPlanner())
    assert result.status == "passed" and all(order["completed"] is not None for order in result.orders)


def test_a_scenario_with_orders_and_no_dispatcher_fails_with_a_sentence() -> None:
    result = run_scenario(scenario(DWELLING), ReservingPlanner())
    assert result.status == "failed" and result.ended == "planner-error"
    assert "has transport orders but no dispatcher" in result.failures[0].message
    assert "--dispatcher" in result.failures[0].message


def _raises(board: OrderBoard) -> Sequence[Assignment]:
    raise ValueError("no idea")


def _hangs(board: OrderBoard) -> Sequence[Assignment]:
    time.sleep(5)
    return []


@pytest.mark.parametrize(
    ("script", "words"),
    [
        (_raises, "dispatch() raised ValueError: no idea"),
        (lambda board: {"vehicle": 1}, "dispatch() returned {'vehicle': 1}; it must return a list of Assignment"),
        (lambda board: [(1, ["a"])], "each item must be an Assignment(vehicle_id, orders)"),
        (lambda board: [Assignment(1, [3])], "with orders=(3,); it must be a list of order ids (str)"),
        (lambda board: [Assignment("1", ["a"])], "with vehicle_id='1'; it must be an int"),  # type: ignore[arg-type]
    ],
)
def test_a_faulty_dispatcher_fails_its_run_with_a_clear_message(script: object, words: str) -> None:
    result = run_scenario(scenario(DWELLING), ReservingPlanner(), dispatcher=Scripted(script))  # type: ignore[arg-type]
    assert result.status == "failed" and result.ended == "planner-error"
    assert words in result.failures[0].message


def test_a_dispatcher_that_hangs_is_stopped_by_the_per_call_timeout() -> None:
    result = run_scenario(scenario(DWELLING), ReservingPlanner(), dispatcher=Scripted(_hangs), planner_timeout=0.5)
    assert result.ended == "planner-error"
    assert "dispatch() did not return within the per-call timeout of 0.5 s" in result.failures[0].message


def test_a_refused_answer_leaves_the_assignments_in_force() -> None:
    def script(board: OrderBoard) -> Sequence[Assignment]:
        if board.time == 0.0:
            return [Assignment(1, ["a"])]
        return [Assignment(1, ["b"]), Assignment(9, ["a"])]  # refused whole (no vehicle 9)

    result = run_scenario(
        dataclasses.replace(scenario(ORDERS[:2]), shift=Shift(duration=60.0, dispatch_period=5.0)),
        ReservingPlanner(),
        dispatcher=Scripted(script),
    )
    assert "assignment-unknown-vehicle" in [e.rejection.code.value for e in result.rejections]
    by_id = {order["id"]: order for order in result.orders}
    assert by_id["a"]["vehicle"] == 1 and by_id["b"]["vehicle"] is None


def test_a_shift_ends_at_its_duration_as_a_normal_end() -> None:
    result = run_scenario(
        dataclasses.replace(scenario(ORDERS[:2]), shift=Shift(duration=20.0)),
        ReservingPlanner(),
        dispatcher=Scripted(once(Assignment(1, ["a"]))),
    )
    assert result.ended == "shift-end" and result.sim_time == pytest.approx(20.0)
    assert not any(f.kind == "timeout" for f in result.failures)


def test_orders_left_open_at_the_time_limit_fail_the_run_as_a_timeout() -> None:
    result = run_scenario(scenario(ORDERS[:2]), ReservingPlanner(), dispatcher=Scripted(once(Assignment(1, ["a"]))))
    timeout = next(f for f in result.failures if f.kind == "timeout")
    assert "orders open: 'b'" in timeout.message


def test_the_dispatcher_a_scenario_names_is_made_fresh_for_each_run() -> None:
    named = dataclasses.replace(scenario(DWELLING), dispatcher="dispatch_support:FirstIdle")
    first, again = (run_scenario(named, ReservingPlanner()) for _ in range(2))
    assert first.status == "passed" and first.trace_hash == again.trace_hash
    assert first.trace_hash == run_scenario(scenario(DWELLING), ReservingPlanner(), dispatcher=FirstIdle()).trace_hash


@pytest.mark.parametrize(
    ("spec", "words"),
    [
        ("no_such_module:X", "dispatcher spec 'no_such_module:X': no module named 'no_such_module'"),
        (
            "dispatch_support:Nope",
            "dispatcher spec 'dispatch_support:Nope': 'dispatch_support' has no attribute 'Nope'",
        ),
        ("dispatch_support:ORDERS", "which is not callable; it must be a dispatcher class"),
        ("dispatch_support:Scenario", "class Scenario has no dispatch method"),
        ("FirstIdle", "dispatcher spec 'FirstIdle' must look like module:attribute, e.g. fleetsim.dispatchers:"),
    ],
)
def test_a_bad_dispatcher_spec_fails_the_run_with_a_sentence(spec: str, words: str) -> None:
    result = run_scenario(dataclasses.replace(scenario(DWELLING), dispatcher=spec), ReservingPlanner())
    assert result.ended == "planner-error" and words in result.failures[0].message


class StopsAt:
    """FirstIdle, that sends this process SIGTERM when asked at or after ``at`` seconds."""

    def __init__(self, at: float) -> None:
        self.at = at

    def dispatch(self, board: OrderBoard, fleet: object, layout: object) -> list[Assignment]:
        if board.time >= self.at:
            os.kill(os.getpid(), signal.SIGTERM)
        return FirstIdle().dispatch(board, fleet, layout)


def test_an_interrupted_shift_keeps_the_orders_done_so_far_in_its_result_and_trace(tmp_path: Path) -> None:
    orders = (*DWELLING, Order("late", (Stop(4),), release=70.0))
    run = dataclasses.replace(scenario(orders), shift=Shift(duration=600.0))
    trace = tmp_path / "trace.jsonl"
    with StopSignals() as stop:
        result = run_scenario(run, ReservingPlanner(), dispatcher=StopsAt(70.0), stop=stop, trace_file=trace)
    assert result.ended == "interrupted" and 60.0 < result.sim_time < 80.0
    done = [order["id"] for order in result.orders if order["completed"] is not None]
    assert done and result.measures is not None and result.measures.completed == len(done)
    assert [order["id"] for order in result.orders] == ["a", "b", "late"]  # every order released so far
    written = trace.read_text(encoding="ascii").splitlines()
    events = [event for line in written[1:] for event in json.loads(line)[3]]
    assert [event[1] for event in events if event[0] == "order-done"] == done
    assert ["release", "late"] in events and ["interrupted", "SIGTERM"] in events
