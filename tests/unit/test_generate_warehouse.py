"""``fleetsim generate warehouse``: the files it writes, the layout's soundness, and every bad option."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from fleetsim.cli.main import main
from fleetsim.enums import Direction, Progress, Shape, Traverse, TurnCapability
from fleetsim.generate import GenerateError, WarehouseOptions, generate_warehouse
from fleetsim.generate.warehouse_layout import sizes_for, warehouse_layout
from fleetsim.layout.layout import Layout
from fleetsim.layout.reachability import reach
from fleetsim.layout.segment import Segment
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.lif.writer import lif_document
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.load.suites.scenario import load_scenario, load_scenario_dir
from fleetsim.load.suites.suite import load_suite
from fleetsim.orders import Station
from fleetsim.scenario import Scenario, VehicleType

FILES = ("map.json", "vehicles.csv", "tasks.csv", "warehouse.fleetsim.yaml")


def _agv(length: float = 1.0, width: float = 0.6) -> dict[str, VehicleType]:
    return {"agv": VehicleType("agv", length, width, 0.4, 1.0, 0.5, TurnCapability.IN_PLACE)}


def _scenario(folder: Path, options: WarehouseOptions | None = None) -> Scenario:
    options = options or WarehouseOptions()
    return load_scenario_dir(folder, vehicle_types=_agv(options.vehicle_length, options.vehicle_width))


def _station_ids(scenario: Scenario, name: str) -> list[int]:
    return [station.segment for station in scenario.stations[name]] if scenario.stations else []


def test_the_default_site_is_a_folder_of_four_files(tmp_path: Path) -> None:
    written = generate_warehouse(tmp_path / "site")
    assert sorted(p.name for p in written.folder.iterdir()) == sorted(FILES)
    assert (written.map, written.vehicles, written.tasks, written.suite) == tuple(
        tmp_path / "site" / name for name in FILES
    )
    counts = {name: len(stations) for name, stations in written.layout.stations.items()}
    assert counts == {"drop": 4, "park": 8, "pick": 12}


@pytest.mark.parametrize("map_format", ["tiled", "lif"])
def test_the_same_options_give_byte_identical_files(tmp_path: Path, map_format: str) -> None:
    options = WarehouseOptions(aisles=5, vehicles=6, parking=9, map_format=map_format)  # type: ignore[arg-type]
    first = generate_warehouse(tmp_path / "a", options)
    second = generate_warehouse(tmp_path / "b", options)
    names = sorted(p.name for p in first.folder.iterdir())
    assert names == sorted(p.name for p in second.folder.iterdir())
    for name in names:
        assert (first.folder / name).read_bytes() == (second.folder / name).read_bytes(), name


def test_the_map_is_in_metres_and_names_its_stations(tmp_path: Path) -> None:
    written = generate_warehouse(tmp_path / "site")
    site = load_site_map(written.map, MapOptions())
    assert site.meters_per_pixel == 1 / 32
    assert sorted(site.stations) == ["drop", "park", "pick"]
    assert dict(site.stations) == dict(written.layout.stations)
    by_id = {segment.id: segment for segment in site.segments}
    assert [by_id[s.segment].name for s in site.stations["pick"]] == [f"pick-{n}" for n in range(1, 13)]
    sizes = sizes_for(1.0, 0.6)
    for station in (*site.stations["pick"], *site.stations["drop"], *site.stations["park"]):
        assert by_id[station.segment].length == pytest.approx(sizes.station)
        assert by_id[station.segment].direction is Direction.FORWARD  # a drive-through place, one way


@pytest.mark.parametrize("one_way", [True, False], ids=["one-way", "two-way"])
def test_the_folder_loads_with_every_vehicle_parked_and_no_lint(tmp_path: Path, one_way: bool) -> None:
    written = generate_warehouse(tmp_path / "site", WarehouseOptions(one_way=one_way))
    scenario = _scenario(written.folder)
    assert [v.start_segment for v in scenario.vehicles] == list(written.layout.parking)
    assert scenario.tasks == ()
    assert scenario.layout.lint(scenario.vehicle_length) == ()


def _reachable(layout: Layout, segment: int) -> frozenset[int]:
    starts = [
        (segment, traverse, progress)
        for traverse in Traverse
        if layout.segments[segment].allows(traverse)
        for progress in Progress
    ]
    return reach(layout, TurnCapability.IN_PLACE, starts).segments


@pytest.mark.parametrize("one_way", [True, False], ids=["one-way", "two-way"])
def test_every_pick_reaches_every_drop_and_every_drop_every_parking_place(tmp_path: Path, one_way: bool) -> None:
    written = generate_warehouse(tmp_path / "site", WarehouseOptions(one_way=one_way, parking=10))
    scenario = _scenario(written.folder)
    picks, drops, parks = (_station_ids(scenario, name) for name in ("pick", "drop", "park"))
    for pick in picks:
        assert set(drops) <= _reachable(scenario.layout, pick)
    for drop in drops:
        assert set(parks) <= _reachable(scenario.layout, drop)
    for park in parks:
        assert set(picks) <= _reachable(scenario.layout, park)


@pytest.mark.parametrize(("length", "width"), [(1.0, 0.6), (2.0, 1.2)])
def test_a_vehicle_on_a_station_blocks_only_the_station_s_own_connectors(
    tmp_path: Path, length: float, width: float
) -> None:
    options = WarehouseOptions(vehicle_length=length, vehicle_width=width, aisle_length=40, aisle_spacing=8)
    scenario = _scenario(generate_warehouse(tmp_path / "site", options).folder, options)
    segments = scenario.layout.segments
    for name in ("pick", "drop", "park"):
        for station in _station_ids(scenario, name):
            others = scenario.layout.conflicts(station) - {station}
            assert len(others) == 2, (name, station)  # the connectors it joins: nothing else is near it
            ends = {segments[station].first, segments[station].last}
            assert all({segments[o].first, segments[o].last} & ends for o in others)


def test_aisles_at_the_least_spacing_do_not_conflict_with_the_next_aisle_s_pick_stations(tmp_path: Path) -> None:
    least = 2 * sizes_for(1.0, 0.6).clearance
    scenario = _scenario(generate_warehouse(tmp_path / "site", WarehouseOptions(aisle_spacing=least)).folder)
    for station in _station_ids(scenario, "pick"):
        assert len(scenario.layout.conflicts(station)) == 3
    with pytest.raises(GenerateError, match=r"aisle_spacing=2\.99 must be at least 3 m for vehicles of 1 x 0\.6 m"):
        warehouse_layout(WarehouseOptions(aisle_spacing=2.99))


def test_parking_that_does_not_fit_one_row_continues_on_a_second(tmp_path: Path) -> None:
    options = WarehouseOptions(vehicles=30)  # 6 aisles hold 14 places along the bottom cross aisle
    written = generate_warehouse(tmp_path / "site", options)
    scenario = _scenario(written.folder)  # start conflicts would be a load error
    assert len(scenario.vehicles) == 30
    assert scenario.layout.lint(scenario.vehicle_length) == ()
    parks = _station_ids(scenario, "park")
    depths = sorted({round(scenario.layout.segments[p].first[1], 6) for p in parks})
    assert len(depths) == 3  # three rows, one below the other
    picks = set(_station_ids(scenario, "pick"))
    for park in parks:
        assert picks <= _reachable(scenario.layout, park)


def test_a_lif_site_has_the_tiled_site_s_segments_and_station_sets(tmp_path: Path) -> None:
    tiled = _scenario(generate_warehouse(tmp_path / "tiled").folder)
    lif_folder = generate_warehouse(tmp_path / "lif", WarehouseOptions(map_format="lif")).folder
    assert sorted(p.name for p in lif_folder.iterdir()) == sorted(["map.lif.json", *FILES[1:]])
    lif = _scenario(lif_folder)
    assert [(s.id, s.direction, s.waypoints) for s in tiled.layout.segments.values()] == [
        (s.id, s.direction, s.waypoints) for s in lif.layout.segments.values()
    ]
    for name in ("pick", "drop", "park"):
        assert _station_ids(lif, name) == _station_ids(tiled, name)
    assert json.loads((lif_folder / "map.lif.json").read_text())["metaInformation"]["exportTimestamp"] == (
        "2024-01-01T00:00:00.00Z"
    )


def test_the_lif_writer_writes_one_station_per_set_at_the_end_its_segments_are_driven_to() -> None:
    segments = [
        Segment(1, Shape.STRAIGHT, Direction.FORWARD, ((0.0, 0.0), (2.0, 0.0))),
        Segment(2, Shape.STRAIGHT, Direction.BACKWARD, ((2.0, 0.0), (4.0, 0.0))),
        Segment(3, Shape.STRAIGHT, Direction.BOTH, ((4.0, 0.0), (6.0, 0.0))),
    ]
    document = lif_document(segments, stations={"pick": [Station(1), Station(2)], "drop": [Station(3)]})
    stations = document["layouts"][0]["stations"]
    # Nodes: N1 (0,0), N2 (2,0), N3 (4,0), N4 (6,0); 1 ends at N2, 2 (driven backward) at N2, 3 at N4.
    assert stations == [
        {"stationId": "drop", "interactionNodeIds": ["N4"], "stationName": "drop"},
        {"stationId": "pick", "interactionNodeIds": ["N2"], "stationName": "pick"},
    ]
    with pytest.raises(ValueError, match="station set 'park' names segment 9, which is not among the segments"):
        lif_document(segments, stations={"park": [Station(9)]})


def test_the_suite_runs_the_folder_as_a_shift_of_pick_to_drop_orders(tmp_path: Path) -> None:
    written = generate_warehouse(tmp_path / "site", WarehouseOptions(seed=7))
    suite = load_suite(written.suite)
    (spec,) = suite.scenarios
    scenario = load_scenario(spec, suite)
    assert scenario.map_path == written.map
    assert scenario.shift is not None and scenario.shift.duration == 3600
    stream = scenario.order_stream
    assert stream is not None and stream.seed == 7
    assert (stream.arrivals.process, stream.arrivals.rate) == ("poisson", 60)
    assert [(draw.stations, draw.dwell) for draw in stream.stops] == [(("pick",), (20, 20)), (("drop",), (15, 15))]
    assert scenario.dispatcher == "fleetsim.dispatchers:NearestVehicleDispatcher"
    assert suite.vehicle_types["agv"].length == 1.0
    assert written.suite.read_text().startswith("# Generated by: fleetsim generate warehouse OUT_DIR --seed 7\n")


def test_no_dispatcher_leaves_the_suite_without_one(tmp_path: Path) -> None:
    written = generate_warehouse(tmp_path / "site", WarehouseOptions(dispatcher=None))
    text = written.suite.read_text()
    assert "dispatcher:" not in text
    assert text.startswith("# Generated by: fleetsim generate warehouse OUT_DIR --no-dispatcher\n")


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"aisles": 1}, "aisles=1 must be a whole number >= 2 (the outer two aisles close the loop)"),
        ({"vehicles": 0}, "vehicles=0 must be a whole number >= 1"),
        ({"pick_stations": 0}, "pick_stations=0 must be a whole number >= 1"),
        ({"drop_stations": 0}, "drop_stations=0 must be a whole number >= 1"),
        ({"vehicles": 9, "parking": 8}, "vehicles=9 must not exceed the 8 parking places"),
        ({"aisle_length": float("nan")}, "aisle_length=nan must be a number of metres > 0"),
        ({"vehicle_width": 0}, "vehicle_width=0 must be a number of metres > 0"),
        ({"seed": -1}, "seed=-1 must be a whole number >= 0"),
        ({"dispatcher": "nearest"}, "dispatcher='nearest' must be module:attribute"),
        ({"map_format": "tmx"}, "map_format='tmx' must be one of tiled, lif"),
    ],
)
def test_a_bad_option_is_refused_by_name_and_value(options: dict[str, object], message: str) -> None:
    with pytest.raises(GenerateError, match=message.replace("(", r"\(").replace(")", r"\)")):
        WarehouseOptions(**options)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    "options", [{"aisles": 2}, {"vehicles": 8, "parking": 8}, {"pick_stations": 1}, {"seed": 0}, {"map_format": "lif"}]
)
def test_the_least_good_options_are_accepted(options: dict[str, object]) -> None:
    WarehouseOptions(**options)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("options", "fits"),
    [
        # Two lay-bys on one aisle need 5 clearances and 2 station lengths: 5 x 1.5 + 2 x 1.5 = 10.5 m.
        ({"aisles": 2, "pick_stations": 4, "aisle_length": 10.5}, True),
        ({"aisles": 2, "pick_stations": 4, "aisle_length": 10.4}, False),
    ],
)
def test_pick_stations_must_fit_beside_their_aisles(options: dict[str, object], fits: bool) -> None:
    built = WarehouseOptions(**options, drop_stations=1, vehicles=1)  # type: ignore[arg-type]
    if fits:
        assert len(warehouse_layout(built).stations["pick"]) == 4
    else:
        with pytest.raises(
            GenerateError,
            match=r"pick_stations=4 puts 2 pick stations beside an aisle, which takes aisles of at least 10\.5 m",
        ):
            warehouse_layout(built)


@pytest.mark.parametrize(
    ("option", "count", "fits"),
    [("drop_stations", 1, True), ("drop_stations", 2, False), ("vehicles", 1, True), ("vehicles", 2, False)],
)
def test_the_dock_and_the_parking_must_fit_along_their_cross_aisle(option: str, count: int, fits: bool) -> None:
    # Two aisles 3 m apart: room for two rungs along each cross aisle, a station and the return rung.
    options = WarehouseOptions(aisles=2, aisle_spacing=3, pick_stations=1, drop_stations=1, vehicles=1)
    built = WarehouseOptions(**{**_fields(options), option: count})  # type: ignore[arg-type]
    if fits:
        warehouse_layout(built)
    else:
        places, where = ("drop stations", "top") if option == "drop_stations" else ("parking places", "bottom")
        with pytest.raises(
            GenerateError,
            match=rf"{option}=2 asks for 2 {places}, more than fit beyond the {where} cross aisle \(3 m long: 2 aisles 3 m apart\), even in rows",
        ):
            warehouse_layout(built)


def _fields(options: WarehouseOptions) -> dict[str, object]:
    return {name: getattr(options, name) for name in options.__dataclass_fields__}


def test_a_folder_with_files_is_refused_unless_forced(tmp_path: Path) -> None:
    folder = tmp_path / "site"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    with pytest.raises(GenerateError, match=r"out_dir='.*site' is not empty; force \(--force\) writes into it anyway"):
        generate_warehouse(folder)
    assert sorted(p.name for p in folder.iterdir()) == ["notes.txt"]
    (folder / "map.lif.json").write_text("{}")  # another map would make the folder ambiguous
    generate_warehouse(folder, force=True)
    assert sorted(p.name for p in folder.iterdir()) == sorted([*FILES, "notes.txt"])


def test_an_empty_folder_is_written_into_and_a_file_is_refused(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    generate_warehouse(tmp_path / "empty")
    (tmp_path / "file").write_text("")
    with pytest.raises(GenerateError, match=r"out_dir='.*file' is a file; give a folder"):
        generate_warehouse(tmp_path / "file")


def test_an_option_the_layout_refuses_writes_nothing(tmp_path: Path) -> None:
    with pytest.raises(GenerateError, match="pick_stations=60"):
        generate_warehouse(tmp_path / "site", WarehouseOptions(pick_stations=60))
    assert not (tmp_path / "site").exists()


def test_a_30_vehicle_site_generates_and_loads_in_well_under_a_few_seconds(tmp_path: Path) -> None:
    options = WarehouseOptions(aisles=12, aisle_length=30, vehicles=30, pick_stations=36, drop_stations=8)
    began = time.perf_counter()
    written = generate_warehouse(tmp_path / "site", options)
    scenario = _scenario(written.folder)
    elapsed = time.perf_counter() - began
    assert len(scenario.vehicles) == 30 and len(scenario.layout.segments) > 300
    assert elapsed < 3.0, f"{elapsed:.2f} s"


def test_the_command_writes_the_folder_and_says_how_to_run_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "site"
    assert main(["generate", "warehouse", str(folder), "--aisles", "4", "--vehicles", "3", "--two-way"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"wrote {folder}: map.json (")
    assert out[0].endswith(
        "12 pick and 4 drop stations, 3 parking places), vehicles.csv (3 vehicles), tasks.csv, warehouse.fleetsim.yaml"
    )
    assert (
        out[1]
        == f"run it: fleetsim run {folder / 'warehouse.fleetsim.yaml'} --planner fleetsim.planners:ReservingPlanner"
    )
    assert "--aisles 4 --vehicles 3 --two-way" in (folder / "warehouse.fleetsim.yaml").read_text()


@pytest.mark.parametrize(
    ("words", "message"),
    [
        (["--aisles", "0"], "--aisles 0: must be a whole number >= 2 (the outer two aisles close the loop)"),
        (["--vehicles", "12", "--parking", "10"], "--vehicles 12: must not exceed the 10 parking places"),
        (["--aisle-spacing", "2"], "--aisle-spacing 2.0: must be at least 3 m for vehicles of 1 x 0.6 m"),
    ],
)
def test_a_bad_option_on_the_command_line_is_a_one_line_usage_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], words: list[str], message: str
) -> None:
    assert main(["generate", "warehouse", str(tmp_path / "site"), *words]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"fleetsim: error: {message}")
    assert not (tmp_path / "site").exists()


def test_a_folder_in_the_way_on_the_command_line_is_a_usage_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["generate", "warehouse", str(tmp_path)]) == 0  # tmp_path is empty
    assert main(["generate", "warehouse", str(tmp_path)]) == 2
    assert capsys.readouterr().err.startswith(f"fleetsim: error: OUT_DIR {tmp_path}: is not empty; force (--force)")
    assert main(["generate", "warehouse", str(tmp_path), "--force", "--format", "lif"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["map.lif.json", *FILES[1:]])
