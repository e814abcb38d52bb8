"""Non-uniform rational B-splines (NURBS) in the plane: evaluation and sampling into polylines.

LIF edges carry their trajectories as NURBS (degree, knot vector, weighted control points). fleetsim's
segments are polylines, so a trajectory is sampled adaptively until no chord strays farther from the curve
than a stated tolerance (1 cm by default). Free of layout vocabulary, so it can be tested on its own.

Evaluation follows the textbook definition: the B-spline basis functions of the knot vector by the
Cox–de Boor recursion (vectorised over parameters with numpy), then the weighted average of the control
points, ``C(u) = Σ Nᵢ(u) wᵢ Pᵢ / Σ Nᵢ(u) wᵢ``, over the domain ``[u_p, u_n]``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fleetsim.layout.geometry import FloatArray, point_segment_distances

__all__ = ["CHORD_TOLERANCE", "Nurbs", "sample_nurbs"]

CHORD_TOLERANCE = 0.01  # metres: the farthest a sampled polyline may stray from its curve
# Each non-empty knot span starts as this many pieces per degree before refinement (so that a span
# whose curve bends back on itself is not mistaken for a straight one by the chord test).
_START_PIECES_PER_DEGREE = 2
_MAX_REFINEMENTS = 40  # halvings of one piece; 2⁻⁴⁰ of a span is far below any tolerance
_TEST_FRACTIONS = np.arange(1, 8) / 8.0
# The probes see a piece's curve at seven points only; holding them to half the tolerance keeps the
# whole curve within it (the property test checks this against dense evaluation of random curves).
_PROBE_SHARE = 0.5


@dataclass(frozen=True, slots=True, eq=False)
class Nurbs:
    """A planar NURBS curve; invalid definitions raise ``ValueError`` naming the value."""

    degree: int
    knots: FloatArray  # non-decreasing, len(control) + degree + 1 values
    control: FloatArray  # (n, 2)
    weights: FloatArray  # (n,), all > 0

    @classmethod
    def of(
        cls,
        degree: int,
        knots: Sequence[float],
        control: Sequence[tuple[float, float]],
        weights: Sequence[float] | None = None,
    ) -> Nurbs:
        """Check and build a curve from plain sequences (weights default to 1)."""
        if isinstance(degree, bool) or not isinstance(degree, int) or degree < 1:
            raise ValueError(f"degree={degree!r} must be a whole number >= 1")
        points = np.asarray(control, dtype=np.float64).reshape(-1, 2) if len(control) else np.empty((0, 2))
        count = len(points)
        if count < degree + 1:
            raise ValueError(
                f"{count} control points are too few for degree {degree}: at least {degree + 1} are needed"
            )
        knot_array = np.asarray(knots, dtype=np.float64)
        if len(knot_array) != count + degree + 1:
            msg = (
                f"the knot vector has {len(knot_array)} values; {count} control points of degree {degree} "
                f"need {count + degree + 1} (control points + degree + 1)"
            )
            raise ValueError(msg)
        if not np.all(np.isfinite(knot_array)) or np.any(np.diff(knot_array) < 0):
            raise ValueError(f"knots={list(knots)!r} must be finite and non-decreasing")
        if not knot_array[degree] < knot_array[count]:
            raise ValueError(f"knots={list(knots)!r} leave an empty domain [{knot_array[degree]}, {knot_array[count]}]")
        weight_array = np.ones(count) if weights is None else np.asarray(weights, dtype=np.float64)
        if len(weight_array) != count:
            raise ValueError(f"{len(weight_array)} weights for {count} control points")
        if not np.all(np.isfinite(weight_array)) or np.any(weight_array <= 0):
            raise ValueError(f"weights={[float(w) for w in weight_array]!r} must be finite and > 0")
        if not np.all(np.isfinite(points)):
            raise ValueError("control points must be finite")
        return cls(degree, knot_array, points, weight_array)

    @property
    def domain(self) -> tuple[float, float]:
        """The parameter interval the curve is defined on: ``[u_p, u_n]``."""
        return float(self.knots[self.degree]), float(self.knots[len(self.control)])

    def evaluate(self, u: FloatArray) -> FloatArray:
        """Points ``(len(u), 2)`` of the curve at parameters ``u`` (clamped to the domain)."""
        p, count = self.degree, len(self.control)
        low, high = self.domain
        u = np.clip(np.asarray(u, dtype=np.float64), low, high)
        # The span k with knots[k] <= u < knots[k+1]; the domain's end belongs to the last span.
        span = np.clip(np.searchsorted(self.knots, u, side="right") - 1, p, count - 1)
        basis = _basis(self.knots, p, span, u)
        index = span[:, None] - p + np.arange(p + 1)
        weighted = basis * self.weights[index]
        total = weighted.sum(axis=1)
        result: FloatArray = (weighted[:, :, None] * self.control[index]).sum(axis=1) / total[:, None]
        return result


def _basis(knots: FloatArray, p: int, span: np.ndarray, u: FloatArray) -> FloatArray:
    """The p + 1 non-zero basis functions at each ``u`` (Cox–de Boor, triangular scheme)."""
    m = len(u)
    basis = np.ones((m, 1))
    left = np.zeros((m, p + 1))
    right = np.zeros((m, p + 1))
    for j in range(1, p + 1):
        left[:, j] = u - knots[span + 1 - j]
        right[:, j] = knots[span + j] - u
        grown = np.zeros((m, j + 1))
        saved = np.zeros(m)
        for r in range(j):
            denominator = right[:, r + 1] + left[:, j - r]
            ratio = np.divide(basis[:, r], denominator, out=np.zeros(m), where=denominator != 0)
            grown[:, r] = saved + right[:, r + 1] * ratio
            saved = left[:, j - r] * ratio
        grown[:, j] = saved
        basis = grown
    return basis


def sample_nurbs(curve: Nurbs, tolerance: float = CHORD_TOLERANCE) -> tuple[tuple[float, float], ...]:
    """A polyline along ``curve`` from its start to its end whose chords stay within ``tolerance``.

    Every non-empty knot span starts as a few pieces; a piece whose curve, tested at every eighth of its
    parameter range, strays farther than half ``tolerance`` from its chord is halved,
    until none does. Repeated points, and points on the straight line between their neighbours, are
    dropped. A degree-1 curve is exactly the polyline through its control points (weights do not bend
    it), which is returned as it is, repeated points dropped.
    """
    if not (math.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"tolerance={tolerance!r} must be a positive number of metres")
    if curve.degree == 1:
        return _degree_one(curve)
    low, high = curve.domain
    breaks = np.unique(curve.knots[(curve.knots >= low) & (curve.knots <= high)])
    pieces = _START_PIECES_PER_DEGREE * curve.degree
    starts = (breaks[:-1, None] + (breaks[1:, None] - breaks[:-1, None]) * np.arange(pieces) / pieces).ravel()
    accepted: list[FloatArray] = []
    begin, end = starts, np.append(starts[1:], high)
    for _ in range(_MAX_REFINEMENTS):
        if len(begin) == 0:
            break
        ends_a, ends_b = curve.evaluate(begin), curve.evaluate(end)
        tests = begin[:, None] + (end - begin)[:, None] * _TEST_FRACTIONS
        probes = curve.evaluate(tests.ravel())
        k = len(_TEST_FRACTIONS)
        gaps = point_segment_distances(probes, np.repeat(ends_a, k, axis=0), np.repeat(ends_b, k, axis=0))
        bad = gaps.reshape(-1, k).max(axis=1) > tolerance * _PROBE_SHARE
        accepted.append(begin[~bad])
        middle = (begin[bad] + end[bad]) / 2.0
        begin, end = np.concatenate([begin[bad], middle]), np.concatenate([middle, end[bad]])
    else:  # pragma: no cover - only a pathological curve gets here
        accepted.append(begin)
    params = np.sort(np.concatenate([*accepted, [high]]))
    points = curve.evaluate(params)
    keep = np.ones(len(points), dtype=bool)
    keep[1:] = np.any(points[1:] != points[:-1], axis=1)
    points = points[keep]
    if len(points) > 2:
        # A point whose neighbours' chord passes through it adds nothing (1 µm: float noise).
        inner = point_segment_distances(points[1:-1], points[:-2], points[2:]) > 1e-6
        points = points[np.concatenate([[True], inner, [True]])]
    return tuple((float(x), float(y)) for x, y in points)


def _degree_one(curve: Nurbs) -> tuple[tuple[float, float], ...]:
    """The control points of a degree-1 curve that its domain reaches, repeated ones dropped."""
    low, high = curve.domain
    # Control point i is reached at knot i + 1; those whose knot lies outside the domain are not.
    reached = curve.evaluate(curve.knots[1:-1].clip(low, high))
    points = [reached[0]]
    for point in reached[1:]:
        if np.any(point != points[-1]):
            points.append(point)
    return tuple((float(x), float(y)) for x, y in points)
