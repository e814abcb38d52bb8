"""Properties of loading and layout that must hold for any map, checked on Hypothesis-generated ones."""

from __future__ import annotations

import tempfile
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.enums import Direction, Shape
from fleetsim.layout.conflicts import all_pairs_conflicts, swept_conflicts
from fleetsim.layout.segment import Segment, polyline_length
from fleetsim.load.tiled.reader import load_map
from fleetsim.load.tiled.writer import write_map

coordinate = st.floats(min_value=-40.0, max_value=40.0, allow_nan=False, allow_infinity=False)
point = st.tuples(coordinate, coordinate)


@st.composite
def segment_lists(draw: st.DrawFn, max_size: int = 12) -> list[Segment]:
    count = draw(st.integers(min_value=1, max_value=max_size))
    ids = draw(st.lists(st.integers(1, 10_000), min_size=count, max_size=count, unique=True))
    segments = []
    for sid in ids:
        # Real maps are drawn in pixels: points closer than a millimetre to all others are not a map.
        waypoints = draw(st.lists(point, min_size=2, max_size=6).filter(lambda ps: polyline_length(tuple(ps)) > 1e-3))
        shape = draw(st.sampled_from(Shape))
        direction = draw(st.sampled_from(Direction))
        segments.append(Segment(sid, shape, direction, tuple(waypoints)))
    return segments


@settings(max_examples=60, deadline=None)
@given(segments=segment_lists(), suffix=st.sampled_from([".json", ".tmj", ".tmx"]))
def test_written_map_loads_back_to_the_same_segments(segments: list[Segment], suffix: str) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        loaded = load_map(write_map(Path(tmp) / f"map{suffix}", segments)).segments
    expected = sorted(segments, key=lambda s: s.id)
    assert [(s.id, s.shape, s.direction) for s in loaded] == [(s.id, s.shape, s.direction) for s in expected]
    for got, want in zip(loaded, expected, strict=True):
        assert len(got.waypoints) == len(want.waypoints)
        for (gx, gy), (wx, wy) in zip(got.waypoints, want.waypoints, strict=True):
            assert abs(gx - wx) <= 1e-9 and abs(gy - wy) <= 1e-9


@settings(max_examples=80, deadline=None)
@given(segments=segment_lists(max_size=25), threshold=st.floats(0.0, 12.0), touch=st.sampled_from([0.0, 0.05]))
def test_grid_broad_phase_finds_exactly_the_all_pairs_conflicts(
    segments: list[Segment], threshold: float, touch: float
) -> None:
    assert swept_conflicts(segments, threshold, touch) == all_pairs_conflicts(segments, threshold, touch=touch)
