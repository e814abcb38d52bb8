"""vehicles.csv and tasks.csv: good files load, every bad one gives exactly one located error."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleetsim.enums import Direction, Progress, Shape, Traverse, TurnCapability
from fleetsim.errors import ScenarioFileError
from fleetsim.layout.segment import Segment
from fleetsim.load.tables.scenario_files import read_tasks, read_vehicles
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Vehicle, VehicleType

SEGMENTS = {
    1: Segment(1, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (5.0, 0.0))),
    2: Segment(2, Shape.STRAIGHT, Direction.FORWARD, ((5.0, 0.0), (10.0, 0.0))),
    3: Segment(3, Shape.STRAIGHT, Direction.BACKWARD, ((10.0, 0.0), (15.0, 0.0))),
}
BIG = VehicleType("big", 2.0, 1.0, 1.0, 0.5, 0.2, TurnCapability.CURVE)
TYPES = {"default": DEFAULT_VEHICLE_TYPE, "big": BIG}
VEHICLES_HEADER = "vehicle_id,start_segment_id,segment_orientation,progress_direction,type\n"
TASKS_HEADER = "vehicle_id,goal_segment_id,goal_progress_direction\n"


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def vehicles_from(
    tmp_path: Path, text: str, default_type: VehicleType | None = DEFAULT_VEHICLE_TYPE
) -> tuple[Vehicle, ...]:
    path = write(tmp_path, "vehicles.csv", text)
    return read_vehicles(path, SEGMENTS, TYPES, default_type, map_name="map.json")


def two_vehicles() -> tuple[Vehicle, ...]:
    return (
        Vehicle(1, 1, Traverse.FORWARD, Progress.FORWARD, DEFAULT_VEHICLE_TYPE),
        Vehicle(2, 2, Traverse.FORWARD, Progress.FORWARD, DEFAULT_VEHICLE_TYPE),
    )


# -- vehicles.csv: good files ---------------------------------------------------------------------


def test_vehicles_load_in_file_order_with_progress_and_type_defaults(tmp_path: Path) -> None:
    vehicles = vehicles_from(tmp_path, VEHICLES_HEADER + "7,1,forward,,\n3,3,backward,reverse,big\n")
    assert vehicles == (
        Vehicle(7, 1, Traverse.FORWARD, Progress.FORWARD, DEFAULT_VEHICLE_TYPE),
        Vehicle(3, 3, Traverse.BACKWARD, Progress.REVERSE, BIG),
    )


def test_progress_and_type_columns_are_optional(tmp_path: Path) -> None:
    vehicles = vehicles_from(tmp_path, "vehicle_id,start_segment_id,segment_orientation\n1,1,backward\n")
    assert vehicles == (Vehicle(1, 1, Traverse.BACKWARD, Progress.FORWARD, DEFAULT_VEHICLE_TYPE),)


def test_header_only_vehicles_file_has_no_vehicles(tmp_path: Path) -> None:
    assert vehicles_from(tmp_path, VEHICLES_HEADER) == ()


def test_names_and_values_are_trimmed_and_case_insensitive_and_a_bom_is_tolerated(tmp_path: Path) -> None:
    text = "\ufeff Vehicle_ID , START_segment_id,Segment_Orientation,Type\n 1 , 2 , FORWARD , BIG \n"
    assert vehicles_from(tmp_path, text) == (Vehicle(1, 2, Traverse.FORWARD, Progress.FORWARD, BIG),)


def test_blank_lines_and_comment_rows_are_skipped(tmp_path: Path) -> None:
    text = "# fleet of two\n\n" + VEHICLES_HEADER + "\n1,1,forward,,\n# 2,1,forward,,\n,,,,\n2,2,forward,,\n"
    assert [vehicle.id for vehicle in vehicles_from(tmp_path, text)] == [1, 2]


def test_crlf_line_endings_are_read(tmp_path: Path) -> None:
    text = (VEHICLES_HEADER + "1,1,forward,,\n").replace("\n", "\r\n")
    assert len(vehicles_from(tmp_path, text)) == 1


# -- vehicles.csv: every bad input is one located error -------------------------------------------


BAD_VEHICLES = [
    pytest.param(
        VEHICLES_HEADER + "1,1,forward,,\n1,2,forward,,\n",
        3,
        "vehicle_id",
        "vehicle id 1 is already used on line 2",
        id="duplicate-vehicle-id-names-both-lines",
    ),
    pytest.param(
        VEHICLES_HEADER + "1,99,forward,,\n",
        2,
        "start_segment_id",
        "segment 99 is not in map.json",
        id="unknown-start-segment",
    ),
    pytest.param(
        VEHICLES_HEADER + "1,2,backward,,\n",
        2,
        "segment_orientation",
        "wrong-way start: segment 2 is one-way 'forward'",
        id="wrong-way-start-on-forward-segment",
    ),
    pytest.param(
        VEHICLES_HEADER + "1,3,forward,,\n",
        2,
        "segment_orientation",
        "wrong-way start: segment 3 is one-way 'backward'",
        id="wrong-way-start-on-backward-segment",
    ),
    pytest.param(
        VEHICLES_HEADER + "x1,1,forward,,\n", 2, "vehicle_id", "'x1' is not a whole number", id="non-integer-vehicle-id"
    ),
    pytest.param(
        VEHICLES_HEADER + "1,1.5,forward,,\n",
        2,
        "start_segment_id",
        "'1.5' is not a whole number",
        id="non-integer-segment-id",
    ),
    pytest.param(
        VEHICLES_HEADER + "-1,1,forward,,\n",
        2,
        "vehicle_id",
        "'-1' is not a whole number >= 0",
        id="negative-vehicle-id",
    ),
    pytest.param(
        VEHICLES_HEADER + "1,1,sideways,,\n",
        2,
        "segment_orientation",
        "'sideways' is not 'forward' or 'backward'",
        id="bad-orientation",
    ),
    pytest.param(VEHICLES_HEADER + "1,1,,,\n", 2, "segment_orientation", "missing", id="empty-orientation"),
    pytest.param(
        VEHICLES_HEADER + "1,1,forward,backward,\n",
        2,
        "progress_direction",
        "'backward' is not 'forward' or 'reverse'",
        id="bad-progress",
    ),
    pytest.param(
        VEHICLES_HEADER + "1,1,forward,,agv\n", 2, "type", "vehicle type 'agv' is not defined", id="unknown-type"
    ),
    pytest.param(
        VEHICLES_HEADER + "1,1,forward,,\n2,1,forward\n",
        3,
        None,
        "row has 3 values but the header has 5 columns",
        id="short-row",
    ),
    pytest.param(
        VEHICLES_HEADER + "1,1,forward,,,extra\n",
        2,
        None,
        "row has 6 values but the header has 5 columns",
        id="long-row",
    ),
    pytest.param("", 1, None, "no header", id="empty-file"),
    pytest.param("\n# only a comment\n", 1, None, "no header", id="no-header"),
    pytest.param(
        "1,1,forward\n", 1, None, "missing header: the first row must be vehicle_id,", id="data-row-instead-of-header"
    ),
    pytest.param(
        "vehicle_id,start_segment_id\n",
        1,
        "segment_orientation",
        "missing required column 'segment_orientation'",
        id="missing-required-column",
    ),
    pytest.param(
        "vehicle_id,start_segment,segment_orientation\n",
        1,
        "start_segment",
        "unknown column 'start_segment'; did you mean 'start_segment_id'?",
        id="unknown-column",
    ),
    pytest.param(
        "vehicle_id,vehicle_id,start_segment_id,segment_orientation\n",
        1,
        "vehicle_id",
        "column 'vehicle_id' appears twice",
        id="duplicate-column",
    ),
    pytest.param(
        "vehicle_id,start_segment_id,segment_orientation,\n",
        1,
        None,
        "header column 4 has no name",
        id="unnamed-column",
    ),
    pytest.param(VEHICLES_HEADER + '1,"1,forward,,\n', 2, None, "malformed CSV", id="unterminated-quote"),
]


@pytest.mark.parametrize(("text", "line", "field", "problem"), BAD_VEHICLES)
def test_bad_vehicles_file_gives_one_located_error(
    tmp_path: Path, text: str, line: int, field: str | None, problem: str
) -> None:
    with pytest.raises(ScenarioFileError) as caught:
        vehicles_from(tmp_path, text)
    error = caught.value
    assert error.location is not None
    assert (error.location.line, error.location.field) == (line, field)
    assert problem in error.problem
    assert str(error).startswith(f"{tmp_path / 'vehicles.csv'}:{line}")


def test_row_without_type_is_rejected_when_there_is_no_default_type(tmp_path: Path) -> None:
    pattern = r"vehicles.csv:2: field 'type': .*no default type.*default, big"
    with pytest.raises(ScenarioFileError, match=pattern):
        vehicles_from(tmp_path, VEHICLES_HEADER + "1,1,forward,,\n", default_type=None)


def test_undecodable_bytes_are_a_located_error(tmp_path: Path) -> None:
    path = tmp_path / "vehicles.csv"
    path.write_bytes(VEHICLES_HEADER.encode() + b"1,1,forw\xe4rd,,\n")
    with pytest.raises(ScenarioFileError, match=r"vehicles.csv:2: not UTF-8 text"):
        read_vehicles(path, SEGMENTS, TYPES, DEFAULT_VEHICLE_TYPE)


def test_missing_vehicles_file_is_a_located_error(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError, match=r"vehicles.csv: file not found"):
        read_vehicles(tmp_path / "vehicles.csv", SEGMENTS, TYPES, DEFAULT_VEHICLE_TYPE)


def test_a_directory_instead_of_a_file_is_a_located_error(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError, match="is a directory"):
        read_vehicles(tmp_path, SEGMENTS, TYPES, DEFAULT_VEHICLE_TYPE)


# -- tasks.csv ------------------------------------------------------------------------------------


def test_task_ids_are_data_row_numbers_not_file_lines(tmp_path: Path) -> None:
    text = "# tasks\n" + TASKS_HEADER + "1,2,\n\n# 2,1,\n2,1,reverse\n1,3,FORWARD\n"
    tasks = read_tasks(write(tmp_path, "tasks.csv", text), SEGMENTS, two_vehicles())
    assert [(task.id, task.vehicle_id, task.goal_segment, task.goal_progress) for task in tasks] == [
        (1, 1, 2, None),
        (2, 2, 1, Progress.REVERSE),
        (3, 1, 3, Progress.FORWARD),
    ]


def test_goal_direction_column_is_optional(tmp_path: Path) -> None:
    path = write(tmp_path, "tasks.csv", "vehicle_id,goal_segment_id\n2,3\n")
    tasks = read_tasks(path, SEGMENTS, two_vehicles())
    assert [(task.id, task.goal_progress) for task in tasks] == [(1, None)]


def test_tasks_accept_a_mapping_of_vehicles(tmp_path: Path) -> None:
    by_id = {vehicle.id: vehicle for vehicle in two_vehicles()}
    assert len(read_tasks(write(tmp_path, "tasks.csv", TASKS_HEADER + "2,1,\n"), SEGMENTS, by_id)) == 1


def test_unknown_goal_segment_message_names_file_line_field_and_map(tmp_path: Path) -> None:
    path = write(tmp_path, "tasks.csv", TASKS_HEADER + "1,1,\n2,2,\n1,99,\n")
    with pytest.raises(ScenarioFileError) as caught:
        read_tasks(path, SEGMENTS, two_vehicles(), map_name="map.json")
    assert str(caught.value) == f"{path}:4: field 'goal_segment_id': segment 99 is not in map.json"


BAD_TASKS = [
    pytest.param(TASKS_HEADER + "5,1,\n", 2, "vehicle_id", "vehicle 5 is not in vehicles.csv", id="unknown-vehicle"),
    pytest.param(TASKS_HEADER + "one,1,\n", 2, "vehicle_id", "'one' is not a whole number", id="non-integer-vehicle"),
    pytest.param(
        TASKS_HEADER + "1,1,backward\n",
        2,
        "goal_progress_direction",
        "'backward' is not 'forward' or 'reverse'",
        id="bad-goal-direction",
    ),
    pytest.param("", 1, None, "no header", id="empty-file"),
    pytest.param(
        "vehicle_id,goal_progress_direction\n",
        1,
        "goal_segment_id",
        "missing required column 'goal_segment_id'",
        id="missing-required-column",
    ),
    pytest.param(
        "vehicle_id,goal_segment_id,goal_direction\n",
        1,
        "goal_direction",
        "unknown column 'goal_direction'",
        id="unknown-column",
    ),
]


@pytest.mark.parametrize(("text", "line", "field", "problem"), BAD_TASKS)
def test_bad_tasks_file_gives_one_located_error(
    tmp_path: Path, text: str, line: int, field: str | None, problem: str
) -> None:
    with pytest.raises(ScenarioFileError) as caught:
        read_tasks(write(tmp_path, "tasks.csv", text), SEGMENTS, two_vehicles())
    location = caught.value.location
    assert location is not None
    assert (location.line, location.field) == (line, field)
    assert problem in caught.value.problem
