"""Open-RMF building maps as driving maps: pixel and metre coordinates, lanes, graphs, levels, names."""

from __future__ import annotations

from pathlib import Path

import pytest
from site_documents import save_yaml

from fleetsim.enums import Direction, Shape
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.site_map import load_site_map

TWO_LEVELS = """\
name: test
levels:
  L1:
    vertices:
      - [100, 400, 0, dock]
      - [300, 400, 0, ""]
      - [300, 200, 0, ward, {is_charger: [4, true], is_holding_point: [4, true]}]
      - [100, 200, 0, ""]
      - [0, 0, 0, ""]
      - [400, 0, 0, ""]
      - [0, 300, 0, ""]
    measurements:
      - [4, 5, {distance: [3, 20]}]
      - [4, 6, {distance: [3, 16.5]}]
    lanes:
      - [0, 1, {bidirectional: [4, true], graph_idx: [2, 0], orientation: [1, ""], speed_limit: [3, 0]}]
      - [1, 2, {bidirectional: [4, false], graph_idx: [2, 0]}]
      - [2, 3, {bidirectional: [4, false], graph_idx: [2, 0], speed_limit: [3, 0.5]}]
      - [3, 0, {graph_idx: [2, 1]}]
      - [0, 1, {bidirectional: [4, true], graph_idx: [2, 0]}]
    doors:
      - [2, 3, {name: [1, d1], type: [1, hinged]}]
  L2:
    vertices:
      - [0, 0, 0, up_a]
      - [10, 0, 0, up_b]
    lanes:
      - [1, 0, {bidirectional: [4, false]}]
lifts:
  lift_1: {x: 10, y: 10}
"""


def load(tmp_path: Path, text: str = TWO_LEVELS, **options: object):  # type: ignore[no-untyped-def]
    return load_site_map(save_yaml(tmp_path, text), MapOptions(**options))  # type: ignore[arg-type]


def test_pixel_coordinates_are_scaled_by_the_mean_of_the_measurements_with_y_pointing_down(tmp_path: Path) -> None:
    site = load(tmp_path)
    scale = (20 / 400 + 16.5 / 300) / 2  # metres per pixel: the mean over the measurements
    assert site.format == "rmf" and site.meters_per_pixel == pytest.approx(scale)
    first = site.segments[0]
    assert [c for point in first.waypoints for c in point] == pytest.approx(
        [100 * scale, -400 * scale, 300 * scale, -400 * scale]
    )


def test_lanes_become_straight_segments_two_way_or_one_way_in_lane_order(tmp_path: Path) -> None:
    site = load(tmp_path)
    assert [(s.id, s.shape, s.direction, s.names) for s in site.segments] == [
        (1, Shape.STRAIGHT, Direction.BOTH, ("dock--v1", "v1--dock")),
        (2, Shape.STRAIGHT, Direction.FORWARD, ("v1--ward",)),
        (3, Shape.STRAIGHT, Direction.FORWARD, ("ward--v3",)),
        (4, Shape.STRAIGHT, Direction.BOTH, ("dock--v1#2", "v1--dock")),  # a second lane between the same waypoints
    ]
    assert site.part == "level 'L1', graph 0"


def test_metre_coordinates_are_taken_as_they_are(tmp_path: Path) -> None:
    text = "coordinate_system: cartesian_meters\n" + TWO_LEVELS.replace("name: test\n", "")
    site = load(tmp_path, text)
    assert site.meters_per_pixel is None
    assert site.segments[1].waypoints == ((300.0, 400.0), (300.0, 200.0))  # y up already: not flipped


def test_a_level_without_measurements_reads_pixels_as_metres_with_a_warning(tmp_path: Path) -> None:
    site = load(tmp_path, level="L2")
    assert [(s.direction, s.names, s.waypoints) for s in site.segments] == [
        (Direction.FORWARD, ("up_b--up_a",), ((10.0, -0.0), (0.0, -0.0)))
    ]
    assert any(
        "a level without measurements (its scale is unknown: pixels are read as metres)" in w for w in site.warnings
    )


def test_another_graph_is_chosen_by_its_graph_idx(tmp_path: Path) -> None:
    site = load(tmp_path, graph=1)
    assert [(s.direction, s.names) for s in site.segments] == [(Direction.FORWARD, ("v3--dock",))]


def test_everything_not_modelled_is_noted_once_per_kind(tmp_path: Path) -> None:
    kinds = [w.split("warning ", 1)[1].split(" (")[0] for w in load(tmp_path, robot_type="x").warnings]
    assert kinds == [
        "not-modelled: a lift",
        "not-modelled: another level",
        "not-modelled: a door",
        "not-modelled: vertex parameter 'is_holding_point'",
        "not-modelled: lane parameter 'speed_limit'",
        "not-modelled: a lane of another graph",
        "option-ignored: map option 'robot_type'",
    ]


def test_default_lane_parameters_and_a_single_level_give_no_warnings(tmp_path: Path) -> None:
    text = """\
levels:
  only:
    vertices: [[0, 0, 0, a], [100, 0, 0, b]]
    measurements: [[0, 1, {distance: [3, 5]}]]
    lanes: [[0, 1, {bidirectional: [4, true], graph_idx: [2, 0], orientation: [1, ""], speed_limit: [3, 0], mutex: [1, ""]}]]
"""
    site = load(tmp_path, text)
    assert site.warnings == () and site.segments[0].waypoints == ((0.0, -0.0), (5.0, -0.0))


def test_the_first_level_is_the_default_and_others_are_chosen_by_name(tmp_path: Path) -> None:
    assert load(tmp_path).part.startswith("level 'L1'")
    assert load(tmp_path, level="L2").part == "level 'L2', graph 0"


def test_tasks_name_lanes_by_their_waypoints(tmp_path: Path) -> None:
    from fleetsim.load.suites.scenario import load_scenario_dir

    save_yaml(
        tmp_path,
        TWO_LEVELS.replace("      - [0, 1, {bidirectional: [4, true], graph_idx: [2, 0]}]\n", ""),
        "map.building.yaml",
    )
    (tmp_path / "vehicles.csv").write_text("vehicle_id,start_segment_id,segment_orientation\n1,v1--dock,backward\n")
    (tmp_path / "tasks.csv").write_text("vehicle_id,goal_segment_id\n1,ward--v3\n")
    scenario = load_scenario_dir(tmp_path)
    assert (scenario.vehicles[0].start_segment, scenario.tasks[0].goal_segment) == (1, 3)
