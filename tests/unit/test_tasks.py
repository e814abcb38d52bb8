"""Task bookkeeping: FIFO queues per vehicle, routed marking, completion and dropping at bookkeeping."""

from __future__ import annotations

import pytest

from fleetsim.enums import Progress, Traverse
from fleetsim.planning import FleetLeg, FleetPlan, TaskBook
from fleetsim.scenario import Task

# File order: tasks 1..5, interleaving vehicles 7 and 3; vehicle 5 has none.
TASKS = (
    Task(1, 7, 10),
    Task(2, 3, 11),
    Task(3, 7, 12, Progress.REVERSE),
    Task(4, 3, 13),
    Task(5, 7, 14),
)


def _book() -> TaskBook:
    return TaskBook(TASKS, [7, 5, 3])


def _leg(segment: int, goal: int | None = None) -> FleetLeg:
    return FleetLeg(segment, Traverse.FORWARD, Progress.FORWARD, fixed=False, goal_for_task=goal)


def test_each_vehicle_queues_its_tasks_in_file_order() -> None:
    book = _book()
    assert book.queue(7) == (TASKS[0], TASKS[2], TASKS[4])
    assert book.queue(3) == (TASKS[1], TASKS[3])
    assert book.queue(5) == ()
    assert (book.head(7), book.head(3), book.head(5)) == (TASKS[0], TASKS[1], None)


def test_queues_lists_every_vehicle_by_id_as_a_read_only_copy() -> None:
    book = _book()
    queues = book.queues()
    assert list(queues) == [3, 5, 7]
    assert queues[5] == ()
    with pytest.raises(TypeError):
        queues[5] = (TASKS[0],)  # type: ignore[index]
    book.complete(2, 1.0)
    book.drop_completed()
    assert queues[3] == (TASKS[1], TASKS[3])


def test_busy_vehicles_are_those_with_queued_tasks_in_ascending_id() -> None:
    assert _book().busy_vehicles() == (3, 7)


def test_heads_give_each_busy_vehicle_its_head_task_by_id_until_bookkeeping_drops_it() -> None:
    book = _book()
    heads = book.heads()
    assert list(heads.items()) == [(3, TASKS[1]), (7, TASKS[0])]
    with pytest.raises(TypeError):
        heads[3] = TASKS[3]  # type: ignore[index]
    book.complete(1, 1.0)
    book.complete(2, 1.0)
    book.complete(4, 1.0)
    assert book.heads() is heads  # completed, still queued until bookkeeping
    book.drop_completed()
    assert list(book.heads().items()) == [(7, TASKS[2])]
    assert list(heads.items()) == [(3, TASKS[1]), (7, TASKS[0])]  # a view handed out earlier stays as it was


def test_a_plan_routes_every_task_it_marks_as_a_goal() -> None:
    book = _book()
    assert book.routed == frozenset()
    book.mark_routed(FleetPlan(7, (_leg(1), _leg(10, goal=1), _leg(2), _leg(12, goal=3))))
    assert book.routed == {1, 3}
    assert book.is_routed(1) and book.is_routed(3) and not book.is_routed(5)
    assert book.queue(7) == (TASKS[0], TASKS[2], TASKS[4])  # routing leaves the queue alone


def test_a_completed_task_leaves_the_routed_set_when_it_leaves_its_queue() -> None:
    book = _book()
    book.mark_routed(FleetPlan(7, (_leg(10, goal=1), _leg(12, goal=3))))
    book.complete(1, 2.5)
    assert book.routed == {1, 3}  # still queued until bookkeeping
    book.drop_completed()
    assert book.routed == {3}
    assert not book.is_routed(1) and book.is_routed(3)


def test_a_plan_without_goal_markers_routes_nothing() -> None:
    book = _book()
    book.mark_routed(FleetPlan(7, (_leg(1), _leg(2))))
    assert book.routed == frozenset()


def test_a_completed_task_stays_queued_until_bookkeeping_drops_it() -> None:
    book = _book()
    book.complete(1, 2.5)
    assert book.is_completed(1)
    assert book.head(7) == TASKS[0]
    assert book.drop_completed() == (TASKS[0],)
    assert book.head(7) == TASKS[2]
    assert book.drop_completed() == ()


def test_completion_keeps_the_first_time_in_completion_order() -> None:
    book = _book()
    book.complete(2, 1.0)
    book.complete(1, 3.0)
    book.complete(2, 9.0)
    assert list(book.completed().items()) == [(2, 1.0), (1, 3.0)]


def test_a_completed_task_behind_an_unfinished_head_is_dropped_only_with_the_head() -> None:
    book = _book()
    book.complete(3, 1.0)
    assert book.drop_completed() == ()
    assert book.queue(7) == (TASKS[0], TASKS[2], TASKS[4])
    book.complete(1, 2.0)
    assert book.drop_completed() == (TASKS[0], TASKS[2])
    assert book.queue(7) == (TASKS[4],)


def test_pending_lists_uncompleted_tasks_by_id_until_all_are_done() -> None:
    book = _book()
    assert book.total == 5
    assert book.pending() == TASKS
    for task_id in (4, 1, 2):
        book.complete(task_id, 1.0)
    assert book.pending() == (TASKS[2], TASKS[4])
    assert not book.all_done()
    book.complete(3, 2.0)
    book.complete(5, 3.0)
    assert book.pending() == ()
    assert book.all_done()
    assert book.total == 5


def test_a_vehicle_whose_tasks_are_done_has_no_more_tasks_and_is_not_busy() -> None:
    book = _book()
    book.complete(2, 1.0)
    book.complete(4, 2.0)
    assert book.busy_vehicles() == (3, 7)  # not until bookkeeping
    book.drop_completed()
    assert book.head(3) is None
    assert book.queue(3) == ()
    assert book.busy_vehicles() == (7,)


def test_a_run_without_tasks_is_all_done_from_the_start() -> None:
    book = TaskBook((), [1, 2])
    assert (book.total, book.pending(), book.all_done(), book.busy_vehicles()) == (0, (), True, ())
    assert book.head(1) is None
