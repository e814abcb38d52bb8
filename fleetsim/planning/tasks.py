"""Task bookkeeping (the thesis's fleet controller): per-vehicle FIFO queues, routed status, completion.

Each vehicle works through its tasks in file order. The head task is *unrouted* until an accepted plan
marks a leg as its goal, then *routed*; it is *completed* when the vehicle enters that leg (or is on it
when the plan is accepted). Completed tasks leave the queue at the next bookkeeping. A vehicle with an
empty queue has no more tasks and is not consulted again.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable, Mapping
from collections.abc import Set as AbstractSet
from types import MappingProxyType

from fleetsim.planning.plans import FleetPlan
from fleetsim.planning.views import LiveKeys
from fleetsim.scenario import Task

__all__ = ["TaskBook"]


class TaskBook:
    """The mutable task state of one run; the simulation owns it."""

    def __init__(self, tasks: Iterable[Task], vehicle_ids: Iterable[int]) -> None:
        self._queues: dict[int, deque[Task]] = {vid: deque() for vid in sorted(vehicle_ids)}
        self._tasks: dict[int, Task] = {}
        for task in tasks:  # file order: the queue order
            self._queues[task.vehicle_id].append(task)
            self._tasks[task.id] = task
        # The routed tasks, as an insertion-ordered set (a dict's keys), and the read-only copy snapshots
        # show, brought up to date by what changed (a large fleet routes tasks many times a step).
        self._routed: dict[int, None] = {}
        self._routed_copy = LiveKeys(self._routed)
        # Whether a task is routed: the dict's own lookup (asked on every planner call).
        self.is_routed: Callable[[int], bool] = self._routed.__contains__
        self.routed_now: AbstractSet[int] = self._routed.keys()  # live, read-only: for checks made at once
        self._completed: dict[int, float] = {}  # task id -> sim time of completion
        # Read-only views handed out on every planner call, rebuilt only after a change.
        self._queues_view: Mapping[int, tuple[Task, ...]] | None = None
        self._heads: Mapping[int, Task] | None = None  # heads(), until a queue changes
        self._undropped = False  # a task completed since the last drop_completed()

    # -- queries -------------------------------------------------------------------------------------

    def queue(self, vehicle_id: int) -> tuple[Task, ...]:
        return tuple(self._queues[vehicle_id])

    def queues(self) -> Mapping[int, tuple[Task, ...]]:
        """Every vehicle's queue, head first (a read-only copy, shared until a queue changes)."""
        if self._queues_view is None:
            self._queues_view = MappingProxyType({vid: tuple(queue) for vid, queue in self._queues.items()})
        return self._queues_view

    def head(self, vehicle_id: int) -> Task | None:
        queue = self._queues[vehicle_id]
        return queue[0] if queue else None

    @property
    def routed(self) -> AbstractSet[int]:
        """The routed tasks now, as a read-only set that never changes (a new one after a change)."""
        return self._routed_copy.keys(exclusive=False)

    def routed_for_snapshot(self, exclusive: bool) -> AbstractSet[int]:
        """:attr:`routed` for the next snapshot; ``exclusive``: nobody but the caller holds the last
        snapshot, so the set it showed may be brought up to date in place (planning/views.py)."""
        return self._routed_copy.keys(exclusive)

    def is_completed(self, task_id: int) -> bool:
        return task_id in self._completed

    def completed(self) -> Mapping[int, float]:
        """Completed task ids with their completion times, in completion order."""
        return MappingProxyType(dict(self._completed))

    def heads(self) -> Mapping[int, Task]:
        """Each vehicle with tasks still queued, ascending, and its head task (shared until a queue changes)."""
        if self._heads is None:
            self._heads = MappingProxyType({vid: queue[0] for vid, queue in self._queues.items() if queue})
        return self._heads

    def busy_vehicles(self) -> tuple[int, ...]:
        """Vehicles with tasks still queued, ascending."""
        return tuple(self.heads())

    def pending(self) -> tuple[Task, ...]:
        """Tasks not yet completed, by task id."""
        return tuple(task for task_id, task in sorted(self._tasks.items()) if task_id not in self._completed)

    @property
    def total(self) -> int:
        return len(self._tasks)

    def all_done(self) -> bool:
        return len(self._completed) == len(self._tasks)

    # -- changes -------------------------------------------------------------------------------------

    def mark_routed(self, plan: FleetPlan) -> None:
        """An accepted plan routes every task it marks as a goal."""
        for leg in plan.legs:
            if leg.goal_for_task is not None and leg.goal_for_task not in self._routed:
                self._routed[leg.goal_for_task] = None
                self._routed_copy.changed(leg.goal_for_task)

    def complete(self, task_id: int, time: float) -> bool:
        """The vehicle entered (or stands on) the task's goal leg: True unless the task was completed
        already or is not (any longer) queued (a withdrawn task's goal marker may still be driven over)."""
        if task_id in self._tasks and task_id not in self._completed:
            self._completed[task_id] = time
            self._undropped = True
            return True
        return False

    def append(self, tasks: Iterable[Task]) -> None:
        """Queue new tasks (a dispatcher's assignment), each at the tail of its vehicle's queue."""
        for task in tasks:
            self._queues[task.vehicle_id].append(task)
            self._tasks[task.id] = task
        self._queues_view = None
        self._heads = None

    def withdraw(self, vehicle_id: int, task_ids: Iterable[int]) -> None:
        """Take tasks not yet completed out of the vehicle's queue (an order taken back); they are forgotten."""
        gone = set(task_ids)
        if not gone:
            return
        queue = self._queues[vehicle_id]
        kept = [task for task in queue if task.id not in gone]
        queue.clear()
        queue.extend(kept)
        for task_id in sorted(gone):
            self._tasks.pop(task_id, None)
            if task_id in self._routed:
                del self._routed[task_id]
                self._routed_copy.changed(task_id)
        self._queues_view = None
        self._heads = None

    def drop_completed(self) -> tuple[Task, ...]:
        """Bookkeeping at the start of a step: completed tasks leave their queues (returned)."""
        if not self._undropped:
            return ()
        self._undropped = False
        dropped = []
        for queue in self._queues.values():
            while queue and queue[0].id in self._completed:
                dropped.append(queue.popleft())
        if dropped:
            self._queues_view = None
            self._heads = None
            # Routed names queued tasks only (so it stays as large as the fleet's queues, not its history).
            for task in dropped:
                if task.id in self._routed:
                    del self._routed[task.id]
                    self._routed_copy.changed(task.id)
        return tuple(dropped)
