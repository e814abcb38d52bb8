"""The fleet snapshot planners receive (SPEC §6): read-only, frozen, detached from later changes."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

import fleetsim
from fleetsim.enums import Direction, Progress, Shape, Traverse
from fleetsim.layout import Segment
from fleetsim.load.tiled.writer import write_map
from fleetsim.planning import FleetController, FleetLeg, FleetPlan
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, Task


def _straight(sid: int, start: tuple[float, float], end: tuple[float, float]) -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, (start, end))


SEGMENTS = (
    _straight(1, (0.0, 0.0), (4.0, 0.0)),
    _straight(2, (4.0, 0.0), (8.0, 0.0)),
    _straight(3, (12.0, 0.0), (12.0, 4.0)),  # pointing +y
    _straight(4, (0.0, 8.0), (4.0, 8.0)),
    _straight(5, (0.0, 16.0), (3.0, 20.0)),  # pointing atan2(4, 3)
)
VEHICLES = """vehicle_id,start_segment_id,segment_orientation,progress_direction
1,1,forward,forward
2,3,backward,reverse
3,4,backward,forward
4,5,forward,reverse
"""
TASKS = """vehicle_id,goal_segment_id,goal_progress_direction
1,2,
2,3,reverse
1,1,
"""


@pytest.fixture(scope="module")
def scenario(tmp_path_factory: pytest.TempPathFactory) -> Scenario:
    folder: Path = tmp_path_factory.mktemp("snapshot")
    write_map(folder / "map.json", SEGMENTS)
    (folder / "vehicles.csv").write_text(VEHICLES, encoding="utf-8")
    (folder / "tasks.csv").write_text(TASKS, encoding="utf-8")
    return fleetsim.load_scenario_dir(folder)


@pytest.fixture()
def controller(scenario: Scenario) -> FleetController:
    return FleetController(scenario)


def test_the_snapshot_holds_time_states_plans_and_task_queues(controller: FleetController) -> None:
    fleet = controller.snapshot(2.5)
    assert fleet.time == 2.5
    assert sorted(fleet.vehicles) == sorted(fleet.plans) == sorted(fleet.tasks) == [1, 2, 3, 4]
    assert fleet.tasks[1] == (Task(1, 1, 2), Task(3, 1, 1))
    assert fleet.tasks[2] == (Task(2, 2, 3, Progress.REVERSE),)
    assert fleet.tasks[3] == ()
    assert fleet.routed == frozenset()


def test_every_vehicle_starts_with_its_start_segment_as_one_fixed_leg(controller: FleetController) -> None:
    fleet = controller.snapshot(0.0)
    assert fleet.plans[1] == FleetPlan(1, (FleetLeg(1, Traverse.FORWARD, Progress.FORWARD, True),))
    assert fleet.plans[2] == FleetPlan(2, (FleetLeg(3, Traverse.BACKWARD, Progress.REVERSE, True),))


@pytest.mark.parametrize(
    ("vehicle_id", "x", "y", "heading"),
    [
        (1, 0.0, 0.0, 0.0),  # forward traverse, nose first: travel direction
        (2, 12.0, 4.0, math.pi / 2),  # driving -y, backing: nose points +y
        (3, 4.0, 8.0, math.pi),  # driving -x, nose first
        (4, 0.0, 16.0, math.atan2(4.0, 3.0) - math.pi),  # driving up-right, backing
    ],
)
def test_a_vehicle_starts_at_rest_at_its_start_segments_entry_facing_its_nose_direction(
    controller: FleetController, vehicle_id: int, x: float, y: float, heading: float
) -> None:
    state = controller.snapshot(0.0).vehicles[vehicle_id]
    assert (state.x, state.y) == (pytest.approx(x, abs=1e-9), pytest.approx(y, abs=1e-9))
    assert (math.cos(state.heading), math.sin(state.heading)) == (
        pytest.approx(math.cos(heading), abs=1e-9),
        pytest.approx(math.sin(heading), abs=1e-9),
    )
    assert -math.pi <= state.heading <= math.pi
    assert (state.speed, state.distance) == (0.0, 0.0)
    assert state.type == DEFAULT_VEHICLE_TYPE


def test_a_vehicles_state_names_its_leg(controller: FleetController) -> None:
    state = controller.snapshot(0.0).vehicles[2]
    assert (state.id, state.segment, state.traverse, state.progress) == (2, 3, Traverse.BACKWARD, Progress.REVERSE)


def test_snapshot_mappings_are_read_only(controller: FleetController) -> None:
    fleet = controller.snapshot(0.0)
    with pytest.raises(TypeError):
        fleet.vehicles[1] = fleet.vehicles[2]  # type: ignore[index]
    with pytest.raises(TypeError):
        fleet.plans[1] = fleet.plans[2]  # type: ignore[index]
    with pytest.raises(TypeError):
        fleet.tasks[3] = fleet.tasks[1]  # type: ignore[index]
    with pytest.raises(TypeError):
        del fleet.plans[1]  # type: ignore[attr-defined]


def test_snapshot_and_vehicle_states_are_frozen(controller: FleetController) -> None:
    fleet = controller.snapshot(0.0)
    with pytest.raises(AttributeError):
        fleet.vehicles[1].speed = 3.0  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        fleet.time = 1.0  # type: ignore[misc]
    with pytest.raises(AttributeError):
        fleet.routed.add(1)  # type: ignore[attr-defined]


def test_later_controller_changes_do_not_show_through_an_earlier_snapshot(controller: FleetController) -> None:
    fleet = controller.snapshot(0.0)
    before = (dict(fleet.vehicles), dict(fleet.plans), dict(fleet.tasks), fleet.routed)
    moved = fleet.vehicles[1]._replace(distance=1.5, speed=0.5, x=1.5)
    longer = FleetPlan(
        1, (*fleet.plans[1].legs, FleetLeg(2, Traverse.FORWARD, Progress.FORWARD, True, goal_for_task=1))
    )
    controller.set_state(moved)
    controller.set_plan(longer)
    controller.tasks.mark_routed(longer)
    controller.tasks.complete(1, 0.5)
    controller.tasks.drop_completed()
    assert (dict(fleet.vehicles), dict(fleet.plans), dict(fleet.tasks), fleet.routed) == before
    later = controller.snapshot(1.0)
    assert later.vehicles[1] == moved
    assert later.plans[1] == longer
    assert later.tasks[1] == (Task(3, 1, 1),)


def test_head_task_is_the_first_queued_task_or_none(controller: FleetController) -> None:
    fleet = controller.snapshot(0.0)
    assert fleet.head_task(1) == Task(1, 1, 2)
    assert fleet.head_task(3) is None
    assert fleet.head_task(99) is None


def test_routed_tasks_are_the_queued_tasks_an_accepted_plan_marks(controller: FleetController) -> None:
    plan = FleetPlan(
        1,
        (
            FleetLeg(1, Traverse.FORWARD, Progress.FORWARD, True),
            FleetLeg(2, Traverse.FORWARD, Progress.FORWARD, False, goal_for_task=1),
        ),
    )
    controller.tasks.mark_routed(plan)
    fleet = controller.snapshot(0.0)
    assert fleet.routed_tasks(1) == (Task(1, 1, 2),)
    assert fleet.is_routed(Task(1, 1, 2))
    assert not fleet.is_routed(Task(3, 1, 1))
    assert fleet.routed_tasks(2) == ()
    assert fleet.routed_tasks(3) == ()
