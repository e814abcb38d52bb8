"""A generated scenario's saved map opens in the real Tiled editor, and Tiled's export loads to the same
segments, connections and conflicts (so a counterexample can be inspected and edited in Tiled)."""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fleetsim.layout import build_layout
from fleetsim.load.tiled.reader import load_map
from fleetsim.scenario import Scenario
from fleetsim.strategies import LAYOUT_KINDS, GenerationSpec, save_scenario, scenarios

if TYPE_CHECKING:  # the fixture's type; conftest modules are not importable packages
    from conftest import TiledCli

pytestmark = pytest.mark.integration

# Tiled keeps JSON coordinates as doubles; TMX keeps about 6 significant digits of pixels.
TOLERANCE_M = {".json": 1e-9, ".tmx": 1e-3}

any_kind = st.sampled_from(LAYOUT_KINDS).flatmap(
    lambda kind: scenarios(GenerationSpec(layout=kind, size=(1, 2), vehicles=(1, 2)))
)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenario=any_kind)
def test_saved_generated_map_exported_by_tiled_loads_to_the_same_layout(tiled: TiledCli, scenario: Scenario) -> None:
    layout = scenario.layout
    with tempfile.TemporaryDirectory() as tmp:
        folder = save_scenario(scenario, Path(tmp) / "generated")
        for suffix, tolerance in TOLERANCE_M.items():
            exported = load_map(tiled.export_map(folder / "map.json", Path(tmp) / f"by_tiled{suffix}")).segments
            assert [(s.id, s.shape, s.direction) for s in exported] == [
                (s.id, s.shape, s.direction) for s in layout.segments.values()
            ]
            for got, want in zip(exported, layout.segments.values(), strict=True):
                assert len(got.waypoints) == len(want.waypoints)
                assert all(
                    abs(g - w) <= tolerance
                    for p, q in zip(got.waypoints, want.waypoints, strict=True)
                    for g, w in zip(p, q, strict=True)
                )
            again = build_layout(exported, vehicle_radius=layout.vehicle_radius)
            assert again.connections == layout.connections
            assert {s: again.conflicts(s) for s in again.segments} == {s: layout.conflicts(s) for s in layout.segments}
