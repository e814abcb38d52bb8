"""Vehicle footprints as oriented rectangles, many pairs at once: signed distance and where it is taken.

A footprint is a rectangle centred on the vehicle's pose ``(x, y)``, its long side along the heading:
``half_length`` ahead and behind, ``half_width`` to either side (the type's length and width halved, plus
any safety margin). :func:`signed_distance` judges pairs of them in arrays:

- apart, the exact distance between the two rectangles: the shortest of the sixteen distances from a
  corner of one to a side of the other, both ways round (for convex polygons the closest points lie on a
  corner of one of them), and the midpoint of those closest points;
- overlapping, minus the penetration depth: the least distance one rectangle must move to be clear of
  the other, the smallest overlap along the four axes of the separating-axis test (for rectangles the
  test's axes are their sides' normals, and the smallest overlap along them is the depth), and the
  midpoint of the two centres.

:func:`interpolate` gives the poses between two steps (centre along the straight line, heading along
the shorter turn), and :func:`motion_bound` how fast, in metres per unit of that interpolation, the
distance between two footprints can change at most: the conservative advancement of :mod:`.monitor`
rests on it.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import numpy.typing as npt

__all__ = ["Boxes", "interpolate", "motion_bound", "separation", "signed_distance"]

Floats = npt.NDArray[np.float64]


class Boxes(NamedTuple):
    """Oriented rectangles, one per row: centre, heading (radians) and half sizes (metres)."""

    x: Floats
    y: Floats
    heading: Floats
    half_length: Floats
    half_width: Floats

    def take(self, rows: npt.NDArray[np.intp]) -> Boxes:
        return Boxes(*(column[rows] for column in self))


def _corners(boxes: Boxes, cos: Floats, sin: Floats) -> Floats:
    """(n, 4, 2): the corners in order round the rectangle."""
    signs_l = np.array([1.0, -1.0, -1.0, 1.0])
    signs_w = np.array([1.0, 1.0, -1.0, -1.0])
    along = boxes.half_length[:, None] * signs_l
    across = boxes.half_width[:, None] * signs_w
    xs = boxes.x[:, None] + along * cos[:, None] - across * sin[:, None]
    ys = boxes.y[:, None] + along * sin[:, None] + across * cos[:, None]
    return np.stack((xs, ys), axis=-1)


def _corner_to_sides(points: Floats, corners: Floats) -> tuple[Floats, Floats]:
    """For each pair: the least distance from a point of ``points`` (p, 4, 2) to a side of the rectangle
    with ``corners`` (p, 4, 2), and the midpoint of that point and its closest point on the side."""
    start = corners[:, None, :, :]  # (p, 1, 4, 2): each side from corner k to corner k + 1
    side = np.roll(corners, -1, axis=1)[:, None, :, :] - start
    offset = points[:, :, None, :] - start  # (p, 4 points, 4 sides, 2)
    length2 = np.einsum("pqsk,pqsk->pqs", side, side)
    t = np.clip(np.einsum("pqsk,pqsk->pqs", offset, side) / np.maximum(length2, 1e-300), 0.0, 1.0)
    nearest = start + t[..., None] * side
    gap = points[:, :, None, :] - nearest
    distance = np.sqrt(np.einsum("pqsk,pqsk->pqs", gap, gap)).reshape(len(points), 16)
    best = np.argmin(distance, axis=1)
    rows = np.arange(len(points))
    closest = nearest.reshape(len(points), 16, 2)[rows, best]
    point = points[rows, best // 4]
    return distance[rows, best], 0.5 * (closest + point)


def _separation(a: Boxes, b: Boxes, cos_a: Floats, sin_a: Floats, cos_b: Floats, sin_b: Floats) -> Floats:
    """The separating-axis test on the four side normals: the largest separation (negative: the overlap)."""
    dx, dy = b.x - a.x, b.y - a.y
    separation = np.full(len(a.x), -np.inf)
    for ux, uy in ((cos_a, sin_a), (-sin_a, cos_a), (cos_b, sin_b), (-sin_b, cos_b)):
        reach_a = a.half_length * np.abs(cos_a * ux + sin_a * uy) + a.half_width * np.abs(-sin_a * ux + cos_a * uy)
        reach_b = b.half_length * np.abs(cos_b * ux + sin_b * uy) + b.half_width * np.abs(-sin_b * ux + cos_b * uy)
        np.maximum(separation, np.abs(dx * ux + dy * uy) - reach_a - reach_b, out=separation)
    return separation


def separation(a: Boxes, b: Boxes) -> Floats:
    """For each pair: the separating-axis test's separation, a lower bound of the distance between the
    rectangles when positive (it is the distance along the best of their side normals), minus the depth
    of their overlap when not. Cheaper than :func:`signed_distance`: no corners."""
    return _separation(a, b, np.cos(a.heading), np.sin(a.heading), np.cos(b.heading), np.sin(b.heading))


def signed_distance(a: Boxes, b: Boxes) -> tuple[Floats, Floats]:
    """For each pair ``(a[i], b[i])``: the distance between the rectangles (negative: minus the depth of
    their overlap) and where it is taken, (p, 2)."""
    count = len(a.x)
    if count == 0:
        return np.zeros(0), np.zeros((0, 2))
    cos_a, sin_a, cos_b, sin_b = np.cos(a.heading), np.sin(a.heading), np.cos(b.heading), np.sin(b.heading)
    separation = _separation(a, b, cos_a, sin_a, cos_b, sin_b)
    distance = separation.copy()
    where = np.stack((0.5 * (a.x + b.x), 0.5 * (a.y + b.y)), axis=-1)
    apart = np.flatnonzero(separation > 0.0)
    if len(apart):
        ca = _corners(a.take(apart), cos_a[apart], sin_a[apart])
        cb = _corners(b.take(apart), cos_b[apart], sin_b[apart])
        d_ab, at_ab = _corner_to_sides(ca, cb)
        d_ba, at_ba = _corner_to_sides(cb, ca)
        first = d_ab <= d_ba
        distance[apart] = np.where(first, d_ab, d_ba)
        where[apart] = np.where(first[:, None], at_ab, at_ba)
    return distance, where


def interpolate(start: Boxes, end: Boxes, tau: Floats) -> Boxes:
    """The poses a fraction ``tau`` (per row, 0..1) of the way from ``start`` to ``end``."""
    turn = np.remainder(end.heading - start.heading + np.pi, 2.0 * np.pi) - np.pi
    return Boxes(
        start.x + tau * (end.x - start.x),
        start.y + tau * (end.y - start.y),
        start.heading + tau * turn,
        start.half_length,
        start.half_width,
    )


def motion_bound(a0: Boxes, a1: Boxes, b0: Boxes, b1: Boxes) -> Floats:
    """The most the distance between ``a`` and ``b`` can change per unit of the interpolation parameter:
    their centres' relative displacement plus each one's turn times its half diagonal (the farthest any
    point of it lies from its centre)."""
    turn_a = np.abs(np.remainder(a1.heading - a0.heading + np.pi, 2.0 * np.pi) - np.pi)
    turn_b = np.abs(np.remainder(b1.heading - b0.heading + np.pi, 2.0 * np.pi) - np.pi)
    relative = np.hypot((a1.x - a0.x) - (b1.x - b0.x), (a1.y - a0.y) - (b1.y - b0.y))
    bound: Floats = relative + turn_a * np.hypot(a0.half_length, a0.half_width)
    bound += turn_b * np.hypot(b0.half_length, b0.half_width)
    return bound
