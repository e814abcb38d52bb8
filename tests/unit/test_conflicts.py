"""Conflict sets (SPEC §4): swept circles by default, the thesis's bounding boxes on request."""

from __future__ import annotations

import numpy as np
import pytest

from fleetsim.enums import ConflictModel, Direction, Shape
from fleetsim.layout import Segment, all_pairs_conflicts, build_layout
from fleetsim.layout.conflicts import bbox_conflicts, swept_conflicts


def _straight(sid: int, *points: tuple[float, float]) -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, tuple(points))


def _quarter_arc(sid: int, radius: float, n: int = 10) -> Segment:
    """90° curve centred on the origin, from (radius, 0) to (0, radius)."""
    angles = np.radians(np.linspace(0.0, 90.0, n))
    return Segment(
        sid, Shape.CURVE, Direction.BOTH, tuple(zip(radius * np.cos(angles), radius * np.sin(angles), strict=True))
    )


def _figure_24() -> list[Segment]:
    """Thesis figure 24: a short straight inside a curve's bounding box, near its inner corner."""
    return [_quarter_arc(1, 5.0), _straight(2, (0.5, 0.5), (1.5, 0.5))]


def test_bbox_model_flags_a_straight_inside_a_curves_box_far_from_the_arc() -> None:
    layout = build_layout(_figure_24(), vehicle_radius=0.5, conflict_model=ConflictModel.BBOX)
    assert layout.conflicts(1) == {1, 2}


def test_swept_model_does_not_flag_a_straight_inside_a_curves_box_far_from_the_arc() -> None:
    layout = build_layout(_figure_24(), vehicle_radius=0.5)
    assert layout.conflicts(1) == {1}
    assert layout.conflicts(2) == {2}


@pytest.mark.parametrize(
    ("gap", "margin", "conflict"),
    [
        (1.19, 0.2, True),
        (1.21, 0.2, False),
        (0.99, 0.0, True),
        (1.01, 0.0, False),
        (1.1, 0.0, False),
        (1.1, 0.2, True),
    ],
)
def test_parallel_lanes_conflict_when_closer_than_two_radii_plus_margin(
    gap: float, margin: float, conflict: bool
) -> None:
    lanes = [_straight(1, (0, 0), (10, 0)), _straight(2, (0, gap), (10, gap))]
    layout = build_layout(lanes, vehicle_radius=0.5, safety_margin=margin)
    assert (2 in layout.conflicts(1)) is conflict
    assert (1 in layout.conflicts(2)) is conflict


def test_lanes_exactly_two_radii_apart_do_not_conflict() -> None:
    lanes = [_straight(1, (0, 0), (10, 0)), _straight(2, (0, 1.0), (10, 1.0))]
    assert build_layout(lanes, vehicle_radius=0.5).conflicts(1) == {1}


@pytest.mark.parametrize("model", list(ConflictModel))
def test_point_vehicles_still_conflict_with_self_and_touching_segments(model: ConflictModel) -> None:
    segments = [
        _straight(1, (0, 0), (4, 0)),
        _straight(2, (4, 0), (4, 4)),  # shares an end with 1
        _straight(3, (2, 0.04), (2, -3)),  # ends on 1's middle, within the connection tolerance
        _straight(4, (1, 0.06), (1, 3)),  # just beyond it
        _straight(5, (10, 10), (12, 10)),
    ]
    layout = build_layout(segments, vehicle_radius=0.0, conflict_model=model)
    assert layout.conflicts(1) == {1, 2, 3}
    assert layout.conflicts(4) == {4}
    assert layout.conflicts(5) == {5}


def test_bbox_model_grows_boxes_by_radius_plus_half_the_margin() -> None:
    lanes = [_straight(1, (0, 0), (10, 0)), _straight(2, (0, 1.1), (10, 1.1))]
    assert bbox_conflicts(lanes, 0.5)[1] == {1}
    assert bbox_conflicts(lanes, 0.5 + 0.1 / 2)[1] == {1, 2}
    layout = build_layout(lanes, vehicle_radius=0.5, safety_margin=0.1, conflict_model=ConflictModel.BBOX)
    assert layout.conflicts(1) == {1, 2}


def _random_segments(count: int, seed: int) -> list[Segment]:
    """Straights and wiggly polylines of up to 10 points, some with repeated or collinear waypoints."""
    rng = np.random.default_rng(seed)
    segments = []
    for sid in range(1, count + 1):
        start = rng.uniform(0.0, 40.0, size=2)
        n = 2 if rng.random() < 0.4 else int(rng.integers(3, 11))
        steps = rng.normal(0.0, 0.8, size=(n - 1, 2))
        if rng.random() < 0.1:
            steps[rng.integers(0, n - 1)] = 0.0  # a zero-length piece
        if rng.random() < 0.1:
            steps[:] = steps[0]  # all pieces collinear
        points = np.vstack([start, start + np.cumsum(steps, axis=0)])
        shape = Shape.STRAIGHT if n == 2 else Shape.CURVE
        segments.append(Segment(sid, shape, Direction.BOTH, tuple(map(tuple, points.tolist()))))
    return segments


@pytest.mark.parametrize("threshold", [0.0, 0.4, 3.0])
def test_broad_phase_finds_the_same_conflicts_as_all_pairs(threshold: float) -> None:
    segments = _random_segments(250, seed=11)
    assert swept_conflicts(segments, threshold, 0.05) == all_pairs_conflicts(segments, threshold, touch=0.05)


def test_layout_conflicts_equal_the_all_pairs_reference() -> None:
    segments = _random_segments(200, seed=5)
    layout = build_layout(segments, vehicle_radius=0.6, safety_margin=0.1)
    reference = all_pairs_conflicts(segments, 2 * 0.6 + 0.1, touch=0.05)
    assert {sid: layout.conflicts(sid) for sid in layout.segments} == reference


@pytest.mark.parametrize("model", list(ConflictModel))
def test_conflicts_are_symmetric_and_include_the_segment_itself(model: ConflictModel) -> None:
    layout = build_layout(_random_segments(150, seed=2), vehicle_radius=0.4, conflict_model=model)
    for sid in layout.segments:
        assert sid in layout.conflicts(sid)
        assert all(sid in layout.conflicts(other) for other in layout.conflicts(sid))


def test_bbox_model_flags_every_pair_the_swept_model_flags() -> None:
    segments = _random_segments(150, seed=9)
    swept = build_layout(segments, vehicle_radius=0.4)
    boxes = build_layout(segments, vehicle_radius=0.4, conflict_model=ConflictModel.BBOX)
    assert all(swept.conflicts(sid) <= boxes.conflicts(sid) for sid in swept.segments)


@pytest.mark.parametrize("model", list(ConflictModel))
def test_layouts_with_zero_or_one_segment_have_trivial_conflicts(model: ConflictModel) -> None:
    assert build_layout([], vehicle_radius=0.3, conflict_model=model).segments == {}
    assert build_layout([_straight(4, (0, 0), (1, 0))], vehicle_radius=0.3, conflict_model=model).conflicts(4) == {4}
