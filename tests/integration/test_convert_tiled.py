"""Maps written by ``fleetsim convert`` open and save in the real Tiled editor (its CLI exports)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from fleetsim.enums import Shape
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.convert import convert_map
from fleetsim.load.maps.site_map import load_site_map

if TYPE_CHECKING:  # the fixture's type; conftest modules are not importable packages
    from conftest import TiledCli

pytestmark = pytest.mark.integration

SITES = Path(__file__).resolve().parents[2] / "scenario_suites" / "sites"
TOLERANCE_M = 1e-3  # TMX keeps about 6 significant digits


@pytest.mark.parametrize(
    ("source", "options"),
    [
        (SITES / "packing-hall" / "map.lif.json", MapOptions(robot_type="Acme.Tug")),
        (SITES / "clinic" / "map.building.yaml", MapOptions()),
    ],
)
def test_a_converted_site_is_opened_and_saved_by_tiled_with_its_segments_intact(
    tiled: TiledCli, tmp_path: Path, source: Path, options: MapOptions
) -> None:
    site = load_site_map(source, options)
    _, written = convert_map(source, tmp_path / "converted.json", options)
    as_tmx = tiled.export_map(written, tmp_path / "by_tiled.tmx")
    as_json = tiled.export_map(as_tmx, tmp_path / "by_tiled.json")
    for path in (as_tmx, as_json):
        loaded = load_site_map(path).segments
        assert [(s.id, s.direction, s.names) for s in loaded] == [(s.id, s.direction, s.names) for s in site.segments]
        assert {s.shape for s in loaded} <= {Shape.STRAIGHT, Shape.PATH}
        for got, want in zip(loaded, site.segments, strict=True):
            assert len(got.waypoints) == len(want.waypoints)
            assert all(math.dist(a, b) <= TOLERANCE_M for a, b in zip(got.waypoints, want.waypoints, strict=True))
