"""MovingAI grid maps and scenario files: the lane graph, the agents' vehicles and tasks, every located error."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fleetsim.enums import Direction, Traverse
from fleetsim.errors import LoadError, LoadErrors, MapError, ScenarioFileError
from fleetsim.layout.layout import build_layout
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite

GRID = ["..@.", ".T..", "S.WE"]


def write_map(folder: Path, rows: list[str], name: str = "grid.map", header: str | None = None) -> Path:
    head = header if header is not None else f"type octile\nheight {len(rows)}\nwidth {len(rows[0])}\nmap\n"
    path = folder / name
    path.write_text(head + "\n".join(rows) + "\n")
    return path


def write_scen(folder: Path, agents: list[tuple[int, int, int, int]], map_name: str = "grid.map") -> Path:
    lines = ["version 1"] + [f"0\t{map_name}\t4\t3\t{sx}\t{sy}\t{gx}\t{gy}\t3" for sx, sy, gx, gy in agents]
    path = folder / "grid.scen"
    path.write_text("\n".join(lines) + "\n")
    return path


def write_suite(folder: Path, entry: str) -> Path:
    path = folder / "grid.fleetsim.yaml"
    path.write_text(f"fleetsim: 1\nname: grid\nscenarios:\n  - name: one\n{entry}")
    return path


def load_entry(folder: Path, entry: str) -> object:
    suite = load_suite(write_suite(folder, entry))
    return load_scenario(suite.scenarios[0], suite)


def test_a_segment_joins_every_two_free_neighbours_named_after_their_cells(tmp_path: Path) -> None:
    site = load_site_map(write_map(tmp_path, GRID))
    names = [segment.name for segment in site.segments]
    assert names == ["r0c0-r0c1", "r0c0-r1c0", "r0c3-r1c3", "r1c0-r2c0", "r1c2-r1c3", "r1c3-r2c3", "r2c0-r2c1"]
    assert site.format == "movingai" and site.part == "4 x 3 cells of 1 m"
    first = site.segments[0]
    assert first.id == 1 and first.direction is Direction.BOTH and first.names[1] == "r0c1-r0c0"
    assert first.ends == ("r0c0", "r0c1")
    # Row 0 is the top; the origin is the map's centre, y up.
    assert first.waypoints == ((-1.5, 1.0), (-0.5, 1.0))


def test_swamp_emitter_and_ground_are_free_water_trees_and_out_of_bounds_are_not(tmp_path: Path) -> None:
    site = load_site_map(write_map(tmp_path, [".GSE", "@OTW", "...."]))
    names = {segment.names[0] for segment in site.segments}
    assert {"r0c0-r0c1", "r0c1-r0c2", "r0c2-r0c3"} <= names
    assert not any("r1c" in name for name in names)


def test_cell_size_scales_the_map_and_a_corner_is_a_turn_in_place(tmp_path: Path) -> None:
    site = load_site_map(write_map(tmp_path, GRID), MapOptions(cell_size=0.5))
    assert site.segments[0].waypoints == ((-0.75, 0.5), (-0.25, 0.5))
    layout = build_layout(site.segments, vehicle_radius=0.1)
    joints = {(to, joint) for to, _, joint in layout.successors(2, Traverse.BACKWARD)}
    assert (1, "turn_in_place") in joints


def test_a_cell_size_for_another_format_is_noted(tmp_path: Path) -> None:
    map_path = write_map(tmp_path, GRID)
    assert load_site_map(map_path, MapOptions(level="L1")).warnings[0].endswith("it does not apply to this map")


@pytest.mark.parametrize(
    ("text", "line", "column", "words"),
    [
        ("type octile\nheight 2\nwidth 3\nmap\n...\n..\n", 6, 3, "2 cell(s) wide; the header says width 3"),
        ("type octile\nheight 2\nwidth 3\nmap\n...\n....\n", 6, 4, "4 cell(s) wide"),
        ("type octile\nheight 2\nwidth 3\nmap\n.x.\n...\n", 5, 2, "unknown cell character 'x'"),
        ("type octile\nheight 3\nwidth 3\nmap\n...\n...\n", 7, None, "2 row(s) but the header says height 3"),
        ("type octile\nheight 1\nwidth 3\nmap\n...\n...\n", 6, 1, "a line after the grid's 1 rows"),
        ("type grid\nheight 1\nwidth 3\nmap\n...\n", 1, None, "fleetsim reads 'type octile' maps"),
        ("type octile\nwidth 3\nheight 1\nmap\n...\n", 2, None, "must be 'height H'"),
        ("type octile\nheight two\nwidth 3\nmap\n...\n", 2, None, "with a whole number"),
        ("type octile\nheight 0\nwidth 3\nmap\n...\n", 2, None, "height=0 must be from 1"),
        ("type octile\nheight 1\nwidth 3\n", 4, None, "header line 4 must be 'map', not an empty line"),
        ("type octile\nheight 1", 2, None, "the header ends early: line 3 must be 'width W'"),
        ("type octile\nheight 1\nwidth 3\nmaps\n...\n", 4, None, "must be 'map'"),
        ("type octile\nheight 1\nwidth 3\nmap\n.@.\n", None, None, "no two neighbouring free cells"),
    ],
)
def test_a_broken_map_is_a_located_error(tmp_path: Path, text: str, line: int, column: int, words: str) -> None:
    path = tmp_path / "bad.map"
    path.write_text(text)
    with pytest.raises(MapError, match=re.escape(words)) as caught:
        load_site_map(path)
    assert caught.value.location is not None
    assert (caught.value.location.line, caught.value.location.column) == (line, column)


def test_every_bad_row_is_reported_at_once(tmp_path: Path) -> None:
    path = tmp_path / "bad.map"
    path.write_text("type octile\nheight 3\nwidth 3\nmap\n.?.\n...\n..\n")
    with pytest.raises(LoadErrors) as caught:
        load_site_map(path)
    assert [(e.location.line, e.location.column) for e in caught.value.errors if e.location] == [(5, 2), (7, 3)]


def test_a_non_positive_cell_size_is_refused(tmp_path: Path) -> None:
    with pytest.raises(MapError, match="cell_size=0 must be a positive number"):
        load_site_map(write_map(tmp_path, GRID), MapOptions(cell_size=0))


# -- .scen -------------------------------------------------------------------------------------------


def test_the_first_n_agents_become_vehicles_with_one_task_each(tmp_path: Path) -> None:
    write_map(tmp_path, [".....", ".@.@.", "....."])
    scen = tmp_path / "grid.scen"
    rows = ["0\tgrid.map\t5\t3\t0\t0\t4\t2\t6", "0\tgrid.map\t5\t3\t4\t0\t0\t2\t6", "0\tgrid.map\t5\t3\t2\t1\t2\t1\t0"]
    scen.write_text("version 1\n" + "\n".join(rows) + "\n")
    scenario = load_entry(tmp_path, "    scen: grid.scen\n    agents: 2\n")
    vehicles, tasks, layout = scenario.vehicles, scenario.tasks, scenario.layout  # type: ignore[attr-defined]
    assert [vehicle.id for vehicle in vehicles] == [1, 2] and len(tasks) == 2
    first = vehicles[0]
    segment = layout.segments[first.start_segment]
    # Agent 1 stands on the centre of (x=0, y=0) and faces its neighbour nearer the goal.
    assert segment.entry(first.traverse) == (-2.0, 1.0)
    assert first.type.name == "movingai" and first.type.max_speed == 1.0
    goal = layout.segments[tasks[0].goal_segment]
    assert set(goal.ends or ()) in ({"r2c4", "r2c3"}, {"r2c4", "r1c4"})


def test_without_agents_every_agent_runs_and_the_suite_type_wins(tmp_path: Path) -> None:
    write_map(tmp_path, [".....", ".@.@.", "....."])
    (tmp_path / "grid.scen").write_text(
        "version 1\n0\tgrid.map\t5\t3\t0\t0\t4\t2\t6\n0\tgrid.map\t5\t3\t4\t0\t0\t2\t6\n"
    )
    suite_path = tmp_path / "typed.fleetsim.yaml"
    suite_path.write_text(
        "fleetsim: 1\nname: typed\nvehicle_types:\n  bot: {length: 0.4, width: 0.4, height: 0.4, max_speed: 2,"
        " acceleration: 1, turn_capability: in_place}\nscenarios:\n  - name: one\n    scen: grid.scen\n"
    )
    suite = load_suite(suite_path)
    scenario = load_scenario(suite.scenarios[0], suite)
    assert [vehicle.type.name for vehicle in scenario.vehicles] == ["bot", "bot"]


@pytest.mark.parametrize(
    ("scen", "field", "words"),
    [
        ("version 1\n0\tgrid.map\t4\t3\t1\t0\t0\t0\t1\n", "start_x", "start (x=1, y=0) is on a blocked cell '@'"),
        ("version 1\n0\tgrid.map\t4\t3\t0\t0\t2\t2\t1\n", "goal_x", "goal (x=2, y=2) is on a blocked cell"),
        ("version 1\n0\tgrid.map\t4\t3\t9\t0\t0\t0\t1\n", "start_x", "off the map"),
        ("version 1\n0\tgrid.map\t4\t3\t0\t0\t0\t7\t1\n", "goal_y", "off the map"),
        ("version 1\n0\tother.map\t4\t3\t0\t0\t0\t2\t1\n", "map", "is not the scenario's map 'grid.map'"),
        ("version 1\n0\tgrid.map\t5\t3\t0\t0\t0\t2\t1\n", "width", "width=5 is not the map's width, 4"),
        ("version 1\n0\tgrid.map\t4\t3\t0\t0\tx\t2\t1\n", "goal_x", "goal_x='x' must be a whole number"),
        ("version 1\n0\tgrid.map\t4\t3\t0\t0\t0\t2\tnan\n", "optimal_length", "must be a number >= 0"),
        ("version 1\n0\tgrid.map\t4\t3\t0\t0\t0\n", None, "the row has 7 field(s)"),
        ("version 2\n", None, "the first line must be 'version 1'"),
    ],
)
def test_a_broken_scenario_file_is_a_located_error(tmp_path: Path, scen: str, field: str | None, words: str) -> None:
    write_map(tmp_path, [".@..", "....", "..@."])
    (tmp_path / "grid.scen").write_text(scen)
    with pytest.raises(ScenarioFileError, match=re.escape(words)) as caught:
        load_entry(tmp_path, "    scen: grid.scen\n    map: grid.map\n")
    location = caught.value.location
    assert location is not None and location.line is not None and location.field == field


def test_more_agents_than_the_file_has_is_an_error_at_the_suite_key(tmp_path: Path) -> None:
    write_map(tmp_path, GRID)
    write_scen(tmp_path, [(0, 0, 0, 2)])
    with pytest.raises(ScenarioFileError, match=re.escape("agents=3, but grid.scen has 1 agent")) as caught:
        load_entry(tmp_path, "    scen: grid.scen\n    agents: 3\n")
    assert caught.value.location is not None and str(caught.value.location.path).endswith("grid.fleetsim.yaml")


def test_a_map_the_scenario_file_names_must_be_beside_it(tmp_path: Path) -> None:
    write_scen(tmp_path, [(0, 0, 0, 2)], map_name="maps/missing.map")
    with pytest.raises(LoadError, match=re.escape("map 'maps/missing.map' is not beside the scenario file")):
        load_entry(tmp_path, "    scen: grid.scen\n")


def test_a_scenario_file_needs_a_movingai_map(tmp_path: Path) -> None:
    write_scen(tmp_path, [(0, 0, 0, 2)])
    shipped = Path(__file__).resolve().parents[2] / "scenario_suites" / "sites" / "clinic" / "map.building.yaml"
    (tmp_path / "map.building.yaml").write_text(shipped.read_text())
    with pytest.raises(ScenarioFileError, match="runs on a MovingAI grid map"):
        load_entry(tmp_path, "    scen: grid.scen\n    map: map.building.yaml\n")


def test_a_scenario_entry_takes_no_vehicles_or_tasks(tmp_path: Path) -> None:
    write_map(tmp_path, GRID)
    write_scen(tmp_path, [(0, 0, 0, 2)])
    with pytest.raises(LoadError, match="scenarios\\[0\\]"):
        load_suite(write_suite(tmp_path, "    scen: grid.scen\n    tasks: tasks.csv\n"))


def test_neighbouring_starts_are_a_start_conflict_at_the_scenario_row(tmp_path: Path) -> None:
    write_map(tmp_path, GRID)
    write_scen(tmp_path, [(0, 0, 0, 2), (0, 1, 1, 0)])
    with pytest.raises(ScenarioFileError, match="start on conflicting segments") as caught:
        load_entry(tmp_path, "    scen: grid.scen\n")
    assert caught.value.location is not None and caught.value.location.line == 3
