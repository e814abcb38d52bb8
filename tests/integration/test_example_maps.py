"""The shipped example maps are Tiled's own files: Tiled wrote them and re-saves them unchanged."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from fleetsim.load.tiled.reader import load_map

if TYPE_CHECKING:  # the fixture's type; conftest modules are not importable packages
    from conftest import TiledCli

pytestmark = pytest.mark.integration

EXAMPLES = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples"
MAPS = sorted(p for p in EXAMPLES.glob("*/map.*"))


def _tiled_version(path: Path) -> str | None:
    if path.suffix == ".tmx":
        return ET.parse(path).getroot().get("tiledversion")
    return json.loads(path.read_text(encoding="utf-8")).get("tiledversion")


def test_there_are_example_maps_in_every_format() -> None:
    assert {p.suffix for p in MAPS} == {".json", ".tmj", ".tmx"}


@pytest.mark.parametrize("path", MAPS, ids=lambda p: p.parent.name)
def test_example_map_was_saved_by_tiled(path: Path) -> None:
    assert _tiled_version(path) is not None


@pytest.mark.parametrize("path", MAPS, ids=lambda p: p.parent.name)
@pytest.mark.parametrize("target_suffix", [".json", ".tmx"])
def test_example_map_resaved_by_tiled_with_templates_detached_loads_the_same(
    tiled: TiledCli, tmp_path: Path, path: Path, target_suffix: str
) -> None:
    exported = tiled.export_map(path, tmp_path / f"resaved{target_suffix}", detach_templates=True)
    original = load_map(path).segments
    resaved = load_map(exported).segments
    assert [s.id for s in resaved] == [s.id for s in original]
    for before, after in zip(original, resaved, strict=True):
        assert (after.shape, after.direction) == (before.shape, before.direction)
        assert len(after.waypoints) == len(before.waypoints)
        for p, q in zip(before.waypoints, after.waypoints, strict=True):
            assert q == pytest.approx(p, abs=1e-4)
