"""The dispatcher's part of a run with transport orders (issue 45): the loop's hook, as disturbances are.

At the start of each step, before planning: vehicles that dwell at a stop count their dwell (from the
moment they are at rest) and, when it is over, drive on (the stop is *served*; the order's last stop
served completes it); orders due are released (``fleetsim.dispatch.stream``); and the dispatcher is
asked (``dispatch(board, fleet, layout)``) when orders were released, when a vehicle ran out of work, or
when its period came round, provided some order is open. Its answer is checked whole
(``fleetsim.dispatch.checks``): refused, each broken rule is a rejection and the assignments in force
stand; accepted, the vehicles' task queues become their new sequences (``fleetsim.dispatch.book``).
When a vehicle reaches a stop (its task completes), it is halted to dwell there if the stop has a dwell.

Everything that happens enters the step's trace line (``["release", order]``, ``["assign", vehicle,
[orders]]``, ``["served", vehicle, order, stop]``, ``["order-done", order]``) and the trace header holds
the orders' source: a run with orders is as deterministic as any, and a run without has none of this.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from fleetsim.dispatch.book import OrderBook
from fleetsim.dispatch.checks import check_answer, validate_answer
from fleetsim.dispatch.protocol import Dispatcher, OrderBoard, Why
from fleetsim.dispatch.stream import OrderSource
from fleetsim.layout.layout import Layout
from fleetsim.motion.driver import Driver
from fleetsim.planning.checks import Rejection
from fleetsim.planning.controller import FleetController
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Scenario
from fleetsim.sim.lorr_counts import HoldClock, lorr_counts
from fleetsim.sim.measures import BACKLOG_EVERY, FleetTimes, OrderMeasures, Stall, measure_orders

__all__ = ["Dispatching"]

_EPS = 1e-9

# How the dispatcher is called, guarded: (its dispatch method, board, fleet, layout) -> its answer.
InvokeDispatch = Callable[[Callable[..., object], OrderBoard, FleetSnapshot, Layout], object]


@dataclass(slots=True)
class _Dwell:
    order: str
    stop: int
    seconds: float
    reached: float
    ends: float | None  # None: still braking to rest


class Dispatching:
    """Releases, dispatches and dwells of one run (a scenario with orders or an order stream)."""

    def __init__(
        self,
        scenario: Scenario,
        dispatcher: Dispatcher,
        controller: FleetController,
        drivers: Mapping[int, Driver],
        invoke: InvokeDispatch,
    ) -> None:
        dt = scenario.settings.time_step
        self.source = OrderSource(scenario.orders, scenario.order_stream, scenario.stations, dt, scenario.order_pool)
        first_task = max((task.id for task in scenario.tasks), default=0) + 1
        self.book = OrderBook(scenario.orders, {v.id: v.type.name for v in scenario.vehicles}, first_task)
        self.dispatcher = dispatcher
        self.controller = controller
        self.layout = scenario.layout
        self._drivers = drivers
        self._invoke = invoke
        self._wants_call, self._refused = getattr(dispatcher, "wants_call", None), getattr(dispatcher, "refused", None)
        period = scenario.shift.dispatch_period if scenario.shift is not None else None
        self._period = max(1, round(period / dt)) if period else None
        self._dwelling: dict[int, _Dwell] = {}
        self._idle: frozenset[int] = frozenset()
        # Who is idle, and who has work and is not dwelling, worked out again only when a task queue, an
        # order sequence or the dwelling vehicles changed since (most steps none does): what they were
        # worked out from (the task heads, the book's version, the dwells' count of changes), and them.
        self._vehicles = frozenset(controller.plans)
        self._dwell_changes = 0
        self._worked_from: tuple[object, int, int] | None = None
        self._worked_out: tuple[frozenset[int], tuple[int, ...]] = (frozenset(), ())
        # For the measures (fleetsim.sim.measures), over the window from the warm-up's end: the odometers
        # when the window opened, and what is summed.
        self.warmup = scenario.shift.warmup if scenario.shift is not None else 0.0
        self._backlog_every = max(1, round(BACKLOG_EVERY / dt))
        self.backlog: list[tuple[float, int]] = []
        self._opened: dict[int, float] | None = None  # odometers at the window's start
        self._idle_since: dict[int, float] = {}
        self._loaded_since: dict[int, float] = {}  # vehicle -> odometer when its started order began
        self.idle_time = 0.0
        self.dwell_time = 0.0
        self.blocked_time = 0.0
        self.loaded_distance = 0.0
        self._dt = dt
        # A League problem's run: who holds orders, and since when (its sumOfCost and makespan).
        self._lorr = scenario.lorr
        self._holds = HoldClock() if scenario.lorr is not None else None

    def header(self) -> dict[str, Any]:
        """What the trace header holds of the orders: their source, canonically, and the dispatcher's period."""
        return {**self.source.header(), "dispatch_period_steps": self._period}

    def is_dwelling(self, vehicle: int) -> bool:
        return vehicle in self._dwelling

    def dwelling(self) -> bool:
        """Some vehicle dwells at a stop (no deadlock then: it will drive on)."""
        return bool(self._dwelling)

    def done(self) -> bool:
        """No order is open and none will be released: a run of orders alone is complete."""
        return self.book.open_count() == 0 and self.source.exhausted() and not self._dwelling

    # -- the step ------------------------------------------------------------------------------------

    def begin_step(self, step: int, now: float, stamp: float, events: list[list[Any]]) -> list[Rejection]:
        """Dwells, releases and the dispatcher's call at the start of step ``step`` (time ``now``); the
        rules a refused answer broke (the loop records them as rejections stamped ``stamp``)."""
        if self._opened is None and now >= self.warmup - _EPS:
            self._open_window(now)
        self._dwell(now, events)
        why: list[Why] = []
        released = self.source.due(step)
        for order in released:
            self.book.release(order, now)
            events.append(["release", order.id])
        if released:
            why.append("release")
        if step % self._backlog_every == 0:
            self.backlog.append((now, self.book.open_count()))
        idle = self._idle_vehicles()
        if idle is not self._idle and idle - self._idle:
            why.append("idle")
        self._set_idle(idle, now)
        if self._opened is not None:
            self._count_standing(idle)
        if self._period is not None and step % self._period == 0:
            why.append("period")
        if self._wants_call is not None and self._wants_call():
            why.append("request")
        if not why or (self.book.open_count() == 0 and "request" not in why):
            return []
        return self._ask(now, why, events)

    def _idle_vehicles(self) -> frozenset[int]:
        """The vehicles with no task, no order and no dwell (and, kept beside them, the working ones)."""
        heads = self.controller.tasks.heads()  # the same object until a queue changes
        source = (heads, self.book.version, self._dwell_changes)
        worked_from = self._worked_from
        if worked_from is not None and worked_from[0] is heads and worked_from[1:] == source[1:]:
            return self._worked_out[0]
        idle = self._vehicles.difference(heads.keys(), self.book.holding(), self._dwelling.keys())
        working = tuple(self._vehicles.difference(idle, self._dwelling.keys()))
        self._worked_from, self._worked_out = source, (idle, working)
        return idle

    def _ask(self, now: float, why: list[Why], events: list[list[Any]]) -> list[Rejection]:
        board = self.book.board(now, why, sorted(self._idle))
        answer = self._invoke(self.dispatcher.dispatch, board, self.controller.snapshot(now), self.layout)
        assignments = validate_answer(answer)
        problems = check_answer(assignments, self.book.context())
        if problems:
            if self._refused is not None:
                self._refused(problems)
            return problems
        for change in self.book.apply(assignments, now):
            self.controller.requeue(change.vehicle_id, change.withdraw, change.append)
            events.append(["assign", change.vehicle_id, list(change.sequence)])
        if self._holds is not None:
            self._holds.update(self.book.holding(), now)
        self._set_idle(self._idle_vehicles(), now)
        return []

    def _count_standing(self, idle: frozenset[int]) -> None:
        """This step's seconds of the vehicles that stand with work: dwelling at a stop, or blocked (a
        vehicle's step added one at a time, as the sums have always been made)."""
        assert idle is self._worked_out[0]  # the working vehicles kept beside it are this step's
        dt = self._dt
        for _ in range(len(self._dwelling)):
            self.dwell_time += dt
        state_of = self.controller.state_of
        for _ in range(sum(1 for vehicle in self._worked_out[1] if state_of(vehicle).speed == 0.0)):
            self.blocked_time += dt

    def _set_idle(self, idle: frozenset[int], now: float) -> None:
        if idle is self._idle:
            return
        for vehicle in sorted(idle - self._idle):
            self._idle_since[vehicle] = now
        for vehicle in sorted(self._idle - idle):
            self.idle_time += self._in_window(self._idle_since.pop(vehicle), now)
        self._idle = idle

    def _in_window(self, since: float, until: float) -> float:
        """Seconds of ``[since, until]`` after the warm-up."""
        return max(0.0, until - max(since, self.warmup))

    def _open_window(self, now: float) -> None:
        self._opened = {vehicle: driver.odometer for vehicle, driver in sorted(self._drivers.items())}
        for vehicle, since in self._loaded_since.items():  # loaded when the window opens: from here
            self._loaded_since[vehicle] = max(since, self._opened[vehicle])

    # -- stops ---------------------------------------------------------------------------------------

    def reached(self, task_id: int, time: float, events: list[list[Any]]) -> None:
        """A task completed: if it is an order's stop, its vehicle dwells there (or it is served at once)."""
        found = self.book.reached(task_id, time)
        if found is None:
            return
        order, index = found
        vehicle = self.book.records[order.id].vehicle
        assert vehicle is not None
        if index == 0:  # loaded from here until its last stop is served
            self._loaded_since[vehicle] = self._drivers[vehicle].odometer
        dwell = order.stops[index].dwell
        if dwell <= 0.0:
            self._serve(vehicle, order.id, index, time, events)
            return
        driver = self._drivers[vehicle]
        braking = driver.halt()
        ends = time + dwell if braking == 0.0 and driver.speed == 0.0 else None
        self._dwelling[vehicle] = _Dwell(order.id, index, dwell, time, ends)
        self._dwell_changes += 1

    def _dwell(self, now: float, events: list[list[Any]]) -> None:
        for vehicle in sorted(self._dwelling):
            dwell = self._dwelling[vehicle]
            if dwell.ends is None and self._drivers[vehicle].speed == 0.0:
                dwell.ends = now + dwell.seconds
            if dwell.ends is not None and now >= dwell.ends - _EPS:
                del self._dwelling[vehicle]
                self._dwell_changes += 1
                self._drivers[vehicle].release()
                self._serve(vehicle, dwell.order, dwell.stop, now, events)

    def _serve(self, vehicle: int, order_id: str, index: int, time: float, events: list[list[Any]]) -> None:
        events.append(["served", vehicle, order_id, index])
        if self.book.served(order_id, index, time):
            events.append(["order-done", order_id])
            self.source.completed(order_id)
            self._unload(vehicle)
            if self._holds is not None:
                self._holds.update(self.book.holding(), time)

    def _unload(self, vehicle: int) -> None:
        since = self._loaded_since.pop(vehicle, None)
        if since is not None and self._opened is not None:
            self.loaded_distance += self._drivers[vehicle].odometer - max(since, self._opened[vehicle])

    # -- the measures --------------------------------------------------------------------------------

    def measures(self, end: float, stalls: Sequence[Stall] = ()) -> OrderMeasures:
        """What the run delivered, over the window from the warm-up's end to ``end`` (the run's end)."""
        if self._opened is None:  # the run ended within its warm-up: an empty window
            self._open_window(end)
        opened = self._opened or {}
        for vehicle in sorted(self._loaded_since):
            self._unload(vehicle)
        idle = self.idle_time + sum(self._in_window(since, end) for since in self._idle_since.values())
        odometers = {vehicle: driver.odometer for vehicle, driver in sorted(self._drivers.items())}
        times = FleetTimes(
            vehicles=len(odometers),
            idle=idle,
            dwelling=self.dwell_time,
            blocked=self.blocked_time,
            distance=sum(odometers[v] - opened.get(v, 0.0) for v in odometers),
            loaded_distance=self.loaded_distance,
        )
        measures = measure_orders(self.book.records, (min(self.warmup, end), end), times, self.backlog, stalls)
        if self._lorr is None or self._holds is None:
            return measures
        records = self.book.records.values()
        finished = sum(1 for record in records if record.completed is not None)
        counts = lorr_counts(self._lorr, self._vehicles, self._holds.totals(end), len(records), finished)
        return replace(measures, lorr=counts)
