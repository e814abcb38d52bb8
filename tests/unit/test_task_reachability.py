"""Loading refuses a task whose goal its vehicle cannot reach, naming the row and the nearest reason."""

from __future__ import annotations

from pathlib import Path

import pytest
from scenario_factory import make_scenario

from fleetsim.enums import Direction, Shape
from fleetsim.errors import ScenarioFileError, UnreachableTaskError
from fleetsim.layout import Segment


def straight(sid: int, a: tuple[float, float], b: tuple[float, float], direction: str = "both") -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction(direction), (a, b))


def refused(folder: Path, segments: tuple[Segment, ...], vehicles: str, tasks: str) -> UnreachableTaskError:
    with pytest.raises(UnreachableTaskError) as caught:
        make_scenario(folder, segments, vehicles, tasks)
    return caught.value


# Two straights in a line whose facing ends are 0.5 m apart.
GAP = (straight(1, (-4.25, 0.0), (-0.25, 0.0)), straight(2, (0.25, 0.0), (4.25, 0.0)))
# The same with the ends 0.04 m apart: within the 0.05 m connection tolerance, so they connect.
CLOSED = (straight(1, (-4.02, 0.0), (-0.02, 0.0)), straight(2, (0.02, 0.0), (4.02, 0.0)))

# Segment 2 leaves the end of segment 1 at a cusp (about 14° between them); both are one-way, so a
# vehicle that only follows curves enters 2 backing, and nothing leads back.
CUSP = (
    straight(1, (0.0, 0.0), (4.0, 0.0), "forward"),
    straight(2, (4.0, 0.0), (0.0, 1.0), "forward"),
)

# A two-way straight, then a one-way straight away from it: a vehicle on 2 can only drive off its end.
DEAD_END = (straight(1, (0.0, 0.0), (4.0, 0.0)), straight(2, (4.0, 0.0), (8.0, 0.0), "forward"))

# A one-way straight into a one-way corner.
ONE_WAY_CORNER = (
    straight(1, (0.0, 0.0), (4.0, 0.0), "forward"),
    straight(2, (4.0, 0.0), (4.0, 4.0), "forward"),
)

# Two two-way straights in a line, then a corner at (8, 0) up to segment 3.
CORNER = (straight(1, (0.0, 0.0), (4.0, 0.0)), straight(2, (4.0, 0.0), (8.0, 0.0)), straight(3, (8.0, 0.0), (8.0, 4.0)))


def one_way_into(direction: str) -> tuple[Segment, ...]:
    """Segment 2 leads one-way to (8, 0), where segment 3 (of ``direction``) begins."""
    return (
        straight(1, (0.0, 0.0), (4.0, 0.0)),
        straight(2, (4.0, 0.0), (8.0, 0.0), "forward"),
        straight(3, (8.0, 0.0), (12.0, 0.0), direction),
    )


# -- the goal lies in a part of the map not connected to the start ---------------------------------


def test_a_goal_across_a_gap_names_the_row_task_vehicle_start_closest_dangling_end_and_distance(tmp_path: Path) -> None:
    error = refused(tmp_path, GAP, "1,1,forward,,\n", "1,2,\n")
    assert str(error) == (
        f"{tmp_path / 'tasks.csv'}:2: field 'goal_segment_id': vehicle 1 cannot reach segment 2, the goal of "
        "task 1, from its start on segment 1 (driven forward, progress forward): segment 2 lies in a part of "
        "the map that is not connected to the part the vehicle can drive in; the closest dangling end is the "
        "last end of segment 1 at (-0.250, 0.000), 0.50 m from the first end of segment 2 at (0.250, 0.000)"
    )
    assert (error.task_id, error.vehicle_id, error.goal_segment) == (1, 1, 2)
    assert isinstance(error, ScenarioFileError) and isinstance(error, ValueError)


def test_the_same_goal_loads_once_the_gap_is_closed_to_within_the_connection_tolerance(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path, CLOSED, "1,1,forward,,\n", "1,2,\n")
    assert [task.goal_segment for task in scenario.tasks] == [2]


def test_the_refusal_carries_the_maps_lint_with_the_gap(tmp_path: Path) -> None:
    error = refused(tmp_path, GAP, "1,1,forward,,\n", "1,2,\n")
    gaps = [note for note in error.notes if note.startswith("warning gap:")]
    assert gaps == [
        "warning gap: the last end of segment 1 at (-0.250, 0.000) is a dead end 0.50 m from the first end of "
        "segment 2 at (0.250, 0.000), within a vehicle length (1 m): did you mean to connect them?"
    ]


# -- reachable, but not with the progress the task asks for ----------------------------------------


def test_a_goal_only_entered_backing_refuses_a_forward_arrival_for_a_curve_vehicle(tmp_path: Path) -> None:
    error = refused(tmp_path, CUSP, "1,1,forward,forward,tugger\n", "1,2,forward\n")
    assert str(error).endswith(
        "vehicle 1 cannot reach segment 2 arriving forward, the goal of task 1, from its start on segment 1 "
        "(driven forward, progress forward): segment 2 can only be entered driving in reverse (backing), and "
        "the task asks for forward arrival"
    )


@pytest.mark.parametrize("arrival", ["reverse", ""])
def test_a_goal_only_entered_backing_is_fine_when_the_task_asks_for_reverse_or_either(
    tmp_path: Path, arrival: str
) -> None:
    make_scenario(tmp_path, CUSP, "1,1,forward,forward,tugger\n", f"1,2,{arrival}\n")


def test_a_vehicle_turning_in_place_may_arrive_forward_where_a_curve_vehicle_cannot(tmp_path: Path) -> None:
    make_scenario(tmp_path, CUSP, "1,1,forward,forward,agv\n", "1,2,forward\n")


def test_a_goal_on_the_start_with_the_other_progress_and_no_way_back_is_refused(tmp_path: Path) -> None:
    error = refused(tmp_path, DEAD_END, "1,2,forward,forward,tugger\n", "1,2,reverse\n")
    assert str(error).endswith(
        "no route leads back onto segment 2, and the vehicle is on it driving forward (nose first); "
        "the task asks for reverse arrival"
    )


@pytest.mark.parametrize("arrival", ["forward", ""])
def test_a_goal_on_the_start_is_reached_there_when_the_progress_matches(tmp_path: Path, arrival: str) -> None:
    make_scenario(tmp_path, DEAD_END, "1,2,forward,forward,tugger\n", f"1,2,{arrival}\n")


# -- the vehicle cannot leave where it is -----------------------------------------------------------


def test_a_vehicle_at_a_one_way_dead_end_cannot_reach_anything_else(tmp_path: Path) -> None:
    error = refused(tmp_path, DEAD_END, "1,2,forward,,\n", "1,1,\n")
    assert str(error).endswith(
        "from its start on segment 2 (driven forward, progress forward): no route leaves segment 2: no segment "
        "it may drive on to meets it at (8.000, 0.000) (a dead end)"
    )


def test_the_same_goal_is_reachable_from_the_other_segment(tmp_path: Path) -> None:
    make_scenario(tmp_path, DEAD_END, "1,1,backward,,\n", "1,2,\n")


def test_a_curve_vehicle_before_a_one_way_corner_is_stuck_naming_the_corner(tmp_path: Path) -> None:
    error = refused(tmp_path, ONE_WAY_CORNER, "1,1,forward,,tugger\n", "1,2,\n")
    assert str(error).endswith(
        "no route leaves segment 1: the only ways on are corners (onto segment 2) that need turning in place, "
        "and vehicle type 'tugger' only follows curves"
    )


def test_a_vehicle_turning_in_place_takes_the_same_corner(tmp_path: Path) -> None:
    make_scenario(tmp_path, ONE_WAY_CORNER, "1,1,forward,,agv\n", "1,2,\n")


# -- only a corner leads there ----------------------------------------------------------------------


def test_a_curve_vehicle_that_can_move_but_only_reach_the_goal_by_a_corner_is_told_which(tmp_path: Path) -> None:
    error = refused(tmp_path, CORNER, "1,1,forward,,tugger\n", "1,3,\n")
    assert str(error).endswith(
        "every route to segment 3 needs turning in place at a corner (the first from segment 2 onto "
        "segment 3), and vehicle type 'tugger' only follows curves"
    )


def test_an_in_place_vehicle_reaches_the_goal_behind_the_corner(tmp_path: Path) -> None:
    make_scenario(tmp_path, CORNER, "1,1,forward,,agv\n", "1,3,\n")


# -- one-way directions lead elsewhere --------------------------------------------------------------


def test_a_goal_beyond_a_one_way_segment_against_its_direction_is_refused(tmp_path: Path) -> None:
    error = refused(tmp_path, one_way_into("backward"), "1,1,forward,,\n", "1,3,\n")
    assert str(error).endswith("every route to segment 3 would drive against a one-way segment")


def test_the_goal_is_reachable_when_its_segment_is_two_way(tmp_path: Path) -> None:
    make_scenario(tmp_path, one_way_into("both"), "1,1,forward,,\n", "1,3,\n")


# -- later tasks start from the previous goal --------------------------------------------------------


def test_a_later_task_is_checked_from_the_previous_tasks_goal_and_names_its_own_row(tmp_path: Path) -> None:
    tasks = "# the vehicle may reach segment 2 but then goes nowhere\n1,2,\n1,1,\n"
    error = refused(tmp_path, DEAD_END, "1,1,forward,,\n", tasks)
    assert str(error) == (
        f"{tmp_path / 'tasks.csv'}:4: field 'goal_segment_id': vehicle 1 cannot reach segment 1, the goal of "
        "task 2, from the goal of task 1 (segment 2): no route leaves segment 2: no segment it may drive on to "
        "meets it at (8.000, 0.000) (a dead end)"
    )
    assert (error.task_id, error.vehicle_id) == (2, 1)


def test_the_same_goals_in_the_other_order_load(tmp_path: Path) -> None:
    scenario = make_scenario(tmp_path, DEAD_END, "1,1,forward,,\n", "1,1,\n1,2,\n")
    assert [task.goal_segment for task in scenario.tasks] == [1, 2]


def test_the_previous_tasks_goal_direction_limits_where_the_next_task_starts(tmp_path: Path) -> None:
    # The tugger reaches segment 2 of the cusp map only backing; asking task 2 for forward arrival on
    # the same segment (it is on it already, backing, and cannot come back) is refused from task 1's goal.
    error = refused(tmp_path, CUSP, "1,1,forward,forward,tugger\n", "1,2,reverse\n1,2,forward\n")
    assert "the goal of task 2, from the goal of task 1 (segment 2, arriving reverse)" in str(error)


def test_each_vehicle_keeps_its_own_chain(tmp_path: Path) -> None:
    segments = (*DEAD_END, straight(3, (0.0, 5.0), (4.0, 5.0)))
    scenario = make_scenario(tmp_path, segments, "1,1,forward,,\n2,3,forward,,\n", "1,2,\n2,3,\n2,3,\n")
    assert len(scenario.tasks) == 3
