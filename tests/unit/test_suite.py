"""Suites: settings inheritance, expectations, files, and the checks a schema cannot make."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from fleetsim.enums import ConflictModel, TurnCapability
from fleetsim.errors import SuiteError
from fleetsim.load.suites.suite import Suite, discover_suites, load_suite
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Expectations, ScenarioSettings

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"

FILES = (
    "crossing/map.json",
    "crossing/vehicles.csv",
    "crossing/tasks.csv",
    "maps/loop.tmx",
    "loop/vehicles.csv",
    "loop/tasks.csv",
)

SUITE = """\
# yaml-language-server: $schema=../schemas/suite.schema.json
fleetsim: 1
name: crossings
description: Two vehicles cross a junction.
vehicle_types:
  agv: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5,
        turn_capability: in_place, turn_rate: 45, color: "#ff0000"}
  tug: {length: 2.0, width: 1.0, height: 1.0, max_speed: 2.0, acceleration: 1.0,
        turn_capability: curve, color: [0, 0, 1]}
defaults:
  vehicle_type: agv
  time_limit: 200
  conflict_model: bbox
scenarios:
  - name: crossing
    dir: crossing/
    tags: [smoke, night_shift]
    expect:
      tasks: 1
      collisions: [11, 12]
      rejections: [wrong-way]
      deadlock: true
      max_makespan: 60
    xfail: "planner cannot do this yet"
  - name: loop-explicit
    description: Explicit file paths.
    map: maps/loop.tmx
    vehicles: loop/vehicles.csv
    tasks: loop/tasks.csv
    time_limit: 120
    vehicle_type: TUG
    stop_on: []
"""


def make_suite(tmp_path: Path, text: str = SUITE, files: tuple[str, ...] = FILES) -> Path:
    for name in files:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("", encoding="utf-8")
    path = tmp_path / "crossings.fleetsim.yaml"
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


@pytest.fixture
def suite(tmp_path: Path) -> Suite:
    return load_suite(make_suite(tmp_path))


def test_suite_header_and_vehicle_types_load(suite: Suite) -> None:
    assert (suite.name, suite.description) == ("crossings", "Two vehicles cross a junction.")
    agv, tug = suite.vehicle_types["agv"], suite.vehicle_types["tug"]
    assert (agv.turn_capability, agv.turn_rate) == (TurnCapability.IN_PLACE, 45.0)
    assert (tug.turn_capability, tug.turn_rate) == (TurnCapability.CURVE, 90.0)  # the default rate
    assert (agv.color, tug.color) == ((1.0, 0.0, 0.0, 1.0), (0.0, 0.0, 1.0, 1.0))


def test_vehicle_types_are_read_only(suite: Suite) -> None:
    with pytest.raises(TypeError):
        suite.vehicle_types["new"] = DEFAULT_VEHICLE_TYPE  # type: ignore[index]


def test_scenarios_keep_file_order_and_entry_lines(suite: Suite) -> None:
    assert [(spec.name, spec.line) for spec in suite.scenarios] == [("crossing", 15), ("loop-explicit", 25)]


def test_a_scenario_inherits_defaults_and_overrides_only_what_it_sets(suite: Suite) -> None:
    crossing, loop = (spec.settings for spec in suite.scenarios)
    assert crossing == ScenarioSettings(vehicle_type="agv", time_limit=200.0, conflict_model=ConflictModel.BBOX)
    assert loop == ScenarioSettings(vehicle_type="tug", time_limit=120.0, conflict_model=ConflictModel.BBOX, stop_on=())


def test_expectations_tags_and_xfail_are_read(suite: Suite) -> None:
    crossing = suite.scenarios[0]
    assert crossing.expect == Expectations(
        tasks=1, collisions=(11, 12), rejections=("wrong-way",), deadlock=True, max_makespan=60.0
    )
    assert (crossing.tags, crossing.xfail) == (("smoke", "night_shift"), "planner cannot do this yet")
    assert suite.scenarios[1].description == "Explicit file paths."


def test_expectations_tags_and_xfail_default_when_absent(suite: Suite) -> None:
    loop = suite.scenarios[1]
    assert (loop.expect, loop.tags, loop.xfail) == (Expectations(), (), None)
    assert suite.scenarios[0].description == ""


def test_dir_and_explicit_paths_resolve_relative_to_the_suite_file(tmp_path: Path, suite: Suite) -> None:
    crossing, loop = suite.scenarios
    assert (crossing.map_path, crossing.vehicles_path, crossing.tasks_path) == (
        tmp_path / "crossing/map.json",
        tmp_path / "crossing/vehicles.csv",
        tmp_path / "crossing/tasks.csv",
    )
    assert (loop.map_path, loop.vehicles_path, loop.tasks_path) == (
        tmp_path / "maps/loop.tmx",
        tmp_path / "loop/vehicles.csv",
        tmp_path / "loop/tasks.csv",
    )
    assert crossing.suite_path == tmp_path / "crossings.fleetsim.yaml"


def test_a_file_named_next_to_dir_replaces_the_folders_file(tmp_path: Path) -> None:
    text = SUITE.replace("    dir: crossing/\n", "    dir: crossing/\n    tasks: loop/tasks.csv\n")
    crossing = load_suite(make_suite(tmp_path, text)).scenarios[0]
    assert crossing.map_path == tmp_path / "crossing/map.json"
    assert crossing.tasks_path == tmp_path / "loop/tasks.csv"


def test_an_explicit_map_next_to_dir_settles_two_map_candidates(tmp_path: Path) -> None:
    text = SUITE.replace("    dir: crossing/\n", "    dir: crossing/\n    map: crossing/map.tmx\n")
    crossing = load_suite(make_suite(tmp_path, text, (*FILES, "crossing/map.tmx"))).scenarios[0]
    assert crossing.map_path == tmp_path / "crossing/map.tmx"


def test_without_vehicle_types_the_built_in_default_type_is_used(tmp_path: Path) -> None:
    text = "fleetsim: 1\nname: s\nscenarios:\n  - {name: a, dir: crossing}\n"
    suite = load_suite(make_suite(tmp_path, text))
    assert dict(suite.vehicle_types) == {"default": DEFAULT_VEHICLE_TYPE}
    assert suite.scenarios[0].settings.vehicle_type == "default"


def test_a_single_vehicle_type_is_the_default_without_being_named(tmp_path: Path) -> None:
    text = SUITE.replace("  vehicle_type: agv\n", "").replace("    vehicle_type: TUG\n", "")
    text = text[: text.index("  tug:")] + text[text.index("defaults:") :]
    suite = load_suite(make_suite(tmp_path, text))
    assert [spec.settings.vehicle_type for spec in suite.scenarios] == ["agv", "agv"]


def test_several_vehicle_types_and_none_chosen_leave_the_default_open(tmp_path: Path) -> None:
    text = SUITE.replace("  vehicle_type: agv\n", "").replace("    vehicle_type: TUG\n", "")
    suite = load_suite(make_suite(tmp_path, text))
    assert [spec.settings.vehicle_type for spec in suite.scenarios] == [None, None]


# -- checks beyond the schema ---------------------------------------------------------------------


CODE_CHECKS = [
    pytest.param(
        ("name: loop-explicit", "name: crossing"),
        (25, 11),
        "scenarios[1].name: scenario name 'crossing' is already used on line 15",
        id="duplicate-name",
    ),
    pytest.param(
        ("name: loop-explicit", "name: Crossing"),
        (25, 11),
        "names may not differ only in case",
        id="duplicate-name-differing-in-case",
    ),
    pytest.param(
        ("  vehicle_type: agv", "  vehicle_type: agx"),
        (11, 17),
        "defaults.vehicle_type: 'agx' is not a vehicle type of this suite (agv, tug); did you mean 'agv'?",
        id="unknown-default-vehicle-type",
    ),
    pytest.param(
        ("vehicle_type: TUG", "vehicle_type: crane"),
        (31, 19),
        "scenarios[1].vehicle_type: 'crane' is not a vehicle type",
        id="unknown-scenario-vehicle-type",
    ),
    pytest.param(
        ("  tug: {", "  AGV: {"),
        (8, 3),
        "vehicle_types: 'AGV' differs from vehicle type 'agv' only in case",
        id="type-names-differ-in-case",
    ),
    pytest.param(
        ("dir: crossing/", "dir: crosing/"), (16, 10), "scenarios[0].dir: no such directory", id="missing-dir"
    ),
    pytest.param(
        ("map: maps/loop.tmx", "map: maps/lop.tmx"), (27, 10), "scenarios[1].map: no such file", id="missing-map-file"
    ),
    pytest.param(
        ("tasks: loop/tasks.csv", "tasks: loop/task.csv"),
        (29, 12),
        "scenarios[1].tasks: no such file",
        id="missing-tasks-file",
    ),
    pytest.param(
        ("time_limit: 200", "time_limit: .nan"),
        (12, 15),
        "defaults.time_limit: nan is not a finite number",
        id="nan-setting",
    ),
]


@pytest.mark.parametrize(("change", "line_column", "problem"), CODE_CHECKS)
def test_suite_mistakes_give_one_error_at_the_offending_value(
    tmp_path: Path, change: tuple[str, str], line_column: tuple[int, int], problem: str
) -> None:
    with pytest.raises(SuiteError) as caught:
        load_suite(make_suite(tmp_path, SUITE.replace(*change)))
    location = caught.value.location
    assert location is not None
    assert (location.line, location.column) == line_column
    assert problem in caught.value.problem


@pytest.mark.parametrize(
    ("files", "problem"),
    [
        pytest.param(
            FILES[1:], "has no map.json, map.tmj, map.tmx, map.lif.json or map.building.yaml", id="no-map-in-dir"
        ),
        pytest.param((*FILES, "crossing/map.tmx"), "has both map.json and map.tmx", id="two-maps-in-dir"),
        pytest.param(FILES[:1] + FILES[2:], "has no vehicles.csv", id="no-vehicles-in-dir"),
    ],
)
def test_a_scenario_folder_must_hold_one_map_and_both_csv_files(
    tmp_path: Path, files: tuple[str, ...], problem: str
) -> None:
    with pytest.raises(SuiteError, match=problem) as caught:
        load_suite(make_suite(tmp_path, files=files))
    assert caught.value.location is not None and caught.value.location.line == 16  # the dir key


def test_empty_suite_file_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(SuiteError, match="empty file"):
        load_suite(make_suite(tmp_path, "# nothing\n"))


# -- discovery ------------------------------------------------------------------------------------


def test_discover_finds_suite_files_sorted_and_skips_hidden_directories(tmp_path: Path) -> None:
    for name in ("b/z.fleetsim.yaml", "a.fleetsim.yaml", "b/other.yaml", ".venv/x.fleetsim.yaml"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("", encoding="utf-8")
    explicit = tmp_path / "b/other.yaml"
    assert discover_suites([tmp_path / "b", tmp_path, explicit]) == [
        tmp_path / "a.fleetsim.yaml",
        explicit,
        tmp_path / "b/z.fleetsim.yaml",
    ]


def test_discover_rejects_a_path_that_does_not_exist(tmp_path: Path) -> None:
    with pytest.raises(SuiteError, match="no such file or directory"):
        discover_suites([tmp_path / "missing"])


def test_a_suite_may_pin_its_planner_and_a_malformed_pin_is_located(tmp_path: Path) -> None:
    pinned = load_suite(SUITES / "caught-bugs.fleetsim.yaml")
    assert pinned.planner == "fleetsim.planners:BFSPlanner"
    assert load_suite(SUITES / "examples.fleetsim.yaml").planner is None
    text = (SUITES / "caught-bugs.fleetsim.yaml").read_text(encoding="utf-8")
    bad = tmp_path / "caught-bugs.fleetsim.yaml"
    bad.write_text(text.replace("planner: fleetsim.planners:BFSPlanner", "planner: BFSPlanner"), encoding="utf-8")
    with pytest.raises(SuiteError, match=r"caught-bugs\.fleetsim\.yaml:\d+:\d+: .*'BFSPlanner'"):
        load_suite(bad)
