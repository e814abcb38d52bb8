"""Station sets from maps (issue 45): Tiled ``station`` properties, LIF stations, Open-RMF station vertices;
how ``fleetsim inspect`` shows them and ``fleetsim convert`` keeps them."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from site_documents import edge, layout, lif_v1, load, node, save_yaml, to_v2

from fleetsim.cli.main import main
from fleetsim.enums import Direction, Shape
from fleetsim.errors import LoadErrors, MapError
from fleetsim.layout.segment import Segment
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.maps.convert import convert_map
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.load.tiled.writer import write_map
from fleetsim.orders import Station

ROW = (
    Segment(1, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (4.0, 0.0))),
    Segment(2, Shape.STRAIGHT, Direction.BOTH, ((4.0, 0.0), (8.0, 0.0))),
    Segment(3, Shape.STRAIGHT, Direction.FORWARD, ((8.0, 0.0), (12.0, 0.0))),
)


def segments_of(site: SiteMap) -> dict[str, list[tuple[int, float, str]]]:
    return {name: [(s.segment, s.weight, s.name) for s in members] for name, members in site.stations.items()}


# -- Tiled ------------------------------------------------------------------------------------------


def tiled_object(object_id: int, x: float, properties: list[dict[str, object]], **keys: object) -> dict[str, object]:
    obj: dict[str, object] = {
        "id": object_id,
        "type": "straight",
        "x": x,
        "y": 160,
        "polyline": [{"x": 0, "y": 0}, {"x": 32, "y": 0}],
        "properties": properties,
    }
    obj.update(keys)
    return obj


def tiled_json(tmp_path: Path, *objects: dict[str, object]) -> Path:
    document = {
        "type": "map",
        "orientation": "orthogonal",
        "width": 20,
        "height": 10,
        "tilewidth": 32,
        "tileheight": 32,
        "infinite": False,
        "layers": [{"type": "objectgroup", "name": "segments", "objects": list(objects)}],
    }
    path = tmp_path / "map.json"
    path.write_text(json.dumps(document), encoding="utf-8")
    return path


def station(value: object, kind: str = "string") -> dict[str, object]:
    return {"name": "station", "type": kind, "value": value}


def weight(value: object) -> dict[str, object]:
    return {"name": "station_weight", "type": "float", "value": value}


@pytest.mark.parametrize("suffix", ["json", "tmx"])
def test_a_tiled_map_written_with_stations_reads_them_back_in_either_format(tmp_path: Path, suffix: str) -> None:
    sets = {"pick": [Station(3), Station(1, 2.5)], "drop": [Station(2)], "park": [Station(1, 2.5)]}
    path = write_map(tmp_path / f"map.{suffix}", ROW, stations=sets)
    assert segments_of(load_site_map(path)) == {
        "drop": [(2, 1.0, "")],
        "park": [(1, 2.5, "")],
        "pick": [(1, 2.5, ""), (3, 1.0, "")],  # ascending by segment, whatever order they were given in
    }


def test_the_writer_refuses_a_segment_of_two_weights_and_a_station_off_the_map(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"segment 1 weighs 2\.0 in station set 'a' and 1\.0 in 'b'"):
        write_map(tmp_path / "map.json", ROW, stations={"a": [Station(1, 2.0)], "b": [Station(1)]})
    with pytest.raises(ValueError, match="station set 'a' names segment 9"):
        write_map(tmp_path / "map.json", ROW, stations={"a": [Station(9)]})


def test_a_station_property_names_one_or_more_sets_and_an_empty_one_none(tmp_path: Path) -> None:
    path = tiled_json(
        tmp_path,
        tiled_object(1, 0, [station(" drop , park,drop ")]),
        tiled_object(2, 32, [station("pick"), weight(3)]),
        tiled_object(3, 64, [station(" ")]),  # a template's empty default, say: no station
        tiled_object(4, 96, []),
    )
    assert segments_of(load_site_map(path)) == {"drop": [(1, 1.0, "")], "park": [(1, 1.0, "")], "pick": [(2, 3.0, "")]}


def test_a_template_makes_its_instances_stations_unless_an_instance_says_otherwise(tmp_path: Path) -> None:
    template = {
        "type": "template",
        "object": {
            "type": "straight",
            "polyline": [{"x": 0, "y": 0}, {"x": 32, "y": 0}],
            "properties": [station("dock"), weight(2)],
        },
    }
    (tmp_path / "dock.tj").write_text(json.dumps(template), encoding="utf-8")
    path = tiled_json(
        tmp_path,
        {"id": 1, "template": "dock.tj", "x": 0, "y": 160},
        {"id": 2, "template": "dock.tj", "x": 32, "y": 160, "properties": [weight(5)]},
        {"id": 3, "template": "dock.tj", "x": 64, "y": 160, "properties": [station("")]},
    )
    assert segments_of(load_site_map(path)) == {"dock": [(1, 2.0, ""), (2, 5.0, "")]}


@pytest.mark.parametrize(
    ("properties", "message"),
    [
        ([station(3, "int")], "the station property is 3; it must be a string of station set names"),
        ([station("pick up")], "'pick up' is not a station set name"),
        ([station("pick;drop")], "'pick;drop' is not a station set name"),
        ([station("pick"), weight(0)], "the station_weight property is 0.0; it must be a number > 0"),
        ([station("pick"), weight(-1.5)], "the station_weight property is -1.5; it must be a number > 0"),
        ([station("pick"), {"name": "station_weight", "type": "bool", "value": True}], "it must be a number"),
    ],
)
def test_a_bad_station_property_is_an_error_naming_the_object(
    tmp_path: Path, properties: list[dict[str, object]], message: str
) -> None:
    path = tiled_json(tmp_path, tiled_object(1, 0, []), tiled_object(7, 32, properties))
    with pytest.raises(MapError, match=message) as info:
        load_site_map(path)
    assert info.value.location is not None and info.value.location.object_id == 7


def test_the_station_properties_of_several_objects_are_reported_together(tmp_path: Path) -> None:
    path = tiled_json(tmp_path, tiled_object(1, 0, [station("a b")]), tiled_object(2, 32, [station("x"), weight(0)]))
    with pytest.raises(LoadErrors) as info:
        load_site_map(path)
    assert [error.location.object_id for error in info.value.errors if error.location] == [1, 2]


def test_a_station_weight_that_is_narrowly_positive_is_accepted(tmp_path: Path) -> None:
    path = tiled_json(tmp_path, tiled_object(1, 0, [station("pick"), weight(0.001)]))
    assert segments_of(load_site_map(path)) == {"pick": [(1, 0.001, "")]}


def test_a_station_property_on_an_object_that_is_no_segment_is_a_warning(tmp_path: Path) -> None:
    point = {"id": 5, "x": 10, "y": 10, "point": True, "properties": [station("pick")]}
    drawing_aid = tiled_object(6, 64, [station("drop")], type="")
    site = load_site_map(tiled_json(tmp_path, tiled_object(1, 0, []), point, drawing_aid))
    assert site.stations == {}
    assert [w.split(": a station property", 1)[1] for w in site.warnings] == [
        " ('pick') on a point, which is not a segment; ignored (stations are segments: polylines of class "
        "straight, curve, s_curve or path)",
        " ('drop') on a polyline without a class, which is not a segment; ignored (stations are segments: "
        "polylines of class straight, curve, s_curve or path)",
    ]
    assert "object 5" in site.warnings[0] and "object 6" in site.warnings[1]


# -- LIF ---------------------------------------------------------------------------------------------

# A-B one-way, B-C two-way (its two edges), C-D one-way: station "load" at B and D, "unload" at A.
LIF = lif_v1(
    layout(
        "hall",
        [node("A", 0, 0), node("B", 5, 0), node("C", 10, 0), node("D", 15, 0), node("E", 20, 0)],
        [edge("A-B", "A", "B"), edge("B-C", "B", "C"), edge("C-B", "C", "B"), edge("C-D", "C", "D")],
        stations=[
            {"stationId": "load", "interactionNodeIds": ["B", "D"], "stationName": "Load", "stationHeight": 0.5},
            {"stationId": "unload", "interactionNodeIds": ["A"]},
            {"stationId": "far", "interactionNodeIds": ["E"]},
        ],
    )
)


@pytest.mark.parametrize("version", ["1.0", "2.0"])
def test_lif_stations_are_the_set_stations_and_a_set_each_at_the_segments_ending_at_their_nodes(
    tmp_path: Path, version: str
) -> None:
    document = LIF if version == "1.0" else to_v2(LIF)
    options = {} if version == "1.0" else {"robot_type": "T/T"}
    site = load(tmp_path, document, **options)
    assert [(s.id, s.names, s.direction) for s in site.segments] == [
        (1, ("A-B",), Direction.FORWARD),
        (2, ("B-C", "C-B"), Direction.BOTH),
        (3, ("C-D",), Direction.FORWARD),
    ]
    # B: the one-way A-B ends there, and the two-way B-C may be driven back to it; nothing ends at A
    # (A-B leaves it), D is the end of C-D; E is on no edge (noted).
    assert segments_of(site) == {
        "load": [(1, 1.0, "load"), (2, 1.0, "load"), (3, 1.0, "load")],
        "stations": [(1, 1.0, "load"), (2, 1.0, "load"), (3, 1.0, "load")],
    }
    notes = [w for w in site.warnings if "station" in w]
    assert len(notes) == 1
    assert "a station no usable edge ends at (2 times, first at " in notes[0]
    assert "/layouts/0/stations/1 ('unload'))" in notes[0]


def test_a_lif_station_at_a_node_the_layout_lacks_or_an_id_used_twice_is_an_error(tmp_path: Path) -> None:
    document = lif_v1(
        layout(
            "hall",
            [node("A", 0, 0), node("B", 5, 0)],
            [edge("A-B", "A", "B")],
            stations=[
                {"stationId": "s", "interactionNodeIds": ["Bx"]},
                {"stationId": "t", "interactionNodeIds": ["B"]},
                {"stationId": "t", "interactionNodeIds": ["B"]},
                {"stationId": "u", "interactionNodeIds": []},
            ],
        )
    )
    with pytest.raises(LoadErrors) as info:
        load(tmp_path, document)
    assert [str(error).split(": ", 1)[1] for error in info.value.errors] == [
        "field '/layouts/0/stations/0/interactionNodeIds/0': station 's': node 'Bx' is not a node of this "
        "layout; did you mean 'B'?",
        "field '/layouts/0/stations/2/stationId': stationId 't' is used twice: by /layouts/0/stations/1 too",
        "field '/layouts/0/stations/3/interactionNodeIds': must not be empty",
    ]


def test_a_lif_layout_without_stations_has_no_station_sets(tmp_path: Path) -> None:
    site = load(tmp_path, lif_v1(layout("hall", [node("A", 0, 0), node("B", 5, 0)], [edge("A-B", "A", "B")])))
    assert site.stations == {}


# -- Open-RMF -------------------------------------------------------------------------------------

BUILDING = """\
coordinate_system: cartesian_meters
levels:
  L1:
    vertices:
      - [0, 0, 0, shelf, {pickup_dispenser: [1, shelf_disp]}]
      - [5, 0, 0, hub]
      - [10, 0, 0, bench, {dropoff_ingestor: [1, bench_ing], is_parking_spot: [4, true]}]
      - [5, 5, 0, dock, {is_charger: [4, true], is_parking_spot: [4, false], pickup_dispenser: [1, ""]}]
      - [5, -5, 0, lonely, {is_charger: [4, true]}]
    lanes:
      - [1, 0, {bidirectional: [4, true]}]
      - [1, 2, {bidirectional: [4, false]}]
      - [3, 1, {bidirectional: [4, false]}]
      - [1, 3, {bidirectional: [4, false]}]
"""


def test_rmf_station_vertices_give_pick_drop_park_and_charge_at_the_lanes_ending_there(tmp_path: Path) -> None:
    site = load_site_map(save_yaml(tmp_path, BUILDING), MapOptions())
    assert [(s.id, s.names) for s in site.segments] == [
        (1, ("hub--shelf", "shelf--hub")),
        (2, ("hub--bench",)),
        (3, ("dock--hub",)),
        (4, ("hub--dock",)),
    ]
    # shelf: the two-way lane 1 ends there (driven from hub); bench: lane 2; dock: lane 4 (lane 3 leaves
    # it). An empty dispenser name and is_parking_spot: false mark nothing.
    assert segments_of(site) == {
        "charge": [(4, 1.0, "dock")],
        "drop": [(2, 1.0, "bench")],
        "park": [(2, 1.0, "bench")],
        "pick": [(1, 1.0, "shelf")],
    }
    notes = [w for w in site.warnings if "station" in w or "vertex parameter" in w]
    assert (
        len(notes) == 1
        and "a station vertex no lane of the graph ends at (once, first at line 9 ('lonely'))" in notes[0]
    )


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ("{is_charger: [1, 'yes']}", "vertex 0 is_charger is 'yes'; it must be true or false"),
        (
            "{pickup_dispenser: [4, true]}",
            "vertex 0 pickup_dispenser is True; it must be a string (the name of the dispenser)",
        ),
        (
            "{dropoff_ingestor: [2, 3]}",
            "vertex 0 dropoff_ingestor is 3; it must be a string (the name of the ingestor)",
        ),
    ],
)
def test_a_station_parameter_of_the_wrong_type_is_an_error_at_its_line(
    tmp_path: Path, params: str, message: str
) -> None:
    text = BUILDING.replace("{pickup_dispenser: [1, shelf_disp]}", params)
    with pytest.raises(MapError) as info:
        load_site_map(save_yaml(tmp_path, text), MapOptions())
    assert str(info.value).endswith(message)
    assert info.value.location is not None and info.value.location.line == 5


# -- commands -------------------------------------------------------------------------------------


def test_inspect_lists_the_station_sets_as_text_and_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write_map(tmp_path / "map.json", ROW, stations={"pick": [Station(3), Station(1, 2.5)]})
    assert main(["inspect", str(path)]) == 0
    text = capsys.readouterr().out
    assert "\nstation sets\n  pick: 1 (weight 2.5), 3\n\nconnections\n" in text
    assert main(["inspect", str(path), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["stations"] == {
        "pick": [{"segment": 1, "weight": 2.5, "name": ""}, {"segment": 3, "weight": 1.0, "name": ""}]
    }


def test_inspect_of_a_map_without_stations_prints_no_station_section(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["inspect", str(write_map(tmp_path / "map.json", ROW))]) == 0
    assert "station sets" not in capsys.readouterr().out


def test_convert_writes_an_rmf_maps_stations_into_the_tiled_map(tmp_path: Path) -> None:
    source = save_yaml(tmp_path, BUILDING)
    site, written = convert_map(source, tmp_path / "site.tmx")
    again = load_site_map(written)
    assert {k: [s.segment for s in v] for k, v in again.stations.items()} == {
        k: [s.segment for s in v] for k, v in site.stations.items()
    }
