"""A run tunes the cyclic garbage collector while it goes and puts it back however it ends (sim/loop.py)."""

from __future__ import annotations

import gc
import threading
from pathlib import Path

from scenario_factory import make_scenario

from fleetsim.enums import Direction, Shape
from fleetsim.layout import Segment
from fleetsim.layout.layout import Layout
from fleetsim.planners import BFSPlanner
from fleetsim.planning.plans import Response
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Scenario, Task
from fleetsim.sim.loop import _COLLECTOR, run_scenario


def _corridor(tmp_path: Path) -> Scenario:
    segments = tuple(
        Segment(i, Shape.STRAIGHT, Direction.BOTH, ((4.0 * i, 0.0), (4.0 * i + 4.0, 0.0))) for i in (1, 2, 3)
    )
    return make_scenario(tmp_path, segments, "1,1,forward,,\n", "1,3,\n")


class _Watching(BFSPlanner):
    """Notes what the collector looks like during its calls; raises on its third when told to."""

    def __init__(self, fail: bool = False) -> None:
        super().__init__()
        self.seen: list[tuple[tuple[int, int, int], int]] = []
        self.fail = fail

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        # (Counting the frozen objects walks them all: the whole heap of a process that ran many tests. The
        # first calls are enough.)
        if len(self.seen) < 3:
            self.seen.append((gc.get_threshold(), gc.get_freeze_count()))
        if self.fail and len(self.seen) == 3:
            raise RuntimeError("planner bug")
        return super().fix_legs(task, fleet, layout)


def test_during_a_run_what_existed_is_set_aside_and_the_young_generation_grows_with_the_fleet(
    tmp_path: Path,
) -> None:
    before = (gc.get_threshold(), gc.get_freeze_count())
    planner = _Watching()
    result = run_scenario(_corridor(tmp_path), planner)
    assert result.ended == "completed"
    threshold, frozen = planner.seen[0]
    assert frozen > 0
    assert threshold[0] == max(before[0][0], _COLLECTOR.OBJECTS_PER_VEHICLE * 1)
    assert threshold[1:] == before[0][1:]
    assert (gc.get_threshold(), gc.get_freeze_count()) == before


def test_a_run_that_ends_in_a_planner_error_puts_the_collector_back(tmp_path: Path) -> None:
    original = gc.get_threshold()
    gc.set_threshold(5, 7, 9)
    try:
        planner = _Watching(fail=True)
        result = run_scenario(_corridor(tmp_path), planner)
        assert result.ended == "planner-error"
        assert planner.seen[0][0] == (_COLLECTOR.OBJECTS_PER_VEHICLE, 7, 9)
        assert (gc.get_threshold(), gc.get_freeze_count()) == ((5, 7, 9), 0)
    finally:
        gc.set_threshold(*original)


def test_overlapping_runs_in_threads_put_the_collector_back_when_the_last_ends() -> None:
    before = (gc.get_threshold(), gc.get_freeze_count())
    first_in, second_done = threading.Event(), threading.Event()
    seen_after_second: list[int] = []

    def first() -> None:
        with _COLLECTOR.spared(10_000):
            first_in.set()
            second_done.wait(5.0)
            seen_after_second.append(gc.get_threshold()[0])

    thread = threading.Thread(target=first)
    thread.start()
    first_in.wait(5.0)
    with _COLLECTOR.spared(100):
        assert gc.get_threshold()[0] == _COLLECTOR.OBJECTS_PER_VEHICLE * 10_000
    second_done.set()
    thread.join()
    assert seen_after_second == [
        _COLLECTOR.OBJECTS_PER_VEHICLE * 10_000
    ]  # still the larger fleet's after the other run ended
    assert (gc.get_threshold(), gc.get_freeze_count()) == before
