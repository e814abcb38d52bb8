"""vehicles.csv and tasks.csv report every bad row at once (issue 32, point 1), capped per file; one bad
row is still its own ScenarioFileError; a ';'- or tab-separated file is named as such (point 6)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleetsim.cli import main
from fleetsim.enums import Direction, Progress, Shape, Traverse
from fleetsim.errors import LoadError, LoadErrors, MapError, ScenarioFileError
from fleetsim.layout.segment import Segment
from fleetsim.load.common.collect import CAP_PER_FILE
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.load.tables.scenario_files import read_tasks, read_vehicles
from fleetsim.load.tiled.writer import write_map
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, ScenarioSettings, Vehicle

SEGMENTS = {
    1: Segment(1, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (5.0, 0.0))),
    2: Segment(2, Shape.STRAIGHT, Direction.FORWARD, ((5.0, 0.0), (10.0, 0.0))),
    3: Segment(3, Shape.STRAIGHT, Direction.BOTH, ((10.0, 0.0), (15.0, 0.0))),
    4: Segment(4, Shape.STRAIGHT, Direction.BOTH, ((15.0, 0.0), (20.0, 0.0))),
}
TYPES = {"default": DEFAULT_VEHICLE_TYPE}
VEHICLES_HEADER = "vehicle_id,start_segment_id,segment_orientation\n"
TASKS_HEADER = "vehicle_id,goal_segment_id,goal_progress_direction\n"
VEHICLES = (
    Vehicle(1, 1, Traverse.FORWARD, Progress.FORWARD, DEFAULT_VEHICLE_TYPE),
    Vehicle(2, 4, Traverse.FORWARD, Progress.FORWARD, DEFAULT_VEHICLE_TYPE),
)


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def located(error: LoadErrors) -> list[tuple[int | None, str | None]]:
    """(line, field) of each collected error."""
    return [(e.location.line, e.location.field) if e.location else (None, None) for e in error.errors]


def tasks_error(tmp_path: Path, text: str) -> LoadError:
    with pytest.raises(LoadError) as caught:
        read_tasks(write(tmp_path / "tasks.csv", text), SEGMENTS, VEHICLES, map_name="map.json")
    return caught.value


def vehicles_error(tmp_path: Path, text: str) -> LoadError:
    with pytest.raises(LoadError) as caught:
        read_vehicles(write(tmp_path / "vehicles.csv", text), SEGMENTS, TYPES, DEFAULT_VEHICLE_TYPE)
    return caught.value


# -- tasks.csv and vehicles.csv alone -------------------------------------------------------------


def test_three_bad_task_rows_are_reported_at_once_each_at_its_line_and_field(tmp_path: Path) -> None:
    error = tasks_error(tmp_path, TASKS_HEADER + "1,2,\n1,99,\n2,1,sideways\n7,1,\n")
    assert isinstance(error, LoadErrors)
    assert located(error) == [(3, "goal_segment_id"), (4, "goal_progress_direction"), (5, "vehicle_id")]
    path = tmp_path / "tasks.csv"
    assert str(error).splitlines() == [
        "3 errors:",
        f"  {path}:3: field 'goal_segment_id': segment 99 is not in map.json",
        f"  {path}:4: field 'goal_progress_direction': 'sideways' is not 'forward' or 'reverse'",
        f"  {path}:5: field 'vehicle_id': vehicle 7 is not in vehicles.csv",
    ]


def test_every_bad_cell_of_one_row_is_reported(tmp_path: Path) -> None:
    error = vehicles_error(tmp_path, VEHICLES_HEADER + "x,77,sideways\n")
    assert isinstance(error, LoadErrors)
    assert located(error) == [(2, "vehicle_id"), (2, "start_segment_id"), (2, "segment_orientation")]


def test_a_duplicate_id_a_wrong_way_start_and_a_short_row_are_all_reported(tmp_path: Path) -> None:
    text = VEHICLES_HEADER + "1,1,forward\n2,2,backward\n1,1,forward\n3,1\n4,1,forward\n"
    error = vehicles_error(tmp_path, text)
    assert isinstance(error, LoadErrors)
    assert located(error) == [(3, "segment_orientation"), (4, "vehicle_id"), (5, None)]
    assert "vehicle id 1 is already used on line 2" in error.errors[1].problem
    assert "row has 2 values but the header has 3 columns" in error.errors[2].problem


def test_sixty_bad_rows_show_fifty_and_count_the_rest(tmp_path: Path) -> None:
    error = tasks_error(tmp_path, TASKS_HEADER + "1,99,\n" * 60)
    assert isinstance(error, LoadErrors)
    path = tmp_path / "tasks.csv"
    assert len(error.errors) == CAP_PER_FILE == 50
    assert error.omitted == {str(path): 10}
    lines = str(error).splitlines()
    assert lines[0] == "60 errors:"
    assert lines[-1] == f"  ... and 10 more in {path}"
    assert [e.location.line for e in error.errors if e.location] == list(range(2, 52))


def test_one_bad_row_is_still_exactly_its_own_error(tmp_path: Path) -> None:
    error = tasks_error(tmp_path, TASKS_HEADER + "1,1,\n2,2,\n1,99,\n")
    assert type(error) is ScenarioFileError
    assert str(error) == f"{tmp_path / 'tasks.csv'}:4: field 'goal_segment_id': segment 99 is not in map.json"


def test_good_rows_around_nothing_bad_load_as_before(tmp_path: Path) -> None:
    path = write(tmp_path / "tasks.csv", TASKS_HEADER + "1,2,\n2,1,reverse\n")
    tasks = read_tasks(path, SEGMENTS, VEHICLES)
    assert [(t.id, t.vehicle_id, t.goal_segment, t.goal_progress) for t in tasks] == [
        (1, 1, 2, None),
        (2, 2, 1, Progress.REVERSE),
    ]


# -- the header -----------------------------------------------------------------------------------


@pytest.mark.parametrize(("separator", "named"), [(";", "';'"), ("\t", "tabs")])
def test_a_header_separated_by_something_else_is_named_as_such(tmp_path: Path, separator: str, named: str) -> None:
    header = separator.join(("vehicle_id", "start_segment_id", "segment_orientation"))
    error = vehicles_error(tmp_path, f"{header}\n1{separator}1{separator}forward\n")
    assert type(error) is ScenarioFileError
    assert error.location is not None and error.location.line == 1
    assert f"this file seems to be separated by {named}; fleetsim reads comma-separated files" in error.problem


@pytest.mark.parametrize("header", ["vehicle_id,goal_segmnt;id", "vehicle;ident"])
def test_a_semicolon_in_a_genuinely_unknown_column_gets_no_separator_hint(tmp_path: Path, header: str) -> None:
    error = tasks_error(tmp_path, f"{header}\n")
    assert "separated" not in str(error)
    assert "unknown column" in str(error)


def test_a_genuinely_unknown_column_keeps_its_did_you_mean_alone(tmp_path: Path) -> None:
    # The misspelt column is not also reported as a missing required one.
    error = vehicles_error(tmp_path, "vehicle_id,start_segment,segment_orientation\n1,1,forward\n")
    assert type(error) is ScenarioFileError
    assert "unknown column 'start_segment'; did you mean 'start_segment_id'?" in error.problem
    assert "separated" not in error.problem


def test_every_problem_of_a_header_is_reported_and_its_rows_are_not_read(tmp_path: Path) -> None:
    error = vehicles_error(tmp_path, "vehicle_id,colour,segment_orientation,colour\n1,99,forward,red\n")
    assert isinstance(error, LoadErrors)
    assert located(error) == [(1, "colour"), (1, "colour"), (1, "start_segment_id")]


# -- a whole scenario -----------------------------------------------------------------------------


def scenario_folder(root: Path, vehicles: str, tasks: str) -> Path:
    folder = root / "bad"
    folder.mkdir(parents=True)
    write_map(folder / "map.json", SEGMENTS.values())
    write(folder / "vehicles.csv", VEHICLES_HEADER + vehicles)
    write(folder / "tasks.csv", TASKS_HEADER + tasks)
    return folder


def scenario_error(folder: Path) -> LoadError:
    with pytest.raises(LoadError) as caught:
        load_scenario_dir(folder)
    return caught.value


def test_a_scenario_reports_its_bad_vehicle_row_and_its_bad_task_row_together(tmp_path: Path) -> None:
    folder = scenario_folder(tmp_path, "1,1,forward\n2,1,sideways\n", "1,2,\n1,99,\n")
    error = scenario_error(folder)
    assert isinstance(error, LoadErrors)
    assert [(e.location.path, e.location.line) for e in error.errors if e.location] == [
        (folder / "vehicles.csv", 3),
        (folder / "tasks.csv", 3),
    ]


def test_a_task_of_a_vehicle_whose_row_is_bad_is_not_also_called_unknown(tmp_path: Path) -> None:
    folder = scenario_folder(tmp_path, "1,1,forward\n2,1,sideways\n", "2,2,\n")
    error = scenario_error(folder)
    assert type(error) is ScenarioFileError
    assert error.location is not None and error.location.path == folder / "vehicles.csv"


def test_reachability_waits_for_clean_files(tmp_path: Path) -> None:
    # Task 1 (segment 1, reached only against segment 2's one-way direction) is unreachable, but the
    # row error comes alone: checking reachability needs every vehicle and task.
    folder = scenario_folder(tmp_path, "1,2,forward\n", "1,1,\n1,2,sideways\n")
    error = scenario_error(folder)
    assert type(error) is ScenarioFileError
    assert "'sideways' is not 'forward' or 'reverse'" in error.problem


def test_a_broken_map_is_reported_with_a_broken_csv_header(tmp_path: Path) -> None:
    folder = scenario_folder(tmp_path, "1,1,forward\n", "1,2,\n")
    write(folder / "map.json", "{")
    write(folder / "tasks.csv", "vehicle_id;goal_segment_id\n1;2\n")
    error = scenario_error(folder)
    assert isinstance(error, LoadErrors)
    assert isinstance(error.errors[0], MapError)
    assert "separated by ';'" in error.errors[1].problem


def test_a_broken_map_with_good_csv_files_is_its_own_error(tmp_path: Path) -> None:
    folder = scenario_folder(tmp_path, "1,1,forward\n", "1,2,\n")
    write(folder / "map.json", "{")
    assert type(scenario_error(folder)) is MapError


def test_a_clean_scenario_loads_unchanged(tmp_path: Path) -> None:
    scenario = load_scenario_dir(scenario_folder(tmp_path, "1,1,forward\n2,4,forward\n", "1,2,\n2,3,\n"))
    assert scenario.vehicles == VEHICLES
    assert [(t.id, t.vehicle_id, t.goal_segment) for t in scenario.tasks] == [(1, 1, 2), (2, 2, 3)]


# -- fleetsim validate ----------------------------------------------------------------------------


def test_validate_prints_every_error_of_a_scenario(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scenario_folder(tmp_path, "1,1,forward\n2,1,forward\n", "1,2,\n1,99,\n2,1,sideways\n7,1,\n")
    suite = write(tmp_path / "bad.fleetsim.yaml", "fleetsim: 1\nname: bad\nscenarios:\n  - name: rows\n    dir: bad/\n")
    assert main(["validate", str(suite)]) == 1
    out = capsys.readouterr().out
    listed = [line.strip() for line in out.splitlines() if line.startswith("         ")]
    assert len(listed) == 3, out
    for line, field in [(3, "goal_segment_id"), (4, "goal_progress_direction"), (5, "vehicle_id")]:
        assert any(f"tasks.csv:{line}: field {field!r}" in entry for entry in listed), out
    assert "       3 errors:" in out
    assert "0 scenario(s) valid, 1 failed" in out


def test_every_vehicle_starting_in_conflict_is_reported(tmp_path: Path) -> None:
    folder = scenario_folder(tmp_path, "1,1,forward\n2,2,forward\n3,4,forward\n4,3,forward\n", "")
    error = scenario_error(folder)
    assert isinstance(error, LoadErrors)
    assert [e.location.line for e in error.errors if e.location] == [3, 5]
    assert all("start on conflicting segments" in e.problem for e in error.errors)


def test_one_start_conflict_is_its_own_error(tmp_path: Path) -> None:
    folder = scenario_folder(tmp_path, "1,1,forward\n2,2,forward\n3,4,forward\n", "")
    assert type(scenario_error(folder)) is ScenarioFileError


def test_an_unknown_default_type_is_reported_with_the_files_structure(tmp_path: Path) -> None:
    folder = scenario_folder(tmp_path, "1,1,forward\n", "1,2,\n")
    settings = ScenarioSettings(vehicle_type="nope")
    with pytest.raises(ScenarioFileError, match="vehicle_type='nope' is not one of the vehicle types"):
        load_scenario_dir(folder, settings=settings)
    write(folder / "tasks.csv", "vehicle_id,goal\n")
    with pytest.raises(LoadErrors) as caught:
        load_scenario_dir(folder, settings=settings)
    assert [e.location.field for e in caught.value.errors if e.location] == [None, "goal", "goal_segment_id"]


def test_a_header_with_several_problems_is_collected_with_the_other_files_rows(tmp_path: Path) -> None:
    folder = scenario_folder(tmp_path, "1,1,sideways\n", "")
    write(folder / "tasks.csv", "vehicle_id,goal\n1,2\n")
    error = scenario_error(folder)
    assert isinstance(error, LoadErrors)
    assert [(Path(e.location.path).name, e.location.field) for e in error.errors if e.location] == [
        ("vehicles.csv", "segment_orientation"),
        ("tasks.csv", "goal"),
        ("tasks.csv", "goal_segment_id"),
    ]
