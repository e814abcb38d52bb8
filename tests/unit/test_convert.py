"""``fleetsim convert``: maps written as LIF 1.0 and as Tiled, and round trips that keep the layout."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from jsonschema import Draft7Validator
from site_documents import layout_of, same_layout

from fleetsim.cli.main import main
from fleetsim.enums import Direction, Traverse
from fleetsim.layout.layout import Layout
from fleetsim.layout.segment import Segment
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.convert import convert_map
from fleetsim.load.maps.site_map import load_site_map

ROOT = Path(__file__).resolve().parents[2] / "scenario_suites"
HALL = ROOT / "sites" / "packing-hall" / "map.lif.json"
CLINIC = ROOT / "sites" / "clinic" / "map.building.yaml"
MIXED = ROOT / "examples" / "mixed" / "map.json"
TUG = MapOptions(robot_type="Acme.Tug")

# LIF 1.0's structure as its specification documents it (required members and their types), written
# for these tests: what a LIF 1.0 consumer may rely on.
_NUMBER = {"type": "number"}
_STRING = {"type": "string"}
LIF_1_0 = {
    "type": "object",
    "required": ["metaInformation", "layouts"],
    "properties": {
        "metaInformation": {
            "type": "object",
            "required": ["projectIdentification", "creator", "exportTimestamp", "lifVersion"],
            "properties": dict.fromkeys(("projectIdentification", "creator", "exportTimestamp", "lifVersion"), _STRING),
        },
        "layouts": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["layoutId", "layoutVersion", "nodes", "edges", "stations"],
                "properties": {
                    "layoutId": _STRING,
                    "layoutVersion": _STRING,
                    "nodes": {
                        "type": "array",
                        "items": {
                            "type": "object",
                            "required": ["nodeId", "nodePosition", "vehicleTypeNodeProperties"],
                            "properties": {
                                "nodeId": _STRING,
                                "nodePosition": {
                                    "type": "object",
                                    "required": ["x", "y"],
                                    "properties": {"x": _NUMBER, "y": _NUMBER},
                                },
                                "vehicleTypeNodeProperties": {
                                    "type": "array",
                                    "minItems": 1,
                                    "items": {
                                        "type": "object",
                                        "required": ["vehicleTypeId"],
                                        "properties": {"vehicleTypeId": _STRING},
                                    },
                                },
                            },
                        },
                    },
                    "edges": {
                        "type": "array",
                        "items": {
                            "type": "object",
                            "required": ["edgeId", "startNodeId", "endNodeId", "vehicleTypeEdgeProperties"],
                            "properties": {
                                "edgeId": _STRING,
                                "startNodeId": _STRING,
                                "endNodeId": _STRING,
                                "vehicleTypeEdgeProperties": {
                                    "type": "array",
                                    "minItems": 1,
                                    "items": {
                                        "type": "object",
                                        "required": ["vehicleTypeId", "rotationAllowed"],
                                        "properties": {
                                            "vehicleTypeId": _STRING,
                                            "rotationAllowed": {"type": "boolean"},
                                            "trajectory": {
                                                "type": "object",
                                                "required": ["knotVector", "controlPoints"],
                                                "properties": {
                                                    "degree": {"type": "number", "minimum": 1},
                                                    "knotVector": {
                                                        "type": "array",
                                                        "items": {"type": "number", "minimum": 0, "maximum": 1},
                                                    },
                                                    "controlPoints": {
                                                        "type": "array",
                                                        "items": {
                                                            "type": "object",
                                                            "required": ["x", "y"],
                                                            "properties": {
                                                                "x": _NUMBER,
                                                                "y": _NUMBER,
                                                                "weight": {"type": "number", "minimum": 1.0},
                                                            },
                                                        },
                                                    },
                                                },
                                            },
                                        },
                                    },
                                },
                            },
                        },
                    },
                    "stations": {"type": "array"},
                },
            },
        },
    },
}


def assert_valid_lif_1_0(document: Any) -> None:
    errors = sorted(Draft7Validator(LIF_1_0).iter_errors(document), key=str)
    assert not errors, errors[0]
    layout = document["layouts"][0]
    node_ids = [n["nodeId"] for n in layout["nodes"]]
    edge_ids = [e["edgeId"] for e in layout["edges"]]
    assert len(set(node_ids)) == len(node_ids) and len(set(edge_ids)) == len(edge_ids)
    assert {e["startNodeId"] for e in layout["edges"]} | {e["endNodeId"] for e in layout["edges"]} <= set(node_ids)
    for e in layout["edges"]:
        for prop in e["vehicleTypeEdgeProperties"]:
            if "trajectory" in prop:
                t = prop["trajectory"]
                assert len(t["knotVector"]) == len(t["controlPoints"]) + t["degree"] + 1


def test_a_lif_site_converted_to_lif_and_back_has_the_same_layout(tmp_path: Path) -> None:
    first = load_site_map(HALL, TUG)
    _, written = convert_map(HALL, tmp_path / "again.lif.json", TUG)
    second = load_site_map(written, MapOptions(robot_type="Acme.Tug"))
    assert [s.names for s in second.segments] == [s.names for s in first.segments]  # edge ids survive
    same_layout(layout_of(first), layout_of(second))
    assert_valid_lif_1_0(json.loads(written.read_text()))


def test_the_lif_writer_makes_one_edge_per_allowed_direction_and_shares_nodes(tmp_path: Path) -> None:
    _, written = convert_map(HALL, tmp_path / "out.lif.json", TUG)
    document = json.loads(written.read_text())
    edges = document["layouts"][0]["edges"]
    assert len(edges) == 15  # 13 segments, two of them two-way
    assert len(document["layouts"][0]["nodes"]) == 12  # the hall's 12 nodes, shared by the edges meeting there
    assert document["metaInformation"]["lifVersion"] == "1.0.0"
    assert {p["vehicleTypeId"] for e in edges for p in e["vehicleTypeEdgeProperties"]} == {"Acme.Tug"}


def canonical(layout: Layout) -> tuple[Any, ...]:
    """The layout in driving terms: every one-way segment written forward (LIF has no backward edges)."""
    flipped = {sid for sid, s in layout.segments.items() if s.direction is Direction.BACKWARD}

    def way(sid: int, traverse: Traverse) -> str:
        return traverse.reversed.value if sid in flipped else traverse.value

    segments = []
    for sid, s in layout.segments.items():
        points = s.waypoints[::-1] if sid in flipped else s.waypoints
        direction = Direction.FORWARD if sid in flipped else s.direction
        segments.append((sid, direction, tuple((round(x, 6), round(y, 6)) for x, y in points)))
    connections = sorted(
        (
            c.from_segment,
            way(c.from_segment, c.from_traverse),
            c.to_segment,
            way(c.to_segment, c.to_traverse),
            c.joint.value,
        )
        for c in layout.connections
    )
    return tuple(segments), tuple(connections), tuple((sid, layout.conflicts(sid)) for sid in layout.segments)


@pytest.mark.parametrize("target", ["out.json", "out.tmx"])
def test_a_tiled_map_converted_to_lif_and_back_to_tiled_has_the_same_layout(tmp_path: Path, target: str) -> None:
    original = load_site_map(MIXED)
    _, lif = convert_map(MIXED, tmp_path / "mixed.lif.json")
    assert_valid_lif_1_0(json.loads(lif.read_text()))
    _, tiled = convert_map(lif, tmp_path / target)
    again = load_site_map(tiled)
    assert again.format == "tiled"
    assert canonical(layout_of(original)) == canonical(layout_of(again))
    # Unnamed segments get edge ids E<id> (E<id>-back against their waypoints), which come back as names.
    assert [seg.names for seg in again.segments] == [
        (f"E{seg.id}", f"E{seg.id}-back") if seg.direction is Direction.BOTH else (f"E{seg.id}",)
        for seg in original.segments
    ]


def test_an_rmf_building_converted_to_tiled_keeps_its_layout_and_lane_names(tmp_path: Path) -> None:
    site = load_site_map(CLINIC)
    _, written = convert_map(CLINIC, tmp_path / "clinic.json")
    again = load_site_map(written)
    same_layout(layout_of(site), layout_of(again))
    assert [s.name for s in again.segments] == [s.name for s in site.segments]


def test_the_convert_command_says_what_it_wrote(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "hall.json"
    assert main(["convert", str(HALL), str(out), "--robot-type", "Acme.Tug"]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[-1] == f"wrote {out} (13 segments from {HALL} (layout 'hall-ground', robot type 'Acme.Tug'))"
    assert any("warning not-modelled: edge property attribute 'maxSpeed'" in line for line in printed)
    # The LIF stations come along as station properties (a Tiled station has no name of its own).
    written = {name: [s.segment for s in members] for name, members in load_site_map(out).stations.items()}
    assert written == {"dock-north": [12, 13], "dock-south": [11], "stations": [11, 12, 13]}


def test_the_convert_command_refuses_an_output_it_cannot_write(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["convert", str(HALL), str(tmp_path / "hall.svg"), "--robot-type", "Acme.Tug"]) == 1
    assert (
        "the output must end in .lif.json (LIF 1.0) or .json, .tmj, .tmx (Tiled), not '.svg'" in capsys.readouterr().err
    )


def test_inspect_lists_id_name_length_direction_and_ends(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["inspect", str(CLINIC), "--level", "L1"]) == 0
    lines = capsys.readouterr().out.splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("  id  name"))
    assert lines[header].split() == ["id", "name", "shape", "direction", "length", "from", "->", "to", "(points)"]
    assert lines[header + 6].split()[:7] == [
        "6",
        "ward_a--ward_b",
        "straight",
        "forward",
        "10.000",
        "(15.000,",
        "-15.000)",
    ]


def test_inspect_json_carries_each_segments_names(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["inspect", str(HALL), "--robot-type", "Acme.Tug", "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["format"] == "lif" and document["part"] == "layout 'hall-ground', robot type 'Acme.Tug'"
    assert document["segments"][10]["names"] == ["P-Q", "Q-P"] and document["segments"][10]["direction"] == "both"


def test_a_tiled_map_given_lif_options_notes_that_they_do_not_apply(tmp_path: Path) -> None:
    site = load_site_map(MIXED, MapOptions(layout="x"))
    assert site.warnings[-1].endswith(
        "warning option-ignored: map option 'layout' (for LIF and RMF maps) (once, first at "
        "map_options); it does not apply to this map"
    )
    assert not any("option-ignored" in w for w in load_site_map(MIXED).warnings)


def test_segments_keep_their_names_through_a_tiled_file(tmp_path: Path) -> None:
    from fleetsim.load.tiled.writer import write_map

    segment = Segment(
        3, load_site_map(MIXED).segments[0].shape, Direction.BOTH, ((0.0, 0.0), (2.0, 0.0)), ('a "quoted" name',)
    )
    for suffix in (".json", ".tmx"):
        assert load_site_map(write_map(tmp_path / f"m{suffix}", [segment])).segments[0].names == ('a "quoted" name',)


def test_naming_the_lif_written_from_a_tiled_map_is_not_an_ignored_option(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tiled = tmp_path / "hall.json"
    convert_map(HALL, tiled, TUG)
    out = tmp_path / "hall.lif.json"
    assert main(["convert", str(tiled), str(out), "--robot-type", "Acme.Tug", "--layout", "ground"]) == 0
    assert "option-ignored" not in capsys.readouterr().out
    document = json.loads(out.read_text(encoding="utf-8"))
    assert document["layouts"][0]["layoutId"] == "ground"
    assert load_site_map(out, MapOptions(robot_type="Acme.Tug")).format == "lif"
    # Read from a Tiled map into another Tiled map, the options still do not apply, and say so.
    assert main(["convert", str(tiled), str(tmp_path / "again.json"), "--robot-type", "Acme.Tug"]) == 0
    assert "warning option-ignored: map option 'robot_type'" in capsys.readouterr().out
