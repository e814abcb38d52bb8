"""The orders of one run as they go: released, assigned, started, served, completed, and when.

The book turns a dispatcher's accepted answer into changes of the vehicles' task queues: each vehicle's
queue ends with one task per remaining stop of each order in its sequence, in sequence order. Where a new
sequence differs from the one in force, the tasks of the orders from the first difference on are
withdrawn and new ones (fresh ids) made, so a queue is always its sequence, head first, and a withdrawn
task's id is never used again. A vehicle's started order (its first stop reached) is always at the head of
its sequence and is never withdrawn.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from fleetsim.dispatch.checks import AnswerContext
from fleetsim.dispatch.protocol import Assignment, OpenOrder, OrderBoard, Why
from fleetsim.orders import Order
from fleetsim.scenario import Task

__all__ = ["OrderBook", "OrderRecord", "Requeue"]


@dataclass(slots=True)
class OrderRecord:
    """One released order's life, for the result (times in simulated seconds; ``None``: not yet)."""

    order: Order
    released: float
    assigned: float | None = None  # first given to a vehicle
    vehicle: int | None = None  # the vehicle holding it now (or that completed it)
    started: float | None = None  # its first stop reached (picked up)
    served: list[float] = field(default_factory=list)  # each stop's dwell ended, in stop order
    completed: float | None = None
    reassigned: int = 0  # how many times it was taken from one vehicle and given to another

    def to_dict(self) -> dict[str, Any]:
        order = self.order
        missed = order.deadline is not None and (self.completed is None or self.completed > order.deadline + 1e-9)
        return {
            "id": order.id,
            "stops": [stop.segment for stop in order.stops],
            "release": _rounded(self.released),
            "deadline": order.deadline,
            "priority": order.priority,
            "vehicle": self.vehicle,
            "assigned": _rounded(self.assigned),
            "started": _rounded(self.started),
            "served": [_rounded(t) for t in self.served],
            "completed": _rounded(self.completed),
            "reassigned": self.reassigned,
            "deadline_missed": missed,
        }


def _rounded(value: float | None) -> float | None:
    return None if value is None else round(value, 6)


@dataclass(frozen=True, slots=True)
class Requeue:
    """What an accepted answer does to one vehicle's queue: withdraw these tasks (its queue's tail), then
    append those; ``sequence`` is its new sequence of orders."""

    vehicle_id: int
    withdraw: tuple[int, ...]
    append: tuple[Task, ...]
    sequence: tuple[str, ...]


class OrderBook:
    """The run-time state of the orders; the simulation owns it."""

    def __init__(self, known: Iterable[Order], vehicle_types: Mapping[int, str], first_task_id: int) -> None:
        self._known: dict[str, Order] = {order.id: order for order in known}
        self._types = dict(vehicle_types)
        self._records: dict[str, OrderRecord] = {}  # every released order, in release order
        self._open: dict[str, None] = {}  # released, not completed (an ordered set)
        self._holder: dict[str, int] = {}
        self._started: set[str] = set()
        self._completed: set[str] = set()
        self._sequences: dict[int, list[str]] = {vehicle: [] for vehicle in sorted(vehicle_types)}
        self._holding: set[int] = set()  # the vehicles whose sequence is not empty
        self.version = 0  # counts the changes of any sequence (so a caller may keep what it derives from them)
        self._tasks: dict[str, list[Task]] = {}  # an assigned order's tasks in force (its remaining stops)
        self._stop_of: dict[int, tuple[str, int]] = {}  # task id -> (order id, stop index), for tasks in force
        self._next_task = first_task_id

    # -- queries -------------------------------------------------------------------------------------

    @property
    def records(self) -> Mapping[str, OrderRecord]:
        return MappingProxyType(self._records)

    def open_count(self) -> int:
        return len(self._open)

    def sequence(self, vehicle_id: int) -> tuple[str, ...]:
        return tuple(self._sequences[vehicle_id])

    def has_orders(self, vehicle_id: int) -> bool:
        return bool(self._sequences[vehicle_id])

    def holding(self) -> frozenset[int]:
        """The vehicles with orders in force (a sequence that is not empty)."""
        return frozenset(self._holding)

    def stop_of(self, task_id: int) -> tuple[Order, int] | None:
        """The order and stop index a task in force serves, or ``None`` (a ``tasks.csv`` task)."""
        found = self._stop_of.get(task_id)
        return None if found is None else (self._known[found[0]], found[1])

    def board(self, time: float, why: Sequence[Why], idle: Sequence[int]) -> OrderBoard:
        orders = {
            order_id: OpenOrder(
                order=self._known[order_id],
                vehicle_id=self._holder.get(order_id),
                started=order_id in self._started,
                served=len(self._records[order_id].served),
                released=self._records[order_id].released,
            )
            for order_id in self._open
        }
        return OrderBoard(
            time=time,
            why=tuple(why),
            orders=MappingProxyType(orders),
            sequences=MappingProxyType({vehicle: tuple(seq) for vehicle, seq in self._sequences.items()}),
            idle=tuple(idle),
        )

    def context(self) -> AnswerContext:
        return AnswerContext(
            vehicle_types=MappingProxyType(self._types),
            known=MappingProxyType(self._known),
            released=frozenset(self._open),
            completed=frozenset(self._completed),
            holder=MappingProxyType(self._holder),
            started=frozenset(self._started),
        )

    # -- changes -------------------------------------------------------------------------------------

    def release(self, order: Order, time: float) -> None:
        self._known[order.id] = order
        self._records[order.id] = OrderRecord(order, released=time)
        self._open[order.id] = None

    def apply(self, assignments: Sequence[Assignment], time: float) -> list[Requeue]:
        """An answer that passed the checks: the vehicles' new sequences, as queue changes by vehicle id."""
        wanted: dict[int, list[str]] = {}
        for assignment in assignments:
            kept = [o for o in self._sequences[assignment.vehicle_id] if o in self._started]
            wanted[assignment.vehicle_id] = kept + [o for o in assignment.orders if o not in kept]
        for vehicle, sequence in list(wanted.items()):
            for order_id in sequence:
                holder = self._holder.get(order_id)
                if holder is not None and holder != vehicle and holder not in wanted:
                    wanted[holder] = [o for o in self._sequences[holder] if o != order_id]
        # Withdraw first, for every vehicle, then assign: an order moving between two vehicles leaves the
        # one before it joins the other, whichever has the lower id.
        kept_until: dict[int, int] = {}
        withdrawn: dict[int, list[int]] = {}
        for vehicle in sorted(wanted):
            old, new = self._sequences[vehicle], wanted[vehicle]
            if old == new:
                continue
            same = 0
            while same < min(len(old), len(new)) and old[same] == new[same]:
                same += 1
            kept_until[vehicle] = same
            withdrawn[vehicle] = []
            for order_id in old[same:]:
                for task in self._tasks.pop(order_id, []):
                    withdrawn[vehicle].append(task.id)
                    del self._stop_of[task.id]
                if self._holder.get(order_id) == vehicle:
                    del self._holder[order_id]
        changes: list[Requeue] = []
        for vehicle, same in kept_until.items():
            new = wanted[vehicle]
            appended: list[Task] = []
            for order_id in new[same:]:
                appended += self._assign(order_id, vehicle, time)
            self._sequences[vehicle] = list(new)
            if new:
                self._holding.add(vehicle)
            else:
                self._holding.discard(vehicle)
            self.version += 1
            changes.append(Requeue(vehicle, tuple(withdrawn[vehicle]), tuple(appended), tuple(new)))
        for order_id, record in self._records.items():
            if order_id in self._open and order_id not in self._holder:
                record.vehicle = None
        return changes

    def _assign(self, order_id: str, vehicle: int, time: float) -> list[Task]:
        order = self._known[order_id]
        record = self._records[order_id]
        if record.vehicle is not None and record.vehicle != vehicle and record.assigned is not None:
            record.reassigned += 1
        if record.assigned is None:
            record.assigned = time
        record.vehicle = vehicle
        self._holder[order_id] = vehicle
        tasks = []
        for index, stop in enumerate(order.stops):
            task = Task(
                id=self._next_task,
                vehicle_id=vehicle,
                goal_segment=stop.segment,
                goal_progress=stop.progress,
                order_id=order_id,
                stop=index,
                deadline=order.deadline,
            )
            self._next_task += 1
            self._stop_of[task.id] = (order_id, index)
            tasks.append(task)
        self._tasks[order_id] = tasks
        return tasks

    def reached(self, task_id: int, time: float) -> tuple[Order, int] | None:
        """A task of an order was completed (its vehicle reached the stop): the order and the stop index."""
        found = self.stop_of(task_id)
        if found is None:
            return None
        order, index = found
        if index == 0 and order.id not in self._started:
            self._started.add(order.id)
            self._records[order.id].started = time
        return found

    def served(self, order_id: str, index: int, time: float) -> bool:
        """The vehicle dwelt at stop ``index``: True when that completed the order."""
        record = self._records[order_id]
        record.served.append(time)
        tasks = self._tasks.get(order_id, [])
        for task in [t for t in tasks if t.stop == index]:
            tasks.remove(task)
            del self._stop_of[task.id]
        if len(record.served) < len(record.order.stops):
            return False
        record.completed = time
        self._completed.add(order_id)
        del self._open[order_id]
        self._tasks.pop(order_id, None)
        holder = self._holder.pop(order_id, None)
        if holder is not None:
            self._sequences[holder].remove(order_id)
            if not self._sequences[holder]:
                self._holding.discard(holder)
            self.version += 1
        self._started.discard(order_id)
        return True
