"""Maps written by the real Tiled editor (its CLI exports) load to the segments the source describes."""

from __future__ import annotations

import math
import os
from itertools import pairwise
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from fleetsim.enums import Direction, Shape
from fleetsim.layout.segment import Point, Segment
from fleetsim.load.tiled.reader import load_map
from fleetsim.load.tiled.writer import write_map

if TYPE_CHECKING:  # the fixture's type; conftest modules are not importable packages
    from conftest import TiledCli

# Without Tiled the `tiled` fixture skips (or, in CI, fails) every test here.
pytestmark = pytest.mark.integration

ASSETS = Path(__file__).resolve().parents[2] / "scenario_suites" / "tiled"
# TMX keeps about 6 significant digits of pixel coordinates: ~1e-3 px on these maps.
TOLERANCE_M = 1e-3


def assert_same_segments(actual: tuple[Segment, ...], expected: tuple[Segment, ...]) -> None:
    assert [(s.id, s.shape, s.direction) for s in actual] == [(s.id, s.shape, s.direction) for s in expected]
    for got, want in zip(actual, expected, strict=True):
        assert_points(got.waypoints, want.waypoints)


def assert_points(actual: tuple[Point, ...], expected: tuple[Point, ...]) -> None:
    assert len(actual) == len(expected), (actual, expected)
    for (ax, ay), (ex, ey) in zip(actual, expected, strict=True):
        assert abs(ax - ex) <= TOLERANCE_M and abs(ay - ey) <= TOLERANCE_M, (actual, expected)


def test_maps_resaved_by_tiled_load_to_the_same_segments(tiled: TiledCli, tmp_path: Path) -> None:
    arc = tuple((5 + 3 * math.sin(math.radians(a)), 3 - 3 * math.cos(math.radians(a))) for a in range(0, 91, 10))
    segments = (
        Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-5.0, 0.0), (5.0, 0.0))),
        Segment(2, Shape.CURVE, Direction.FORWARD, arc),
        Segment(3, Shape.S_CURVE, Direction.BACKWARD, ((8.0, 3.0), (8.1, 3.7), (7.3, 5.123456789))),
    )
    source = write_map(tmp_path / "source.tmx", segments, meters_per_pixel=0.05)
    as_json = tiled.export_map(source, tmp_path / "by_tiled.json")
    as_tmx = tiled.export_map(as_json, tmp_path / "by_tiled.tmx")
    for path in (source, as_json, as_tmx):
        loaded = load_map(path)
        assert loaded.meters_per_pixel == 0.05
        assert_same_segments(loaded.segments, segments)


# A curve template rotated 90° in an object layer (offset 2,-6) inside a group (-4,24) inside a group
# (16,8): the offsets sum to (14, 26). Map: 20 x 10 tiles of 32 px, so the centre is pixel (320, 160).
NESTED_MAP = """<?xml version="1.0" encoding="UTF-8"?>
<map version="1.8" orientation="orthogonal" renderorder="right-down" width="20" height="10"
     tilewidth="32" tileheight="32" infinite="0" nextlayerid="4" nextobjectid="3">
 <group id="1" name="outer" offsetx="16" offsety="8">
  <group id="2" name="inner" offsetx="-4" offsety="24">
   <objectgroup id="3" name="segments" offsetx="2" offsety="-6">
    <object id="1" template="{template}" x="98" y="56" rotation="90"/>
    <object id="2" template="{template}" x="306" y="134" rotation="180">
     <properties><property name="direction" value="backward"/></properties>
     <polyline points="0,0 32,16"/>
    </object>
   </objectgroup>
  </group>
 </group>
</map>
"""
BEND_TX = """<?xml version="1.0" encoding="UTF-8"?>
<template>
 <object type="curve">
  <properties><property name="direction" value="forward"/></properties>
  <polyline points="0,0 64,0 64,32"/>
 </object>
</template>
"""
BEND_TJ = """{"type": "template", "object": {"type": "curve", "name": "", "rotation": 0,
 "width": 0, "height": 0, "visible": true,
 "properties": [{"name": "direction", "type": "string", "value": "forward"}],
 "polyline": [{"x": 0, "y": 0}, {"x": 64, "y": 0}, {"x": 64, "y": 32}]}}
"""
NESTED_EXPECTED = (
    # origin (98, 56) + (14, 26) = (112, 82); points turned 90° clockwise: (0,0) (0,64) (-32,64).
    Segment(1, Shape.CURVE, Direction.FORWARD, ((-6.5, 2.4375), (-6.5, 0.4375), (-7.5, 0.4375))),
    # origin (306, 134) + (14, 26) = the map centre; the overriding points turned 180°: (-32, -16).
    Segment(2, Shape.CURVE, Direction.BACKWARD, ((0.0, 0.0), (-1.0, 0.5))),
)


@pytest.mark.parametrize("template_suffix", [".tx", ".tj"])
@pytest.mark.parametrize("map_suffix", [".tmx", ".json"])
def test_rotated_template_instance_in_nested_offset_groups_matches_tiled_detached_export(
    tiled: TiledCli, tmp_path: Path, map_suffix: str, template_suffix: str
) -> None:
    (tmp_path / "templates").mkdir()
    template = tmp_path / "templates" / ("bend" + template_suffix)
    template.write_text(BEND_TX if template_suffix == ".tx" else BEND_TJ)
    source = tmp_path / "nested.tmx"
    source.write_text(NESTED_MAP.format(template="templates/bend" + template_suffix))
    if map_suffix == ".json":  # Tiled's own JSON, template references kept
        source = tiled.export_map(source, tmp_path / "nested.json")
        assert "bend" + template_suffix in source.read_text()

    original = load_map(source)
    assert_same_segments(original.segments, NESTED_EXPECTED)
    for detached_suffix in (".json", ".tmx"):
        detached = tiled.export_map(source, tmp_path / ("detached" + detached_suffix), detach_templates=True)
        assert "template" not in detached.read_text()
        assert_same_segments(load_map(detached).segments, original.segments)


def _turn_degrees(points: tuple[Point, ...]) -> float:
    """The turn of an evenly sampled arc: its n chords turn by (n - 1)/n of the arc's angle."""
    headings = [math.atan2(b[1] - a[1], b[0] - a[0]) for a, b in pairwise(points)]
    chords = len(headings)
    return math.degrees(abs(headings[-1] - headings[0])) * chords / (chords - 1)


def test_shipped_templates_survive_a_tiled_round_trip(tiled: TiledCli, tmp_path: Path) -> None:
    def ref(name: str) -> str:
        return os.path.relpath(ASSETS / name, tmp_path)

    # straight → curve (left turn) → s-curve turned to head up the screen, end to end.
    source = tmp_path / "shipped.tmx"
    source.write_text(f"""<?xml version="1.0" encoding="UTF-8"?>
<map version="1.8" orientation="orthogonal" width="30" height="30" tilewidth="32" tileheight="32"
     infinite="0" nextlayerid="2" nextobjectid="4">
 <objectgroup id="1" name="segments">
  <object id="1" template="{ref("straight.tx")}" x="160" y="480"/>
  <object id="2" template="{ref("curve.tx")}" x="288" y="480">
   <properties><property name="direction" propertytype="direction" value="forward"/></properties>
  </object>
  <object id="3" template="{ref("s_curve.tx")}" x="352" y="416" rotation="-90"/>
 </objectgroup>
</map>
""")
    resaved = tiled.export_map(source, tmp_path / "resaved.tmx")
    detached = tiled.export_map(source, tmp_path / "detached.json", detach_templates=True)
    original = load_map(source)
    for path in (resaved, detached):
        loaded = load_map(path)
        assert_same_segments(loaded.segments, original.segments)
        straight, curve, s_curve = loaded.segments
        assert [s.shape for s in loaded.segments] == [Shape.STRAIGHT, Shape.CURVE, Shape.S_CURVE]
        assert [s.direction for s in loaded.segments] == [Direction.BOTH, Direction.FORWARD, Direction.BOTH]
        assert math.dist(straight.last, curve.first) < 0.05
        assert math.dist(curve.last, s_curve.first) < 0.05
        assert straight.length == pytest.approx(4.0)
        turn = _turn_degrees(curve.waypoints)
        assert turn == pytest.approx(90.0, abs=0.01)
        assert len(curve.waypoints) >= 9 * turn / 90.0  # ≥ 9 waypoints per 90° (SPEC §3)
        assert s_curve.last[0] - s_curve.first[0] == pytest.approx(-1.0, abs=TOLERANCE_M)
        assert s_curve.last[1] - s_curve.first[1] == pytest.approx(4.0, abs=TOLERANCE_M)


def test_station_properties_survive_a_tiled_round_trip_and_template_merging(tiled: TiledCli, tmp_path: Path) -> None:
    # A template that makes its instances "dock" stations of weight 2; one instance overrides the weight,
    # one clears the station, one names two sets of its own. Tiled keeps each instance's overrides.
    template = tmp_path / "dock.tx"
    template.write_text("""<?xml version="1.0" encoding="UTF-8"?>
<template>
 <object type="straight">
  <properties>
   <property name="station" value="dock"/>
   <property name="station_weight" type="float" value="2"/>
  </properties>
  <polyline points="0,0 32,0"/>
 </object>
</template>
""")
    source = tmp_path / "stations.tmx"
    source.write_text("""<?xml version="1.0" encoding="UTF-8"?>
<map version="1.8" orientation="orthogonal" width="20" height="10" tilewidth="32" tileheight="32"
     infinite="0" nextlayerid="2" nextobjectid="5">
 <objectgroup id="1" name="segments">
  <object id="1" template="dock.tx" x="0" y="160"/>
  <object id="2" template="dock.tx" x="32" y="160">
   <properties><property name="station_weight" type="float" value="0.5"/></properties>
  </object>
  <object id="3" template="dock.tx" x="64" y="160">
   <properties><property name="station" value=""/></properties>
  </object>
  <object id="4" template="dock.tx" x="96" y="160">
   <properties><property name="station" value="pick,park"/></properties>
  </object>
 </objectgroup>
</map>
""")
    expected = {"dock": [(1, 2.0), (2, 0.5)], "park": [(4, 2.0)], "pick": [(4, 2.0)]}
    resaved = tiled.export_map(source, tmp_path / "resaved.json")
    detached = tiled.export_map(source, tmp_path / "detached.tmx", detach_templates=True)
    for path in (source, resaved, detached):
        stations = load_map(path).stations
        assert {name: [(s.segment, s.weight) for s in members] for name, members in stations.items()} == expected
