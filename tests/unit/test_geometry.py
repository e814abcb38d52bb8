"""Exact distances and the grid broad phase, checked against brute force."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fleetsim.layout.geometry import (
    away_direction,
    close_point_pairs,
    overlapping_box_pairs,
    point_segment_distances,
    segment_distances,
)

P = tuple[float, float]


def _distance(a0: P, a1: P, b0: P, b1: P) -> float:
    arrays = [np.array([p], dtype=np.float64) for p in (a0, a1, b0, b1)]
    return float(segment_distances(*arrays)[0])


@pytest.mark.parametrize(
    ("a0", "a1", "b0", "b1", "expected"),
    [
        pytest.param((0, 0), (4, 4), (0, 4), (4, 0), 0.0, id="crossing"),
        pytest.param((0, 0), (4, 0), (0, 1.5), (4, 1.5), 1.5, id="parallel"),
        pytest.param((0, 0), (4, 0), (2, 0), (6, 0), 0.0, id="collinear-overlapping"),
        pytest.param((0, 0), (4, 0), (5, 0), (6, 0), 1.0, id="collinear-disjoint"),
        pytest.param((0, 0), (4, 0), (2, 0), (2, 3), 0.0, id="t-touching"),
        pytest.param((0, 0), (4, 0), (6, 3), (9, 7), math.hypot(2, 3), id="endpoint-to-endpoint"),
        pytest.param((2, 2), (2, 2), (0, 0), (4, 0), 2.0, id="zero-length-vs-segment"),
        pytest.param((1, 1), (1, 1), (4, 5), (4, 5), 5.0, id="both-zero-length"),
        pytest.param((1, 1), (1, 1), (1, 1), (1, 1), 0.0, id="same-point"),
        pytest.param((0, 0), (4, 0), (1, -1), (3, -1), 1.0, id="parallel-shorter-below"),
    ],
)
def test_segment_distance_matches_known_geometry(a0: P, a1: P, b0: P, b1: P, expected: float) -> None:
    assert _distance(a0, a1, b0, b1) == pytest.approx(expected, abs=1e-12)
    assert _distance(b1, b0, a1, a0) == pytest.approx(expected, abs=1e-12)


def test_segment_distance_is_never_more_than_densely_sampled_distance_and_close_to_it() -> None:
    rng = np.random.default_rng(7)
    a0, a1, b0, b1 = (rng.uniform(-3, 3, size=(200, 2)) for _ in range(4))
    exact = segment_distances(a0, a1, b0, b1)
    t = np.linspace(0.0, 1.0, 121)
    pa = a0[:, None, :] + t[None, :, None] * (a1 - a0)[:, None, :]
    pb = b0[:, None, :] + t[None, :, None] * (b1 - b0)[:, None, :]
    sampled = np.linalg.norm(pa[:, :, None, :] - pb[:, None, :, :], axis=-1).min(axis=(1, 2))
    assert np.all(exact <= sampled + 1e-12)
    assert np.all(sampled - exact < 0.05)  # sample spacing <= 8.5 m / 120


def test_point_to_zero_length_segment_is_point_distance() -> None:
    d = point_segment_distances(np.array([[3.0, 4.0]]), np.array([[0.0, 0.0]]), np.array([[0.0, 0.0]]))
    assert d.tolist() == [5.0]


def _brute_force_box_pairs(boxes: np.ndarray) -> set[tuple[int, int]]:
    n = len(boxes)
    return {
        (i, j)
        for i in range(n)
        for j in range(i + 1, n)
        if boxes[i, 0] <= boxes[j, 2]
        and boxes[j, 0] <= boxes[i, 2]
        and boxes[i, 1] <= boxes[j, 3]
        and boxes[j, 1] <= boxes[i, 3]
    }


def test_grid_finds_exactly_the_overlapping_boxes_of_mixed_sizes() -> None:
    rng = np.random.default_rng(3)
    lo = rng.uniform(0, 100, size=(400, 2))
    size = np.where(rng.random((400, 1)) < 0.05, rng.uniform(20, 60, (400, 2)), rng.uniform(0, 3, (400, 2)))
    size[:20] = 0.0  # degenerate boxes (points)
    boxes = np.concatenate([lo, lo + size], axis=1)
    pairs = overlapping_box_pairs(boxes)
    found = {(int(i), int(j)) for i, j in pairs}
    assert len(found) == len(pairs)  # each pair reported once
    assert found == _brute_force_box_pairs(boxes)


def test_boxes_that_share_only_an_edge_overlap() -> None:
    boxes = np.array([[0.0, 0.0, 1.0, 1.0], [1.0, 0.0, 2.0, 1.0], [2.5, 0.0, 3.0, 1.0]])
    assert overlapping_box_pairs(boxes).tolist() == [[0, 1]]


def test_close_point_pairs_includes_the_radius_and_excludes_beyond() -> None:
    points = np.array([[0.0, 0.0], [0.05, 0.0], [0.0, 0.051], [5.0, 5.0], [5.0, 5.0]])
    pairs, gaps = close_point_pairs(points, 0.05)
    assert pairs.tolist() == [[0, 1], [3, 4]]
    assert gaps.tolist() == pytest.approx([0.05, 0.0])


def test_away_direction_skips_waypoints_at_the_end_point() -> None:
    waypoints = ((-4.0, 0.0), (0.0, 0.0), (0.0, 0.0))
    assert away_direction(waypoints, at_last=True, skip=0.0) == (-1.0, 0.0)


def test_away_direction_of_a_segment_collapsed_to_a_point_is_undefined() -> None:
    assert away_direction(((1.0, 1.0), (1.0, 1.0)), at_last=False, skip=0.05) is None


def test_a_piece_too_short_to_invert_its_squared_length_is_measured_as_a_point() -> None:
    # |d|² underflows to a subnormal; 1/|d|² would be inf and poison the distance with NaN.
    tiny = np.array([[0.0, 0.0]]), np.array([[0.0, 8.9e-157]])
    other = np.array([[0.0, 1.0]]), np.array([[0.0, 0.0]])
    assert segment_distances(*tiny, *other).tolist() == [0.0]
    assert point_segment_distances(np.array([[3.0, 4.0]]), *tiny).tolist() == [5.0]
