"""write_map writes Tiled 1.8 maps that load_map reads back to the same segments."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from fleetsim.enums import Direction, Shape
from fleetsim.errors import LayoutError
from fleetsim.layout.segment import Segment
from fleetsim.load.tiled.reader import load_map
from fleetsim.load.tiled.writer import write_map

ARC = tuple((3 + 2 * math.sin(math.radians(a)), -1 / 3 + 2 - 2 * math.cos(math.radians(a))) for a in range(0, 91, 10))
SEGMENTS = (
    Segment(4, Shape.STRAIGHT, Direction.BOTH, ((-7.25, 0.1), (3.0, -1 / 3))),
    Segment(2, Shape.CURVE, Direction.FORWARD, ARC),
    Segment(9, Shape.S_CURVE, Direction.BACKWARD, ((0.0, 0.0), (1.0, 0.05), (2.0, 0.5), (4.0, 1.0))),
)


def assert_same_segments(loaded: tuple[Segment, ...], expected: tuple[Segment, ...], tol: float) -> None:
    expected = tuple(sorted(expected, key=lambda segment: segment.id))
    assert [(s.id, s.shape, s.direction) for s in loaded] == [(s.id, s.shape, s.direction) for s in expected]
    for got, want in zip(loaded, expected, strict=True):
        assert len(got.waypoints) == len(want.waypoints)
        for (gx, gy), (wx, wy) in zip(got.waypoints, want.waypoints, strict=True):
            assert abs(gx - wx) <= tol and abs(gy - wy) <= tol, (got.id, got.waypoints, want.waypoints)


@pytest.mark.parametrize("suffix", [".json", ".tmj", ".tmx"])
def test_write_then_load_gives_back_the_same_segments(tmp_path: Path, suffix: str) -> None:
    path = write_map(tmp_path / ("map" + suffix), SEGMENTS)
    assert path == tmp_path / ("map" + suffix)
    assert_same_segments(load_map(path).segments, SEGMENTS, tol=1e-9)


@pytest.mark.parametrize("suffix", [".json", ".tmx"])
def test_meters_per_pixel_is_written_as_a_map_property_and_round_trips(tmp_path: Path, suffix: str) -> None:
    loaded = load_map(write_map(tmp_path / ("map" + suffix), SEGMENTS, tile_size=16, meters_per_pixel=0.01))
    assert loaded.meters_per_pixel == 0.01
    assert_same_segments(loaded.segments, SEGMENTS, tol=1e-9)


@pytest.mark.parametrize("suffix", [".json", ".tmx"])
def test_written_map_is_centred_on_the_world_origin_with_a_margin(tmp_path: Path, suffix: str) -> None:
    loaded = load_map(write_map(tmp_path / ("map" + suffix), SEGMENTS, margin_tiles=2))
    # Whole tiles on each side of the origin; the farthest point (x = -7.25 m) needs 8 tiles + 2.
    assert (loaded.width_px, loaded.height_px) == (2 * 10 * 32, 2 * 4 * 32)


def test_tmx_is_written_the_way_tiled_1_8_writes_it(tmp_path: Path) -> None:
    root = ET.parse(write_map(tmp_path / "map.tmx", SEGMENTS)).getroot()
    assert (root.get("version"), root.get("orientation"), root.get("infinite")) == ("1.8", "orthogonal", "0")
    assert (root.get("nextobjectid"), root.get("nextlayerid")) == ("10", "2")
    obj = root.find("objectgroup/object[@id='9']")
    assert obj is not None and obj.get("type") == "s_curve" and obj.get("class") is None
    (prop,) = obj.findall("properties/property")
    assert prop.attrib == {"name": "direction", "propertytype": "direction", "value": "backward"}
    polyline = obj.find("polyline")
    assert polyline is not None and polyline.get("points", "").startswith("0,0 ")


def test_json_is_written_the_way_tiled_1_8_writes_it(tmp_path: Path) -> None:
    document = json.loads(write_map(tmp_path / "map.json", SEGMENTS).read_text())
    assert (document["type"], document["version"], document["nextobjectid"]) == ("map", "1.8", 10)
    (layer,) = document["layers"]
    assert [obj["id"] for obj in layer["objects"]] == [2, 4, 9]
    obj = layer["objects"][0]
    assert obj["type"] == "curve" and obj["polyline"][0] == {"x": 0, "y": 0}
    assert obj["properties"] == [
        {"name": "direction", "propertytype": "direction", "type": "string", "value": "forward"}
    ]
    assert "properties" not in document  # default scale: no meters_per_pixel property


def test_writer_refuses_duplicate_segment_ids(tmp_path: Path) -> None:
    with pytest.raises(LayoutError, match="id=4"):
        write_map(tmp_path / "map.json", [*SEGMENTS, SEGMENTS[0]])


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"tile_size": 0}, "tile_size=0"),
        ({"meters_per_pixel": -1.0}, "meters_per_pixel=-1.0"),
        ({"margin_tiles": -1}, "margin_tiles=-1"),
    ],
)
def test_writer_refuses_bad_parameters(tmp_path: Path, kwargs: dict[str, float], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        write_map(tmp_path / "map.json", SEGMENTS, **kwargs)  # type: ignore[arg-type]


def test_writer_refuses_unknown_suffix_and_empty_maps(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"map\.yaml"):
        write_map(tmp_path / "map.yaml", SEGMENTS)
    with pytest.raises(ValueError, match="empty"):
        write_map(tmp_path / "map.json", [])
