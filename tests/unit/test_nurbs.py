"""The NURBS evaluator against curves known exactly, and its sampling against the chord tolerance."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.layout.geometry import point_segment_distances
from fleetsim.layout.nurbs import CHORD_TOLERANCE, Nurbs, sample_nurbs

HALF = math.sqrt(0.5)
# A whole circle of radius 1 as a rational quadratic NURBS: nine control points on a square, corner
# weights √½, knots doubled at the quarters.
CIRCLE = Nurbs.of(
    2,
    (0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1),
    ((1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1), (1, 0)),
    (1, HALF, 1, HALF, 1, HALF, 1, HALF, 1),
)


def dense(curve: Nurbs, count: int = 20001) -> np.ndarray:
    low, high = curve.domain
    return curve.evaluate(np.linspace(low, high, count))


def deviation(curve: Nurbs, polyline: tuple[tuple[float, float], ...]) -> float:
    """The largest distance from the curve (densely evaluated) to the polyline."""
    points = dense(curve)
    a, b = np.array(polyline[:-1]), np.array(polyline[1:])
    best = np.full(len(points), np.inf)
    for start, end in zip(a, b, strict=True):
        best = np.minimum(
            best, point_segment_distances(points, np.tile(start, (len(points), 1)), np.tile(end, (len(points), 1)))
        )
    return float(best.max())


def test_a_rational_quadratic_nurbs_is_an_exact_circle() -> None:
    radii = np.hypot(*dense(CIRCLE).T)
    assert np.max(np.abs(radii - 1.0)) < 1e-12


@pytest.mark.parametrize("radius", [0.5, 2.0, 25.0])
def test_a_quarter_circle_is_exact_and_its_samples_keep_the_chord_tolerance(radius: float) -> None:
    quarter = Nurbs.of(2, (0, 0, 0, 1, 1, 1), ((radius, 0), (radius, radius), (0, radius)), (1, HALF, 1))
    assert np.max(np.abs(np.hypot(*dense(quarter).T) - radius)) < 1e-9 * radius
    polyline = sample_nurbs(quarter)
    assert polyline[0] == pytest.approx((radius, 0.0)) and polyline[-1] == pytest.approx((0.0, radius))
    # The sagitta of a chord spanning angle θ is r(1 − cos θ/2): every chord's must be within 1 cm.
    angles = np.diff(np.arctan2([y for _, y in polyline], [x for x, _ in polyline]))
    sagittas = radius * (1 - np.cos(angles / 2))
    assert sagittas.max() <= CHORD_TOLERANCE
    assert deviation(quarter, polyline) <= CHORD_TOLERANCE
    # ... and it is not wastefully dense: halving pieces leaves the largest chord above a tenth of the tolerance.
    if radius >= 2.0:
        assert sagittas.max() > CHORD_TOLERANCE / 10


def test_the_sampled_whole_circle_closes_and_keeps_the_tolerance() -> None:
    polyline = sample_nurbs(CIRCLE)
    assert polyline[0] == pytest.approx((1.0, 0.0)) and polyline[-1] == pytest.approx((1.0, 0.0))
    assert deviation(CIRCLE, polyline) <= CHORD_TOLERANCE


def test_degree_one_is_the_polyline_through_its_control_points() -> None:
    zigzag = ((0, 0), (1, 1), (2, 0), (3, 1))
    curve = Nurbs.of(1, (0, 0, 0.2, 0.7, 1, 1), zigzag, (1, 3, 0.5, 1))  # weights do not bend a line
    assert sample_nurbs(curve) == tuple((float(x), float(y)) for x, y in zigzag)
    # The knot 0.2 is reached at the second control point: a piece is linear in its own span.
    assert curve.evaluate(np.array([0.2]))[0] == pytest.approx((1.0, 1.0))


def bezier(control: np.ndarray, weights: np.ndarray, t: float) -> np.ndarray:
    """The rational Bézier curve by Bernstein polynomials: the reference for clamped single-span NURBS."""
    n = len(control) - 1
    bernstein = np.array([math.comb(n, i) * t**i * (1 - t) ** (n - i) for i in range(n + 1)])
    weighted = bernstein * weights
    result: np.ndarray = weighted @ control / weighted.sum()
    return result


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_single_span_nurbs_of_each_degree_with_weights_match_rational_bezier(degree: int) -> None:
    rng = np.random.default_rng(degree)
    control = rng.uniform(-5, 5, size=(degree + 1, 2))
    weights = rng.uniform(0.3, 3.0, size=degree + 1)
    curve = Nurbs.of(degree, [0.0] * (degree + 1) + [1.0] * (degree + 1), [tuple(p) for p in control], list(weights))
    for t in np.linspace(0, 1, 11):
        assert curve.evaluate(np.array([t]))[0] == pytest.approx(bezier(control, weights, t), abs=1e-12)


def test_a_cubic_with_interior_knots_is_continuous_and_samples_within_tolerance() -> None:
    curve = Nurbs.of(
        3, (0, 0, 0, 0, 0.3, 0.6, 1, 1, 1, 1), ((0, 0), (2, 0), (3, 2), (5, -1), (6, 3), (8, 3)), (1, 2, 0.5, 1, 1.5, 1)
    )
    polyline = sample_nurbs(curve)
    assert polyline[0] == (0.0, 0.0) and polyline[-1] == pytest.approx((8.0, 3.0))
    assert deviation(curve, polyline) <= CHORD_TOLERANCE
    left, right = curve.evaluate(np.array([0.3 - 1e-9, 0.3 + 1e-9]))
    assert math.dist(left, right) < 1e-6


def test_reversing_knots_and_control_points_traces_the_same_curve_backwards() -> None:
    knots = (0, 0, 0, 0.4, 1, 1, 1)
    control = ((0, 0), (1, 2), (3, 2), (4, 0))
    weights = (1, 2, 0.7, 1)
    forward = Nurbs.of(2, knots, control, weights)
    backward = Nurbs.of(2, tuple(1 - k for k in reversed(knots)), tuple(reversed(control)), tuple(reversed(weights)))
    u = np.linspace(0, 1, 101)
    assert np.allclose(forward.evaluate(u), backward.evaluate(1 - u)[:, :], atol=1e-12)


@settings(max_examples=300, deadline=None)
@given(
    degree=st.integers(1, 3),
    extra=st.integers(0, 3),
    seed=st.integers(0, 2**32 - 1),
)
def test_random_curves_sample_within_the_chord_tolerance(degree: int, extra: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    count = degree + 1 + extra
    inner = np.sort(rng.uniform(0, 1, size=count - degree - 1))
    knots = [0.0] * (degree + 1) + list(inner) + [1.0] * (degree + 1)
    curve = Nurbs.of(
        degree, knots, [tuple(p) for p in rng.uniform(-3, 3, size=(count, 2))], list(rng.uniform(0.2, 4.0, size=count))
    )
    assert deviation(curve, sample_nurbs(curve)) <= CHORD_TOLERANCE * 1.0001


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((0, (0, 1), ((0, 0),)), "degree=0 must be a whole number >= 1"),
        ((2, (0, 0, 0, 1, 1), ((0, 0), (1, 1))), "2 control points are too few for degree 2: at least 3 are needed"),
        ((1, (0, 0, 1), ((0, 0), (1, 1))), "the knot vector has 3 values; 2 control points of degree 1 need 4"),
        ((1, (0, 1, 0.5, 1), ((0, 0), (1, 1))), "must be finite and non-decreasing"),
        ((1, (0, 0.5, 0.5, 1), ((0, 0), (1, 1))), "leave an empty domain [0.5, 0.5]"),
    ],
)
def test_invalid_curves_are_refused_naming_the_value(args: tuple[object, ...], message: str) -> None:
    with pytest.raises(ValueError) as caught:
        Nurbs.of(*args)  # type: ignore[arg-type]
    assert message in str(caught.value)


def test_weights_must_be_positive_and_one_per_control_point() -> None:
    with pytest.raises(ValueError, match="must be finite and > 0"):
        Nurbs.of(1, (0, 0, 1, 1), ((0, 0), (1, 0)), (1, 0))
    with pytest.raises(ValueError, match="3 weights for 2 control points"):
        Nurbs.of(1, (0, 0, 1, 1), ((0, 0), (1, 0)), (1, 1, 1))
