"""The shipped Tiled assets (scenario_suites/tiled/) are what the loader and SPEC §3 expect."""

from __future__ import annotations

import json
import math
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from fleetsim.enums import Direction, Shape
from fleetsim.errors import Location
from fleetsim.layout.segment import Segment
from fleetsim.load.tiled.reader import load_map, parse_direction

ASSETS = Path(__file__).resolve().parents[2] / "scenario_suites" / "tiled"


def instance(tmp_path: Path, template: str, suffix: str = ".tmx") -> Segment:
    """The template instanced at the centre of a 20 x 20 map (so its origin is world (0, 0))."""
    reference = os.path.relpath(ASSETS / template, tmp_path)
    path = tmp_path / ("map" + suffix)
    if suffix == ".tmx":
        path.write_text(
            '<map orientation="orthogonal" width="20" height="20" tilewidth="32" '
            f'tileheight="32"><objectgroup><object id="1" template="{reference}" '
            'x="320" y="320"/></objectgroup></map>'
        )
    else:
        path.write_text(
            json.dumps(
                {
                    "orientation": "orthogonal",
                    "width": 20,
                    "height": 20,
                    "tilewidth": 32,
                    "tileheight": 32,
                    "layers": [
                        {"type": "objectgroup", "objects": [{"id": 1, "template": reference, "x": 320, "y": 320}]}
                    ],
                }
            )
        )
    (segment,) = load_map(path).segments
    return segment


def test_project_declares_the_direction_enum_in_the_loaders_index_order() -> None:
    project = json.loads((ASSETS / "fleetsim.tiled-project").read_text())
    (enum,) = [t for t in project["propertyTypes"] if t["name"] == "direction"]
    assert (enum["type"], enum["storageType"], enum["valuesAsFlags"]) == ("enum", "string", False)
    assert enum["values"] == ["both", "forward", "backward"]
    for index, name in enumerate(enum["values"]):
        assert parse_direction(index, Location("project")) is Direction(name)
    assert project["folders"] == ["."]


@pytest.mark.parametrize("template", ["straight.tx", "curve.tx", "s_curve.tx", "path.tx"])
def test_templates_use_type_and_the_direction_enum(template: str) -> None:
    obj = ET.parse(ASSETS / template).getroot().find("object")
    assert obj is not None and obj.get("type") == template.removesuffix(".tx")
    (prop,) = obj.findall("properties/property")
    assert prop.attrib == {"name": "direction", "propertytype": "direction", "value": "both"}


@pytest.mark.parametrize("suffix", [".tmx", ".json"])
def test_straight_template_is_four_tiles_along_x(tmp_path: Path, suffix: str) -> None:
    segment = instance(tmp_path, "straight.tx", suffix)
    assert (segment.shape, segment.direction) == (Shape.STRAIGHT, Direction.BOTH)
    assert segment.waypoints == ((0.0, 0.0), (4.0, 0.0))


@pytest.mark.parametrize("suffix", [".tmx", ".json"])
def test_curve_template_is_a_dense_quarter_circle_of_two_tiles(tmp_path: Path, suffix: str) -> None:
    segment = instance(tmp_path, "curve.tx", suffix)
    assert segment.shape is Shape.CURVE
    assert len(segment.waypoints) == 10  # 10° steps: ≥ 9 waypoints per 90° (SPEC §3)
    assert segment.first == (0.0, 0.0) and segment.last == (2.0, 2.0)  # a left turn, y up
    for x, y in segment.waypoints:
        assert math.hypot(x, y - 2.0) == pytest.approx(2.0, abs=1e-5)


@pytest.mark.parametrize("suffix", [".tmx", ".json"])
def test_s_curve_template_changes_lane_by_one_tile_over_four(tmp_path: Path, suffix: str) -> None:
    segment = instance(tmp_path, "s_curve.tx", suffix)
    assert segment.shape is Shape.S_CURVE and len(segment.waypoints) == 13
    assert segment.first == (0.0, 0.0) and segment.last == (4.0, 1.0)
    for x, y in segment.waypoints:  # the cosine profile
        assert y == pytest.approx((1 - math.cos(math.pi * x / 4)) / 2, abs=1e-5)
