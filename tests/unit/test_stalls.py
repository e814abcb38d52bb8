"""A shift's stalls: a vehicle with work that stands for ``stall_after`` seconds is found once, explained
with the orders held up; one that waits less, dwells at a stop or has no work is not; ``on_stall: end``
ends the run at the first."""

from __future__ import annotations

import dataclasses

import pytest
from dispatch_support import FirstIdle, scenario

from fleetsim.layout.layout import Layout
from fleetsim.orders import Order, Shift, Stop
from fleetsim.planners import ReservingPlanner
from fleetsim.planning.plans import Response
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Task
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult
from fleetsim.sim.result_schema import result_problem

ORDERS = (Order("a", (Stop(7),), release=0.0), Order("b", (Stop(2),), release=0.0))


class Ignores2(ReservingPlanner):
    """Never plans for vehicle 2: with its order, it stands."""

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return [] if task.vehicle_id == 2 else super().plan_routes(task, fleet, layout)


def run(shift: Shift, planner: ReservingPlanner | None = None, orders: tuple[Order, ...] = ORDERS) -> RunResult:
    return run_scenario(
        dataclasses.replace(scenario(orders), shift=shift), planner or Ignores2(), dispatcher=FirstIdle()
    )


def test_a_vehicle_with_work_that_stands_for_stall_after_seconds_is_a_stall_explained() -> None:
    result = run(Shift(duration=30.0, stall_after=5.0))
    assert [(s.vehicle, s.orders) for s in result.stalls] == [(2, ("b",))]
    stall = result.stalls[0]
    # It drives its start leg to its end (every plan begins fixed with it), then stands: looked for every
    # simulated second, it is found within a second of standing five.
    assert 5.0 <= stall.time - stall.since < 6.0 and stall.since > 0.0
    assert "vehicle 2 has work and has not moved for" in stall.message() and "orders held up: b" in stall.message()
    assert result.measures is not None and result.measures.stalls == 1 and result.measures.first_stall == stall.time
    assert result.ended == "shift-end" and not any(f.kind == "stall" for f in result.failures)  # counted
    assert result_problem(result.to_dict()) is None


def test_a_shorter_standstill_is_no_stall() -> None:
    assert run(Shift(duration=9.0, stall_after=5.0)).stalls == ()  # it stood less than 5 s by then
    assert run(Shift(duration=30.0, stall_after=40.0)).stalls == ()


def test_a_vehicle_dwelling_at_a_stop_or_without_work_is_no_stall() -> None:
    dwelling = (Order("a", (Stop(7, dwell=20.0),), release=0.0),)  # vehicle 2 has no work
    result = run(Shift(duration=150.0, stall_after=5.0), ReservingPlanner(), dwelling)
    assert result.orders[0]["completed"] is not None and result.stalls == ()


def test_on_stall_end_ends_the_run_at_the_first_stall_and_fails_it() -> None:
    result = run(Shift(duration=30.0, stall_after=5.0, on_stall="end"))
    assert result.ended == "stall" and result.sim_time == pytest.approx(result.stalls[0].time)
    stall = next(f for f in result.failures if f.kind == "stall")
    assert stall.details["vehicle"] == 2 and stall.details["orders"] == ["b"]
    assert result_problem(result.to_dict()) is None


def test_a_shift_of_tasks_alone_runs_to_its_end_once_they_are_done() -> None:
    loop = scenario(())
    tasks = dataclasses.replace(loop, tasks=_loop_tasks(), orders=(), shift=Shift(duration=200.0))
    result = run_scenario(tasks, ReservingPlanner())
    assert result.tasks_completed == result.tasks_total and result.ended == "shift-end" and result.deadlock is None


def _loop_tasks() -> tuple[Task, ...]:
    return (Task(1, 1, 7), Task(2, 2, 2))
