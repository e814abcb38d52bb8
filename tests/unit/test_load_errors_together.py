"""A map that fails to load, or a suite entry whose folder is missing, no longer hides the scenario's
CSV errors: all are reported together, by `load_scenario`, `load_suite`, `fleetsim validate`,
`fleetsim run` and pytest (issue: reports that say where the trouble is, point 8). What needs the map
(a segment exists, an orientation is allowed) waits for the map."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from fleetsim.cli import main
from fleetsim.errors import LoadErrors, MapError, ScenarioFileError, SuiteError, SuiteErrors
from fleetsim.load.suites.scenario import load_scenario, load_scenario_dir
from fleetsim.load.suites.suite import load_suite

CROSSING = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples" / "crossing"
PLANNER = "fleetsim.planners:ReservingPlanner"
# Vehicle 2 faces 'sideways' (line 3); a task names vehicle 7, which no row has (line 3); a task's goal
# is segment 99, which the crossing does not have (line 4): only the map can say that.
VEHICLES = "vehicle_id,start_segment_id,segment_orientation\n1,1,forward\n2,5,sideways\n"
TASKS = "vehicle_id,goal_segment_id\n1,4\n7,8\n2,99\n"
MAP_PROBLEM = "the file is not valid JSON"
ORIENTATION = "vehicles.csv:3: field 'segment_orientation': 'sideways' is not 'forward' or 'backward'"
UNKNOWN_VEHICLE = "tasks.csv:3: field 'vehicle_id': vehicle 7 is not in vehicles.csv"


def scenario(root: Path, *, map_text: str | None = None, vehicles: str = VEHICLES, tasks: str = TASKS) -> Path:
    """The crossing in ``root/examples/bad`` with these files (the map broken when ``map_text`` is
    given), its Tiled templates in ``root/tiled``."""
    folder = root / "examples" / "bad"
    shutil.copytree(CROSSING, folder)
    shutil.copytree(CROSSING.parents[1] / "tiled", root / "tiled")
    if map_text is not None:
        (folder / "map.json").write_text(map_text, encoding="utf-8")
    (folder / "vehicles.csv").write_text(vehicles, encoding="utf-8")
    (folder / "tasks.csv").write_text(tasks, encoding="utf-8")
    return folder


def suite(root: Path, entry: str) -> Path:
    path = root / "bad.fleetsim.yaml"
    path.write_text(f"fleetsim: 1\nname: bad\nscenarios:\n  - name: bad\n{entry}", encoding="utf-8")
    return path


def shown_by_validate_run_and_pytest(root: Path, suite_path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    """What `fleetsim validate`, `fleetsim run` and pytest print for the suite (each of them fails)."""
    assert main(["validate", str(suite_path)]) == 1
    assert main(["run", str(suite_path), "--planner", PLANNER]) == 1
    command = [sys.executable, "-m", "pytest", suite_path.name, "--planner", PLANNER, "-p", "no:cacheprovider"]
    # Without CI's strictness about hashes (no lock file here): only the load errors are the story.
    environment = {key: value for key, value in os.environ.items() if key != "CI"}
    done = subprocess.run(command, cwd=root, capture_output=True, text=True, check=False, timeout=120, env=environment)
    assert done.returncode != 0 and "Traceback" not in done.stdout, done.stdout
    return capsys.readouterr().out + done.stdout


# -- a map that does not load, with CSV errors -----------------------------------------------------


def test_a_broken_map_and_bad_csv_rows_are_reported_together(tmp_path: Path) -> None:
    folder = scenario(tmp_path, map_text="{")
    with pytest.raises(LoadErrors) as caught:
        load_scenario_dir(folder)
    errors = caught.value.errors
    assert isinstance(errors[0], MapError) and MAP_PROBLEM in errors[0].problem
    assert [str(e).removeprefix(f"{folder}/") for e in errors[1:]] == [ORIENTATION, UNKNOWN_VEHICLE]
    # Whether segment 99 exists needs the map: not said until the map loads. (The folder's own path is left
    # out: pytest's numbered temporary folders hold "99" at times.)
    assert not any("99" in str(e).replace(str(tmp_path), "") for e in errors)


def test_with_the_map_mended_the_segment_check_joins_the_row_errors(tmp_path: Path) -> None:
    with pytest.raises(LoadErrors) as caught:
        load_scenario_dir(scenario(tmp_path))
    assert [type(e) for e in caught.value.errors] == [ScenarioFileError] * 3
    assert "segment 99 is not in map.json" in str(caught.value.errors[2])


def test_a_broken_map_with_clean_rows_is_the_map_error_alone(tmp_path: Path) -> None:
    folder = scenario(tmp_path, map_text="{", vehicles="vehicle_id,start_segment_id,segment_orientation\n1,1,forward\n")
    (folder / "tasks.csv").write_text("vehicle_id,goal_segment_id\n1,4\n", encoding="utf-8")
    with pytest.raises(MapError):
        load_scenario_dir(folder)


def test_validate_run_and_pytest_show_a_broken_map_with_the_csv_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scenario(tmp_path, map_text="{")
    shown = shown_by_validate_run_and_pytest(tmp_path, suite(tmp_path, "    dir: examples/bad\n"), capsys)
    for said in (MAP_PROBLEM, ORIENTATION, UNKNOWN_VEHICLE):
        assert shown.count(said) == 3, (said, shown)  # validate, run, pytest
    assert "3 errors:" in shown


# -- a suite entry whose folder is missing, with CSV errors ---------------------------------------


def test_a_missing_dir_is_reported_with_the_errors_of_the_named_tasks_file(tmp_path: Path) -> None:
    scenario(tmp_path)
    path = suite(
        tmp_path, "    dir: nowhere\n    vehicles: examples/bad/vehicles.csv\n    tasks: examples/bad/tasks.csv\n"
    )
    with pytest.raises(SuiteErrors) as caught:
        load_suite(path)
    first, *rows = caught.value.errors
    assert isinstance(first, SuiteError) and first.location is not None
    assert first.location.line == 5 and first.problem.startswith("scenarios[0].dir: no such directory")
    assert [str(e).removeprefix(f"{tmp_path}/examples/bad/") for e in rows] == [ORIENTATION, UNKNOWN_VEHICLE]


def test_validate_run_and_pytest_show_a_missing_dir_with_the_csv_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scenario(tmp_path, tasks="vehicle_id,goal_segment_id\n1,4\nx,8\n7,99\n")
    path = suite(tmp_path, "    dir: nowhere\n    tasks: examples/bad/tasks.csv\n")
    shown = shown_by_validate_run_and_pytest(tmp_path, path, capsys)
    for said in (
        "bad.fleetsim.yaml:5:10: scenarios[0].dir: no such directory",
        "tasks.csv:3: field 'vehicle_id': 'x' is not a whole number >= 0",
    ):
        assert shown.count(said) == 3, (said, shown)  # validate, run, pytest's collection error
    # Without vehicles.csv (it was to be in the folder) nobody can say vehicle 7 is unknown; nor, without
    # the map, that segment 99 is.
    assert "tasks.csv:4" not in shown


def test_a_missing_dir_with_clean_named_files_is_the_one_suite_error(tmp_path: Path) -> None:
    scenario(
        tmp_path,
        vehicles="vehicle_id,start_segment_id,segment_orientation\n1,1,forward\n",
        tasks="vehicle_id,goal_segment_id\n1,99\n",
    )
    path = suite(
        tmp_path, "    dir: nowhere\n    vehicles: examples/bad/vehicles.csv\n    tasks: examples/bad/tasks.csv\n"
    )
    with pytest.raises(SuiteError) as caught:
        load_suite(path)
    assert type(caught.value) is SuiteError and "no such directory" in caught.value.problem


def test_rows_naming_no_type_are_not_judged_when_the_default_type_is_the_mistake(tmp_path: Path) -> None:
    scenario(tmp_path)
    path = tmp_path / "typed.fleetsim.yaml"
    path.write_text(
        "fleetsim: 1\nname: typed\nvehicle_types:\n"
        "  agv: {length: 1, width: 0.6, height: 0.4, max_speed: 1, acceleration: 0.5, turn_capability: in_place}\n"
        "  tug: {length: 2, width: 1, height: 1, max_speed: 2, acceleration: 1, turn_capability: curve}\n"
        "defaults: {vehicle_type: agx}\n"
        "scenarios:\n  - name: bad\n    dir: nowhere\n    vehicles: examples/bad/vehicles.csv\n",
        encoding="utf-8",
    )
    with pytest.raises(SuiteErrors) as caught:
        load_suite(path)
    problems = [e.problem for e in caught.value.errors]
    assert problems[0].startswith("defaults.vehicle_type: 'agx' is not a vehicle type")
    assert problems[1].startswith("scenarios[0].dir: no such directory")
    assert problems[2:] == ["'sideways' is not 'forward' or 'backward'"]  # not "names no vehicle type"


def test_a_clean_suite_entry_with_named_files_still_loads(tmp_path: Path) -> None:
    scenario(
        tmp_path,
        vehicles="vehicle_id,start_segment_id,segment_orientation\n1,1,forward\n2,5,forward\n",
        tasks="vehicle_id,goal_segment_id\n1,4\n2,8\n",
    )
    path = suite(tmp_path, "    dir: examples/bad\n    tasks: examples/bad/tasks.csv\n")
    loaded = load_suite(path)
    built = load_scenario(loaded.scenarios[0], loaded)
    assert [(t.vehicle_id, t.goal_segment) for t in built.tasks] == [(1, 4), (2, 8)]
