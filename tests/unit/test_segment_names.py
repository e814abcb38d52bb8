"""``vehicles.csv`` and ``tasks.csv`` name segments by id or by the name the site uses."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleetsim.enums import Direction, Progress, Shape, Traverse
from fleetsim.errors import ScenarioFileError
from fleetsim.layout.segment import Segment
from fleetsim.load.tables.scenario_files import read_tasks, read_vehicles
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Vehicle

SEGMENTS = {
    1: Segment(1, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (1.0, 0.0)), ("Dock A",)),
    2: Segment(2, Shape.STRAIGHT, Direction.BOTH, ((1.0, 0.0), (2.0, 0.0)), ("N1-N2", "N2-N1")),
    3: Segment(3, Shape.STRAIGHT, Direction.FORWARD, ((2.0, 0.0), (3.0, 0.0)), ("1",)),
    4: Segment(4, Shape.STRAIGHT, Direction.BOTH, ((3.0, 0.0), (4.0, 0.0)), ("twin",)),
    5: Segment(5, Shape.STRAIGHT, Direction.BOTH, ((4.0, 0.0), (5.0, 0.0)), ("twin",)),
    6: Segment(6, Shape.STRAIGHT, Direction.BOTH, ((5.0, 0.0), (6.0, 0.0)), ("7",)),
}
VEHICLE = Vehicle(1, 1, Traverse.FORWARD, Progress.FORWARD, DEFAULT_VEHICLE_TYPE)


def goals(tmp_path: Path, *cells: str) -> list[int]:
    path = tmp_path / "tasks.csv"
    path.write_text("vehicle_id,goal_segment_id\n" + "".join(f"1,{cell}\n" for cell in cells))
    return [task.goal_segment for task in read_tasks(path, SEGMENTS, [VEHICLE], map_name="site.lif.json")]


def goal_error(tmp_path: Path, cell: str) -> str:
    with pytest.raises(ScenarioFileError) as caught:
        goals(tmp_path, cell)
    assert caught.value.location is not None and caught.value.location.line == 2
    assert caught.value.location.field == "goal_segment_id"
    return caught.value.problem


def test_a_task_names_its_goal_by_id_or_by_any_name_of_the_segment(tmp_path: Path) -> None:
    assert goals(tmp_path, "2", "Dock A", "dock a", "N1-N2", "N2-N1", "id:2", "name:Dock A") == [2, 1, 1, 2, 2, 2, 1]


def test_a_vehicle_starts_on_a_segment_given_by_its_name(tmp_path: Path) -> None:
    path = tmp_path / "vehicles.csv"
    path.write_text("vehicle_id,start_segment_id,segment_orientation\n1,N2-N1,backward\n")
    (vehicle,) = read_vehicles(path, SEGMENTS, {"default": DEFAULT_VEHICLE_TYPE}, DEFAULT_VEHICLE_TYPE)
    assert (vehicle.start_segment, vehicle.traverse) == (2, Traverse.BACKWARD)


def test_a_number_that_is_one_segments_id_and_another_segments_name_must_be_told_apart(tmp_path: Path) -> None:
    problem = goal_error(tmp_path, "1 ")  # segment 1's id and segment 3's name (cells are trimmed)
    assert problem == "'1' is both the id of segment 1 and the name of segment 3; write 'id:1' or 'name:1'"
    assert goals(tmp_path, "id:1", "name:1") == [1, 3]


def test_a_number_that_is_only_a_name_reads_as_that_name(tmp_path: Path) -> None:
    assert goals(tmp_path, "7") == [6]  # there is no segment 7: the name of segment 6


def test_a_name_carried_by_two_segments_is_refused(tmp_path: Path) -> None:
    assert goal_error(tmp_path, "twin") == "'twin' names segments 4, 5 of site.lif.json; use the segment id instead"


def test_an_unknown_name_says_what_was_meant(tmp_path: Path) -> None:
    problem = goal_error(tmp_path, "Dock B")
    assert problem == "segment 'Dock B' is not in site.lif.json (neither an id nor a name); did you mean 'Dock A'?"


@pytest.mark.parametrize(
    ("cell", "problem"),
    [
        ("id:x", "'id:x': after 'id:' comes a whole number >= 0"),
        ("id:9", "segment 9 is not in site.lif.json"),
        ("name:nothing", "no segment of site.lif.json is named 'nothing'"),
        ("99", "segment 99 is not in site.lif.json"),
    ],
)
def test_forced_readings_and_unknown_ids_are_located_errors(tmp_path: Path, cell: str, problem: str) -> None:
    assert goal_error(tmp_path, cell) == problem


def test_on_a_map_without_names_a_cell_must_be_a_whole_number(tmp_path: Path) -> None:
    unnamed = {1: Segment(1, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (1.0, 0.0)))}
    path = tmp_path / "tasks.csv"
    path.write_text("vehicle_id,goal_segment_id\n1,dock\n")
    with pytest.raises(ScenarioFileError, match="'dock' is not a whole number >= 0"):
        read_tasks(path, unnamed, [VEHICLE])
