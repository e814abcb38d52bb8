"""Transport orders as a run's trace tells them: who carries what, who waits where, the backlog (issue 45).

The pictures, recordings and the viewer show a run's orders from its trace alone (docs/trace.md): the
header's ``orders`` says where they come from, each step's events what happened to them. Followed step by
step over the replayed frames (:mod:`fleetsim.recording.replay`), they give at every step:

- each vehicle's *carry*: its orders in sequence (``assign``; an order leaves it when it is completed), whether
  it is loaded (its first order's first stop is served), the next stop of that order, whether it dwells at a
  stop (from the step its stop's task is completed — the vehicle whose plan marks that task as a leg's goal
  — to the stop's ``served``) and whether it is stalled (from its ``stall`` until it moves again);
- the orders *waiting* at each station: released, their first stop not yet served, by that stop's segment;
- how many orders are open (released, not completed) and completed, and the *backlog*: the open orders at
  each full minute, sampled as the run's measures sample it (at the step's start, after the dwells that
  ended and the releases of the step, before anything the planner or the motion did in it), so the series
  is ``result.json``'s ``measures.backlog``.

An order's stops come from the header: an ``orders.csv`` order is there whole; a generated stream's n-th
order is drawn again from the header's stream (seed, draws, station segments and their integer weights:
what the order's contents are drawn from, order by order, whatever the arrivals; ``fleetsim.dispatch.stream``).
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from fleetsim.dispatch.stream import OrderSource
from fleetsim.enums import Progress
from fleetsim.orders import Arrivals, OrderStream, Station, StopDraw
from fleetsim.recording.replay import Frame, TraceError, replay
from fleetsim.scenario import Scenario
from fleetsim.sim.measures import BACKLOG_EVERY

__all__ = ["Carry", "OrderChanges", "OrderState", "OrderStops", "OrderTracker", "frame_and_orders_at"]

_GENERATED = re.compile(r"s([1-9][0-9]*)")


@dataclass(frozen=True, slots=True)
class OrderStops:
    """What the trace says of one order's stops: their segments and dwells (seconds), in order."""

    id: str
    segments: tuple[int, ...]
    dwells: tuple[float, ...]


@dataclass(frozen=True, slots=True)
class Carry:
    """What a vehicle does for its orders at the end of a step.

    Attributes:
        orders: Its orders in sequence, the one it serves first (started, if any) first.
        loaded: Its first order's first stop is served (picked up).
        stop: The index (from 0) of the next stop of its first order to be served.
        stops: How many stops that order has (0 when the trace does not say).
        dwell: ``(since, seconds)`` while it dwells at that stop: reached at ``since``, to stand ``seconds``.
        stalled: Found stalled (``["stall", vehicle]``) and not moved since.
    """

    orders: tuple[str, ...] = ()
    loaded: bool = False
    stop: int = 0
    stops: int = 0
    dwell: tuple[float, float] | None = None
    stalled: bool = False

    @property
    def order(self) -> str | None:
        return self.orders[0] if self.orders else None


_IDLE = Carry()


@dataclass(frozen=True, slots=True)
class OrderState:
    """The orders at the end of a step."""

    carry: Mapping[int, Carry]  # vehicles with an order or a stall only
    waiting: Mapping[int, tuple[str, ...]]  # station segment -> orders waiting there, in release order
    open: int
    done: int
    backlog: tuple[tuple[float, int], ...]  # (seconds, open orders) at each full minute so far

    def carry_of(self, vehicle: int) -> Carry:
        return self.carry.get(vehicle, _IDLE)


@dataclass(slots=True)
class OrderChanges:
    """What one step changed: the vehicles whose carry and the stations whose waiting orders changed,
    whether the counts did, and the backlog sample taken at the step's start (``None``: none)."""

    vehicles: set[int] = field(default_factory=set)
    stations: set[int] = field(default_factory=set)
    counts: bool = False
    sample: int | None = None

    def __bool__(self) -> bool:
        return bool(self.vehicles or self.stations or self.counts or self.sample is not None)


class _Generated:
    """The stops of a generated stream's orders ``s1``, ``s2``, ..., drawn again from the header's stream.

    An order's contents are drawn order by order from a generator of their own, whatever the arrivals and
    the time step: a source of the same draws releasing one order a step gives the n-th order's stops.
    """

    def __init__(self, stream: Mapping[str, Any]) -> None:
        draws, stations = [], {}
        for index, draw in enumerate(stream["stops"]):
            name = f"#{index}"
            # The header's weights are the exact integers the draws use (an int is a float's exact equal).
            stations[name] = tuple(Station(int(segment), int(weight)) for segment, weight in draw["segments"])
            low, high = draw["dwell_ms"]
            progress = None if draw["progress"] is None else Progress(draw["progress"])
            count = (int(draw["count"][0]), int(draw["count"][1]))
            draws.append(StopDraw((name,), bool(draw["weighted"]), (low / 1000, high / 1000), count, progress))
        one_a_second = OrderStream(int(stream["seed"]), Arrivals("interval", interval=1.0), tuple(draws))
        self._source = OrderSource((), one_a_second, stations, 1.0)
        self._step = 0
        self._made: dict[str, OrderStops] = {}

    def get(self, order_id: str) -> OrderStops | None:
        match = _GENERATED.fullmatch(order_id)
        if match is None:
            return None
        while len(self._made) < int(match.group(1)):
            for order in self._source.due(self._step):
                self._made[order.id] = OrderStops(
                    order.id, tuple(s.segment for s in order.stops), tuple(s.dwell for s in order.stops)
                )
            self._step += 1
        return self._made[order_id]


class OrderTracker:
    """Follows a run's orders through its replayed frames (see the module's description).

    ``header``: the trace's header (parsed). A run without orders (no ``orders`` in it) has nothing to
    follow: :attr:`active` is false and :meth:`follow` changes nothing.
    """

    def __init__(self, header: Mapping[str, Any]) -> None:
        source = header.get("orders")
        self.active = isinstance(source, Mapping)
        self._tasks = int(header.get("tasks", 0))
        dt = int(header.get("time_step_us", 100_000)) / 1e6
        self._dt = dt
        self._every = max(1, round(BACKLOG_EVERY / dt))
        self._known: dict[str, OrderStops] = {}
        self._generated: _Generated | None = None
        if isinstance(source, Mapping):
            for record in source.get("orders") or ():
                order_id, _, _, stops = record[:4]
                self._known[order_id] = OrderStops(
                    order_id, tuple(int(s[0]) for s in stops), tuple(int(s[2]) / 1000 for s in stops)
                )
            if source.get("stream") is not None:
                self._generated = _Generated(source["stream"])
        self._sequences: dict[int, tuple[str, ...]] = {}
        self._served: dict[str, int] = {}  # open orders: stops served
        self._waiting: dict[int, tuple[str, ...]] = {}
        self._goal_of: dict[int, int] = {}  # task -> the vehicle whose plan marks a leg as its goal
        self._dwell: dict[int, tuple[float, float]] = {}
        self._stalled: set[int] = set()
        self._carry: dict[int, Carry] = {}
        self.open = 0
        self.done = 0
        self.backlog: list[tuple[float, int]] = []

    @classmethod
    def of_trace(cls, lines: Sequence[str]) -> OrderTracker:
        try:
            header = json.loads(lines[0]) if lines else {}
        except json.JSONDecodeError:
            header = {}
        return cls(header if isinstance(header, dict) else {})

    def stops(self, order_id: str) -> OrderStops | None:
        """The order's stops as the trace's header gives them (``None``: it does not)."""
        known = self._known.get(order_id)
        if known is None and self._generated is not None:
            known = self._generated.get(order_id)
        return known

    def follow(self, frame: Frame) -> OrderChanges:
        """Take in one step's frame (in order, from step 0); what it changed."""
        changes = OrderChanges()
        if not self.active:
            return changes
        if frame.step == 0:
            changes.counts = True  # the first record of a run with orders says so, even with none yet
        for vehicle in frame.replanned:
            for leg in frame.plans[vehicle].legs:
                if leg.goal_for_task is not None and leg.goal_for_task > self._tasks:
                    self._goal_of[leg.goal_for_task] = vehicle
        sampling = frame.step % self._every == 0
        for event in frame.events:
            kind = event[0]
            if sampling and kind == "complete":
                self._sample(frame, changes)
                sampling = False
            if kind == "release":
                self._release(str(event[1]), changes)
            elif kind == "assign":
                self._assign(int(event[1]), tuple(str(o) for o in event[2]), changes)
            elif kind == "complete":
                self._reached(int(event[1]), frame.time, changes)
            elif kind == "served":
                self._serve(int(event[1]), str(event[2]), int(event[3]), changes)
            elif kind == "order-done":
                self._complete(str(event[1]), changes)
            elif kind == "stall":
                self._stalled.add(int(event[1]))
                changes.vehicles.add(int(event[1]))
        if sampling:
            self._sample(frame, changes)
        for vehicle in frame.moved:
            if vehicle in self._stalled and not any(e[0] == "stall" and e[1] == vehicle for e in frame.events):
                self._stalled.discard(vehicle)
                changes.vehicles.add(vehicle)
        for vehicle in changes.vehicles:
            self._carry[vehicle] = self._carry_now(vehicle)
        return changes

    def state(self) -> OrderState:
        """The orders as they are after the last frame taken in."""
        carry = {v: c for v, c in sorted(self._carry.items()) if c != _IDLE}
        waiting = {s: w for s, w in sorted(self._waiting.items()) if w}
        return OrderState(MappingProxyType(carry), MappingProxyType(waiting), self.open, self.done, tuple(self.backlog))

    def carry_of(self, vehicle: int) -> Carry:
        return self._carry.get(vehicle, _IDLE)

    def waiting_at(self, segment: int) -> tuple[str, ...]:
        return self._waiting.get(segment, ())

    # -- the events -------------------------------------------------------------------------------

    def _sample(self, frame: Frame, changes: OrderChanges) -> None:
        # The measures sample at the step's start (step x time step, as the loop computes it).
        self.backlog.append((frame.step * self._dt, self.open))
        changes.sample = self.open

    def _release(self, order_id: str, changes: OrderChanges) -> None:
        self.open += 1
        changes.counts = True
        self._served[order_id] = 0
        stops = self.stops(order_id)
        if stops is not None:
            station = stops.segments[0]
            self._waiting[station] = (*self._waiting.get(station, ()), order_id)
            changes.stations.add(station)

    def _assign(self, vehicle: int, orders: tuple[str, ...], changes: OrderChanges) -> None:
        for other, sequence in list(self._sequences.items()):
            if other != vehicle and any(o in orders for o in sequence):
                self._sequences[other] = tuple(o for o in sequence if o not in orders)
                changes.vehicles.add(other)
        self._sequences[vehicle] = orders
        changes.vehicles.add(vehicle)

    def _reached(self, task: int, time: float, changes: OrderChanges) -> None:
        vehicle = self._goal_of.pop(task, None)
        if vehicle is None or not self._sequences.get(vehicle):
            return
        order_id = self._sequences[vehicle][0]
        stops = self.stops(order_id)
        index = self._served.get(order_id, 0)
        if stops is not None and index < len(stops.dwells) and stops.dwells[index] > 0:
            self._dwell[vehicle] = (time, stops.dwells[index])
            changes.vehicles.add(vehicle)

    def _serve(self, vehicle: int, order_id: str, index: int, changes: OrderChanges) -> None:
        self._served[order_id] = index + 1
        self._dwell.pop(vehicle, None)
        changes.vehicles.add(vehicle)
        if index == 0:
            stops = self.stops(order_id)
            if stops is not None:
                station = stops.segments[0]
                self._waiting[station] = tuple(o for o in self._waiting.get(station, ()) if o != order_id)
                changes.stations.add(station)

    def _complete(self, order_id: str, changes: OrderChanges) -> None:
        self.open -= 1
        self.done += 1
        changes.counts = True
        self._served.pop(order_id, None)
        for vehicle, sequence in list(self._sequences.items()):
            if order_id in sequence:
                self._sequences[vehicle] = tuple(o for o in sequence if o != order_id)
                changes.vehicles.add(vehicle)

    def _carry_now(self, vehicle: int) -> Carry:
        orders = self._sequences.get(vehicle, ())
        stalled = vehicle in self._stalled
        if not orders:
            return Carry(stalled=stalled)
        first = orders[0]
        served = self._served.get(first, 0)
        stops = self.stops(first)
        return Carry(
            orders=orders,
            loaded=served > 0,
            stop=served,
            stops=0 if stops is None else len(stops.segments),
            dwell=self._dwell.get(vehicle),
            stalled=stalled,
        )


def followed(scenario: Scenario, lines: Sequence[str]) -> Iterable[tuple[Frame, OrderTracker, OrderChanges]]:
    """Each replayed frame of a run's trace with the orders followed up to it (the tracker is one object,
    taken on frame by frame)."""
    tracker = OrderTracker.of_trace(lines)
    for frame in replay(scenario, lines):
        yield frame, tracker, tracker.follow(frame)


def frame_and_orders_at(scenario: Scenario, lines: Sequence[str], step: int) -> tuple[Frame, OrderState | None]:
    """The frame of step ``step`` (``-1``: the last) and the orders then (``None`` for a run without)."""
    last: tuple[Frame, OrderTracker] | None = None
    for frame, tracker, _ in followed(scenario, lines):
        last = frame, tracker
        if frame.step == step:
            break
    if last is None:
        msg = "the trace has no steps"
        raise TraceError(msg)
    frame, tracker = last
    if step not in (-1, frame.step):
        msg = f"step={step!r} must be between 0 and {frame.step} (the run's last step)"
        raise TraceError(msg)
    return frame, tracker.state() if tracker.active else None
