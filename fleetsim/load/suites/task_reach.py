"""The static task check of scenario loading: every task's goal must be reachable (issue 15, point 4).

A vehicle does its tasks in file order. Its first task starts where the vehicle starts; every later one
starts wherever the previous task may have left it: on that task's goal segment, entered in any way the
layout, the one-way directions, the progress rules of the vehicle's turn capability and that task's goal
direction allow. A task whose goal cannot be reached from there is an
:class:`~fleetsim.errors.UnreachableTaskError` naming its row of ``tasks.csv``, the task, the vehicle,
where it starts from and the most specific reason (:mod:`fleetsim.layout.unreachable`).

"Reachable" is "some planner could do it": the check fails only when no route exists at all, so a
scenario it accepts may still defeat a planner that arrives at one goal in a way that leads nowhere next.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from fleetsim.enums import TurnCapability
from fleetsim.errors import Location, UnreachableTaskError
from fleetsim.layout.layout import Layout
from fleetsim.layout.reachability import Reach, ReachIndex, State, arrivals, goal_states, reach, state_text
from fleetsim.layout.unreachable import why_unreachable
from fleetsim.scenario import Task, Vehicle

__all__ = ["check_tasks_reachable"]


def check_tasks_reachable(
    layout: Layout, vehicles: Iterable[Vehicle], tasks: Iterable[tuple[Task, int]], tasks_path: Path
) -> None:
    """Raise :class:`~fleetsim.errors.UnreachableTaskError` for the first task (in file order) whose
    vehicle cannot reach its goal; ``tasks`` pairs each task with its line in ``tasks_path``."""
    by_id = {vehicle.id: vehicle for vehicle in vehicles}
    # Where each vehicle may be now, and the task that left it there (None: it has not moved yet).
    here: dict[int, tuple[frozenset[State], Task | None]] = {
        vid: (frozenset({(v.start_segment, v.traverse, v.progress)}), None) for vid, v in by_id.items()
    }
    indexes: dict[TurnCapability, ReachIndex] = {}  # built on first use: one pass over the map each
    for task, line in tasks:
        vehicle = by_id[task.vehicle_id]
        starts, previous = here[vehicle.id]
        capability = vehicle.type.turn_capability
        index = indexes.get(capability)
        if index is None:
            index = indexes[capability] = ReachIndex(layout, capability)
        entered = index.entered(starts, goal_states(layout, task.goal_segment))
        arrived = arrivals(starts, entered, task.goal_segment, task.goal_progress)
        if not arrived:
            where = reach(layout, capability, starts)  # the whole picture, for the reason
            location = Location(tasks_path, line, field="goal_segment_id")
            raise _unreachable(layout, where, task, vehicle, previous, location)
        here[vehicle.id] = (arrived, task)


def _unreachable(
    layout: Layout, where: Reach, task: Task, vehicle: Vehicle, previous: Task | None, location: Location
) -> UnreachableTaskError:
    if previous is None:
        (start,) = where.starts
        origin = f"from its start on {state_text(start)}"
    else:
        arriving = f", arriving {previous.goal_progress.value}" if previous.goal_progress is not None else ""
        origin = f"from the goal of task {previous.id} (segment {previous.goal_segment}{arriving})"
    arrive = f" arriving {task.goal_progress.value}" if task.goal_progress is not None else ""
    reason = why_unreachable(layout, where, task.goal_segment, task.goal_progress, vehicle.type.name)
    msg = (
        f"vehicle {vehicle.id} cannot reach segment {task.goal_segment}{arrive}, the goal of task {task.id}, "
        f"{origin}: {reason}"
    )
    return UnreachableTaskError(msg, location, task_id=task.id, vehicle_id=vehicle.id, goal_segment=task.goal_segment)
