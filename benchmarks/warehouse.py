"""Generated warehouse-like layouts for benchmarks: a lattice of junctions joined by straights.

Each junction has a horizontal and a vertical straight crossing it and four 90° curves (10 waypoints,
radius 1 m) joining its arms; long straights join neighbouring junctions: 8 segments per junction.
"""

from __future__ import annotations

import math

import numpy as np

from fleetsim.enums import Direction, Shape
from fleetsim.layout.segment import Point, Segment

__all__ = ["warehouse", "warehouse_with_at_least"]

SPACING = 6.0  # m between junction centres
CURVE_RADIUS = 1.0
CURVE_POINTS = 10


def _arc(cx: float, cy: float, start_deg: float) -> tuple[Point, ...]:
    angles = np.radians(start_deg + np.linspace(0.0, 90.0, CURVE_POINTS))
    return tuple((cx + CURVE_RADIUS * math.cos(a), cy + CURVE_RADIUS * math.sin(a)) for a in angles)


def warehouse(junctions_per_side: int) -> list[Segment]:
    """``8 * junctions_per_side**2`` two-way segments, ids 1.. in generation order."""
    segments: list[Segment] = []

    def add(shape: Shape, points: tuple[Point, ...]) -> None:
        segments.append(Segment(len(segments) + 1, shape, Direction.BOTH, points))

    r = CURVE_RADIUS
    for i in range(junctions_per_side):
        for j in range(junctions_per_side):
            x, y = i * SPACING, j * SPACING
            add(Shape.STRAIGHT, ((x - r, y), (x + r, y)))
            add(Shape.STRAIGHT, ((x, y - r), (x, y + r)))
            add(Shape.CURVE, _arc(x + r, y + r, 180.0))  # each centred on a corner of the junction square
            add(Shape.CURVE, _arc(x - r, y + r, 270.0))
            add(Shape.CURVE, _arc(x - r, y - r, 0.0))
            add(Shape.CURVE, _arc(x + r, y - r, 90.0))
            add(Shape.STRAIGHT, ((x + r, y), (x + SPACING - r, y)))
            add(Shape.STRAIGHT, ((x, y + r), (x, y + SPACING - r)))
    return segments


def warehouse_with_at_least(segment_count: int) -> list[Segment]:
    return warehouse(max(1, math.ceil(math.sqrt(segment_count / 8))))
