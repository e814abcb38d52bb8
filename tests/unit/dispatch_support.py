"""Scenarios with transport orders on the shipped one-way loop, and a scripted dispatcher, for the tests."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from functools import cache
from pathlib import Path
from typing import Any

from fleetsim import load_scenario, load_suite
from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.orders import Order, Shift, Stop
from fleetsim.planners import ReservingPlanner
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult

# Vehicles 1 (on segment 1) and 2 (on segment 6) of the shipped one-way loop (segments 1-10).
ORDERS = (
    Order("a", (Stop(7), Stop(2)), release=0.0),
    Order("b", (Stop(2), Stop(7)), release=0.0),
    Order("late", (Stop(4),), release=30.0),
    Order("tug", (Stop(9),), release=0.0, vehicle_types=("tugger",)),
)


@cache
def _loop() -> Scenario:
    suite = load_suite(Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml")
    spec = next(s for s in suite.scenarios if s.name == "loop-one-way")
    return load_scenario(spec, suite)


def scenario(orders: tuple[Order, ...] = ORDERS, **settings: Any) -> Scenario:
    loop = _loop()
    return dataclasses.replace(
        loop,
        tasks=(),
        orders=orders,
        settings=dataclasses.replace(loop.settings, stop_on=(), time_limit=120.0, **settings),
    )


Script = Callable[[OrderBoard], Sequence[Assignment]]


class Scripted:
    """Answers each call with what ``script(board)`` gives, and keeps the boards it was shown."""

    def __init__(self, script: Script) -> None:
        self.script = script
        self.boards: list[OrderBoard] = []

    def dispatch(self, board: OrderBoard, fleet: object, layout: object) -> Sequence[Assignment]:
        self.boards.append(board)
        return self.script(board)


def once(*assignments: Assignment) -> Script:
    """The assignments at the first call, nothing after."""
    calls: list[int] = []

    def script(board: OrderBoard) -> Sequence[Assignment]:
        calls.append(1)
        return assignments if len(calls) == 1 else []

    return script


def run(script: Script, orders: tuple[Order, ...] = ORDERS) -> RunResult:
    return run_scenario(scenario(orders), ReservingPlanner(), dispatcher=Scripted(script))


def with_period(orders: tuple[Order, ...], period: float) -> Scenario:
    """A two-minute shift whose dispatcher is also asked every ``period`` seconds."""
    base = scenario(orders)
    return dataclasses.replace(base, shift=Shift(duration=120.0, dispatch_period=period))


class FirstIdle:
    """Each unassigned order, oldest first, to the idle vehicle with the lowest id."""

    def dispatch(self, board: OrderBoard, fleet: object, layout: object) -> list[Assignment]:
        idle = list(board.idle)
        return [Assignment(idle.pop(0), [order.id]) for order in board.unassigned() if idle]


_REPO = Path(__file__).resolve().parents[2]
_LOOP = _REPO / "scenario_suites" / "examples" / "loop"
GATE_ORDERS = "order_id,release,stops,dwell\na,0,7>2,2\nb,5,2>7,2\n"


def gate_suite(folder: Path, entry: str) -> Path:
    """A suite in ``folder`` of one entry on the shipped loop with two orders, ``entry`` its last lines."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "orders.csv").write_text(GATE_ORDERS, encoding="utf-8")
    path = folder / "gate.fleetsim.yaml"
    path.write_text(
        f"""fleetsim: 1
name: gate
scenarios:
  - name: loop
    map: {_LOOP / "map.tmx"}
    vehicles: {_LOOP / "vehicles.csv"}
    tasks: {_LOOP / "tasks.csv"}
    orders: orders.csv
    shift: {{duration: 90}}
    dispatcher: fleetsim.dispatchers:NearestVehicleDispatcher
{entry}""",
        encoding="utf-8",
    )
    return path
