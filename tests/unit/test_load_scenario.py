"""Assembling a scenario: map → vehicles → layout → tasks, the start-conflict check, all or nothing."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from fleetsim.enums import ConflictModel, Direction, Shape, TurnCapability
from fleetsim.errors import LoadError, MapError, ScenarioFileError, SuiteError
from fleetsim.layout.segment import Segment
from fleetsim.load.suites.scenario import load_scenario, load_scenario_dir
from fleetsim.load.suites.suite import load_suite
from fleetsim.load.tiled.writer import write_map
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Expectations, Scenario, ScenarioSettings, VehicleType

# Segments 1 and 2 touch at x=5 (so they conflict); segment 3 is far away from both.
SEGMENTS = (
    Segment(1, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (5.0, 0.0))),
    Segment(2, Shape.STRAIGHT, Direction.FORWARD, ((5.0, 0.0), (10.0, 0.0))),
    Segment(3, Shape.STRAIGHT, Direction.BOTH, ((0.0, 4.0), (10.0, 4.0))),
)
HEADER = "vehicle_id,start_segment_id,segment_orientation,progress_direction,type\n"
BIG = VehicleType("big", 4.0, 3.0, 1.0, 1.0, 0.5, TurnCapability.CURVE)


NO_TASKS = "vehicle_id,goal_segment_id\n"


def make_dir(tmp_path: Path, vehicles: str, tasks: str = NO_TASKS, name: str = "sc") -> Path:
    folder = tmp_path / name
    folder.mkdir(exist_ok=True)
    write_map(folder / "map.json", SEGMENTS)
    (folder / "vehicles.csv").write_text(HEADER + vehicles, encoding="utf-8")
    (folder / "tasks.csv").write_text(tasks, encoding="utf-8")
    return folder


def test_a_scenario_folder_loads_completely(tmp_path: Path) -> None:
    folder = make_dir(tmp_path, "1,1,forward,,\n2,3,backward,reverse,\n", NO_TASKS + "1,2\n2,3\n")
    scenario = load_scenario_dir(folder)
    assert scenario.name == "sc"
    assert sorted(scenario.layout.segments) == [1, 2, 3]
    assert [(v.id, v.start_segment, v.type) for v in scenario.vehicles] == [
        (1, 1, DEFAULT_VEHICLE_TYPE),
        (2, 3, DEFAULT_VEHICLE_TYPE),
    ]
    assert [(t.id, t.vehicle_id, t.goal_segment) for t in scenario.tasks] == [(1, 1, 2), (2, 2, 3)]
    assert (scenario.settings, scenario.expect) == (ScenarioSettings(), Expectations())
    assert (scenario.map_path, scenario.vehicles_path, scenario.tasks_path) == (
        folder / "map.json",
        folder / "vehicles.csv",
        folder / "tasks.csv",
    )


def test_vehicles_starting_on_conflicting_segments_are_rejected_naming_both(tmp_path: Path) -> None:
    folder = make_dir(tmp_path, "1,1,forward,,\n2,3,forward,,\n3,2,forward,,\n")
    with pytest.raises(ScenarioFileError) as caught:
        load_scenario_dir(folder)
    assert str(caught.value) == (
        f"{folder / 'vehicles.csv'}:4: field 'start_segment_id': vehicles 1 (line 2, segment 1) and "
        "3 (line 4, segment 2) start on conflicting segments; move one, or set allow_start_conflicts: true "
        "for this scenario"
    )


def test_two_vehicles_on_the_same_segment_conflict(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError, match=r"vehicles 1 .* and 2 .* start on conflicting segments"):
        load_scenario_dir(make_dir(tmp_path, "1,3,forward,,\n2,3,backward,,\n"))


def test_allow_start_conflicts_accepts_conflicting_starts(tmp_path: Path) -> None:
    folder = make_dir(tmp_path, "1,1,forward,,\n2,2,forward,,\n")
    scenario = load_scenario_dir(folder, settings=ScenarioSettings(allow_start_conflicts=True))
    assert [vehicle.id for vehicle in scenario.vehicles] == [1, 2]


def test_a_larger_vehicle_type_in_use_widens_the_conflicts(tmp_path: Path) -> None:
    types = {"default": DEFAULT_VEHICLE_TYPE, "big": BIG}
    small = load_scenario_dir(
        make_dir(tmp_path, "1,1,forward,,\n2,3,forward,,\n", name="small"),
        vehicle_types=types,
        settings=ScenarioSettings(vehicle_type="default"),
    )
    assert small.layout.vehicle_radius == DEFAULT_VEHICLE_TYPE.swept_radius
    with pytest.raises(ScenarioFileError, match="start on conflicting segments"):
        load_scenario_dir(
            make_dir(tmp_path, "1,1,forward,,big\n2,3,forward,,\n", name="big"),
            vehicle_types=types,
            settings=ScenarioSettings(vehicle_type="default"),
        )


def test_the_bbox_model_uses_the_bbox_radius(tmp_path: Path) -> None:
    folder = make_dir(tmp_path, "1,1,forward,,\n")
    scenario = load_scenario_dir(folder, settings=ScenarioSettings(conflict_model=ConflictModel.BBOX))
    assert scenario.layout.conflict_model is ConflictModel.BBOX
    assert scenario.layout.vehicle_radius == DEFAULT_VEHICLE_TYPE.bbox_radius


def test_without_vehicles_the_default_type_sets_the_radius(tmp_path: Path) -> None:
    types = {"default": DEFAULT_VEHICLE_TYPE, "big": BIG}
    settings = ScenarioSettings(vehicle_type="big")
    scenario = load_scenario_dir(make_dir(tmp_path, ""), vehicle_types=types, settings=settings)
    assert (scenario.vehicles, scenario.layout.vehicle_radius) == ((), BIG.swept_radius)


@pytest.mark.parametrize(
    ("files", "problem"),
    [
        pytest.param(
            ("vehicles.csv", "tasks.csv"),
            "needs exactly one of map.json, map.tmj, map.tmx, map.lif.json, map.building.yaml; found none",
            id="no-map",
        ),
        pytest.param(("map.json", "map.tmj", "vehicles.csv", "tasks.csv"), "found map.json and map.tmj", id="two-maps"),
    ],
)
def test_a_scenario_folder_needs_exactly_one_map(tmp_path: Path, files: tuple[str, ...], problem: str) -> None:
    for name in files:
        (tmp_path / name).write_text("", encoding="utf-8")
    with pytest.raises(ScenarioFileError, match=problem):
        load_scenario_dir(tmp_path)


def test_a_missing_folder_is_a_located_error(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError, match="nowhere: no such directory"):
        load_scenario_dir(tmp_path / "nowhere")


def test_a_missing_tasks_file_is_a_located_error(tmp_path: Path) -> None:
    folder = make_dir(tmp_path, "1,1,forward,,\n")
    (folder / "tasks.csv").unlink()
    with pytest.raises(ScenarioFileError, match=r"tasks\.csv: file not found"):
        load_scenario_dir(folder)


def test_a_broken_map_is_one_map_error(tmp_path: Path) -> None:
    folder = make_dir(tmp_path, "1,1,forward,,\n")
    (folder / "map.json").write_text("{not json", encoding="utf-8")
    with pytest.raises(MapError):
        load_scenario_dir(folder)


# -- through a suite ------------------------------------------------------------------------------

SUITE = """\
fleetsim: 1
name: s
vehicle_types:
  small: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}
  big: {length: 4.0, width: 3.0, height: 1.0, max_speed: 1.0, acceleration: 0.5, turn_capability: curve}
defaults:
  vehicle_type: small
  connection_tolerance: 0.1
scenarios:
  - name: one
    dir: sc
    joint_angle_tolerance: 20
    expect: {collisions: [1, 2], tasks: 1}
"""


def load_first(tmp_path: Path, suite_text: str, vehicles: str, tasks: str = NO_TASKS) -> Scenario:
    make_dir(tmp_path, vehicles, tasks)
    path = tmp_path / "s.fleetsim.yaml"
    path.write_text(textwrap.dedent(suite_text), encoding="utf-8")
    suite = load_suite(path)
    return load_scenario(suite.scenarios[0], suite)


def test_a_suite_scenario_gets_its_settings_types_and_expectations(tmp_path: Path) -> None:
    text = SUITE + "    allow_start_conflicts: true\n"  # the big vehicle reaches across to segment 1
    scenario = load_first(tmp_path, text, "1,1,forward,,\n2,3,forward,,big\n", NO_TASKS + "2,3\n")
    assert scenario.name == "one"
    assert [vehicle.type.name for vehicle in scenario.vehicles] == ["small", "big"]
    assert (scenario.layout.connection_tolerance, scenario.layout.joint_angle_tolerance) == (0.1, 20.0)
    assert scenario.layout.vehicle_radius == BIG.swept_radius
    assert scenario.expect == Expectations(tasks=1, collisions=(1, 2))
    assert set(scenario.vehicle_types) == {"small", "big"}


def test_expected_collisions_on_a_segment_not_in_the_map_are_rejected(tmp_path: Path) -> None:
    pattern = r"s.fleetsim.yaml:10: scenario 'one': expect.collisions names segment 9"
    with pytest.raises(SuiteError, match=pattern):
        load_first(tmp_path, SUITE.replace("[1, 2]", "[1, 9]"), "1,1,forward,,\n")


def test_an_unknown_start_segment_names_the_map_file(tmp_path: Path) -> None:
    pattern = r"vehicles.csv:2: field 'start_segment_id': segment 7 is not in map.json"
    with pytest.raises(ScenarioFileError, match=pattern):
        load_first(tmp_path, SUITE, "1,7,forward,,\n")


def test_rows_without_type_fail_when_several_types_and_no_default(tmp_path: Path) -> None:
    with pytest.raises(ScenarioFileError, match=r"vehicles.csv:2: field 'type': .*no default type"):
        load_first(tmp_path, SUITE.replace("  vehicle_type: small\n", ""), "1,1,forward,,\n")


def test_every_load_failure_is_a_load_error(tmp_path: Path) -> None:
    with pytest.raises(LoadError):
        load_first(tmp_path, SUITE, "1,1,forward,,\n", "vehicle_id,goal_segment_id\n5,1\n")


def test_map_warnings_reach_the_scenario(tmp_path: Path) -> None:
    folder = make_dir(tmp_path, "1,1,forward,,\n")
    doc = (folder / "map.json").read_text(encoding="utf-8")
    # Turn segment 3 into a polygon: a shape class on a non-polyline is skipped with a warning.
    start = doc.index('{"id":3,')
    marked = doc[:start] + doc[start:].replace('"polyline"', '"polygon"', 1)
    (folder / "map.json").write_text(marked, encoding="utf-8")
    scenario = load_scenario_dir(folder)
    assert sorted(scenario.layout.segments) == [1, 2]
    assert len(scenario.warnings) == 1 and "object 3" in scenario.warnings[0] and "polygon" in scenario.warnings[0]
