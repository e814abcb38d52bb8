"""Snapshots share their copies of the fleet while nobody else holds them (planning/views.py).

A planning round changes one plan at a time; the snapshot's copies are then brought up to date in place
instead of copied whole, but only while the controller alone holds the last snapshot, its mappings and
the dicts under them. Whatever a planner keeps must never change under it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from collections.abc import Set as AbstractSet
from pathlib import Path

import pytest

import fleetsim
from fleetsim.enums import Direction, Progress, Shape, Traverse
from fleetsim.layout import Segment
from fleetsim.load.tiled.writer import write_map
from fleetsim.planning import FleetController, FleetLeg, FleetPlan, views
from fleetsim.scenario import Scenario, Task

VEHICLES = 16


@pytest.fixture(scope="module")
def scenario(tmp_path_factory: pytest.TempPathFactory) -> Scenario:
    # Each vehicle on a segment of its own, with a second segment ahead of it.
    folder: Path = tmp_path_factory.mktemp("sharing")
    segments = []
    for index in range(VEHICLES):
        y = 10.0 * index
        segments.append(Segment(2 * index + 1, Shape.STRAIGHT, Direction.BOTH, ((0.0, y), (4.0, y))))
        segments.append(Segment(2 * index + 2, Shape.STRAIGHT, Direction.BOTH, ((4.0, y), (8.0, y))))
    write_map(folder / "map.json", segments)
    rows = [f"{index + 1},{2 * index + 1},forward,forward" for index in range(VEHICLES)]
    vehicles = "vehicle_id,start_segment_id,segment_orientation,progress_direction\n" + "\n".join(rows) + "\n"
    (folder / "vehicles.csv").write_text(vehicles, encoding="utf-8")
    tasks = "vehicle_id,goal_segment_id,goal_progress_direction\n1,2,\n"
    (folder / "tasks.csv").write_text(tasks, encoding="utf-8")
    return fleetsim.load_scenario_dir(folder)


@pytest.fixture()
def controller(scenario: Scenario) -> FleetController:
    return FleetController(scenario)


def _longer(controller: FleetController, vehicle: int) -> FleetPlan:
    """The vehicle's plan with the segment ahead added as a planned leg."""
    plan = controller.plans[vehicle]
    return FleetPlan(vehicle, (*plan.legs, FleetLeg(2 * vehicle, Traverse.FORWARD, Progress.FORWARD, False)))


def _plans_id(controller: FleetController, time: float) -> int:
    """The id of the plans mapping of the snapshot at ``time``, keeping no reference to it."""
    return id(controller.snapshot(time).plans)


def test_a_change_nobody_else_sees_updates_the_shared_copy_in_place(controller: FleetController) -> None:
    first = _plans_id(controller, 0.0)
    longer = _longer(controller, 3)
    controller.set_plan(longer)
    fleet = controller.snapshot(0.0)
    assert id(fleet.plans) == first  # brought up to date, not copied
    assert fleet.plans[3] == longer
    assert dict(fleet.plans) == dict(controller.plans)


def test_a_kept_snapshot_never_changes_and_the_next_is_a_new_copy(controller: FleetController) -> None:
    kept = controller.snapshot(0.0)
    before = dict(kept.plans)
    longer = _longer(controller, 3)
    controller.set_plan(longer)
    later = controller.snapshot(0.0)
    assert later.plans is not kept.plans
    assert dict(kept.plans) == before
    assert later.plans[3] == longer


def test_a_kept_mapping_never_changes(controller: FleetController) -> None:
    plans = controller.snapshot(0.0).plans
    vehicles = controller.snapshot(0.0).vehicles
    before = (dict(plans), dict(vehicles))
    controller.set_plan(_longer(controller, 3))
    controller.set_state(controller.states[3]._replace(x=1.0, distance=1.0))
    controller.snapshot(0.1)
    assert (dict(plans), dict(vehicles)) == before


def test_a_kept_iterator_or_view_never_changes(controller: FleetController) -> None:
    items = controller.snapshot(0.0).plans.items()
    values: Iterator[FleetPlan] = iter(controller.snapshot(0.0).plans.values())
    before = list(items)
    controller.set_plan(_longer(controller, 1))
    controller.snapshot(0.0)
    assert list(items) == before
    assert list(values) == [plan for _, plan in before]


def test_a_snapshot_at_a_new_time_after_a_state_change_shows_it(controller: FleetController) -> None:
    first = id(controller.snapshot(0.0).vehicles)
    moved = controller.states[5]._replace(x=2.0, distance=2.0, speed=0.5)
    controller.set_state(moved)
    fleet = controller.snapshot(0.1)
    assert id(fleet.vehicles) == first
    assert fleet.vehicles[5] == moved
    assert fleet.time == 0.1


def test_many_changes_at_once_make_a_fresh_copy(controller: FleetController) -> None:
    first = _plans_id(controller, 0.0)
    for vehicle in range(1, VEHICLES // 2 + 1):
        controller.set_plan(_longer(controller, vehicle))
    fleet = controller.snapshot(0.0)
    assert id(fleet.plans) != first
    assert dict(fleet.plans) == dict(controller.plans)


def test_without_reference_counts_every_change_makes_a_fresh_copy(
    controller: FleetController, monkeypatch: pytest.MonkeyPatch
) -> None:
    # (Not CPython, say.) Nothing counts as held only here, so every view after a change is a new copy.
    monkeypatch.setattr(views, "_refcount", None)
    controller.snapshot(0.0)
    assert not views.held_only_here(controller, "_snapshot")
    controller.set_plan(_longer(controller, 3))
    fleet = controller.snapshot(0.0)
    assert fleet.plans[3] == controller.plans[3]
    assert dict(fleet.plans) == dict(controller.plans)


def test_held_only_here_counts_every_other_holder() -> None:
    class Holder:
        def __init__(self) -> None:
            self.thing: object = object()

    holder = Holder()
    assert views.held_only_here(holder, "thing")
    extra = [holder.thing]
    assert not views.held_only_here(holder, "thing")
    assert views.held_only_here(holder, "thing", others=1)
    extra.clear()
    assert views.held_only_here(holder, "thing")


# -- the routed set: the same rules for fleet.routed (a read-only set) -----------------------------------


@pytest.fixture()
def busy(scenario: Scenario) -> FleetController:
    """Sixteen vehicles with one task each (task i is vehicle i's, to segment 2i)."""
    tasks = tuple(Task(i, i, 2 * i, None) for i in range(1, VEHICLES + 1))
    return FleetController(dataclasses.replace(scenario, tasks=tasks))


def _route(controller: FleetController, *tasks: int) -> None:
    for task in tasks:
        plan = FleetPlan(
            task, (*controller.plans[task].legs, FleetLeg(2 * task, Traverse.FORWARD, Progress.FORWARD, False, task))
        )
        controller.tasks.mark_routed(plan)
        controller.set_plan(plan)


def _routed_id(controller: FleetController, time: float) -> int:
    """The id of the routed set of the snapshot at ``time``, keeping no reference to it."""
    return id(controller.snapshot(time).routed)


def test_the_routed_set_nobody_else_holds_is_brought_up_to_date_in_place(busy: FleetController) -> None:
    _route(busy, *range(1, 13))
    first = _routed_id(busy, 0.0)
    _route(busy, 13)
    assert _routed_id(busy, 0.0) == first and 13 in busy.snapshot(0.0).routed
    busy.tasks.complete(2, 1.0)
    busy.bookkeeping()  # a done task leaves the set: deleted in place too
    routed = busy.snapshot(0.1).routed
    assert id(routed) == first
    assert sorted(routed) == [1, *range(3, 14)] == sorted(busy.tasks.routed_now)


def test_a_kept_routed_set_or_iterator_never_changes(busy: FleetController) -> None:
    _route(busy, *range(1, 13))
    kept = busy.snapshot(0.0).routed
    _route(busy, 13)
    later = busy.snapshot(0.0).routed
    assert later is not kept and 13 in later and 13 not in kept
    walking = iter(later)
    del later
    _route(busy, 14)
    assert 14 in busy.snapshot(0.0).routed
    assert sorted(walking) == list(range(1, 14))  # the iterator's set was copied, not changed under it


def test_a_kept_snapshot_keeps_its_routed_set(controller: FleetController) -> None:
    route = FleetPlan(1, (*controller.plans[1].legs, FleetLeg(2, Traverse.FORWARD, Progress.FORWARD, False, 1)))
    kept = controller.snapshot(0.0)
    controller.tasks.mark_routed(route)
    controller.set_plan(route)
    later = controller.snapshot(0.0)
    assert (set(kept.routed), set(later.routed)) == (set(), {1})
    assert later.is_routed(controller.tasks.head(1)) and not kept.is_routed(controller.tasks.head(1))


def test_the_routed_set_is_a_read_only_set(busy: FleetController) -> None:
    _route(busy, 1, 2)
    routed = busy.snapshot(0.0).routed
    assert isinstance(routed, AbstractSet) and routed == {1, 2} and routed | {3} == {1, 2, 3}
    assert not hasattr(routed, "add") and not hasattr(routed, "discard")
