"""Layout geometry that is valid by construction: pieces, and the three kinds of generated layouts.

Plain functions without Hypothesis, so benchmarks build the same lattices the strategies draw. Each
builder returns segments with ids 1.. in generation order, whose ends meet exactly where they should
connect; parallel lanes stay at least :data:`LANE_GAP` apart except where they meet, which keeps them
from conflicting for vehicles with a swept radius below ``LANE_GAP / 2`` (1.25 m).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from fleetsim.enums import Direction, Shape
from fleetsim.layout.segment import Point, Segment

__all__ = [
    "CURVE_POINTS",
    "GRID",
    "LANE_GAP",
    "SECTION",
    "SPACING",
    "arc",
    "corridor",
    "grid",
    "loop",
    "quantized",
    "s_curve",
    "warehouse",
]

SPACING = 6.0  # m between warehouse junction centres
SECTION = 4.0  # m: length of loop sides' and corridors' straights
LANE_GAP = 2.5  # m between a corridor and its passing bay
LOOP_SHIFT = 1.0  # m a loop's lane moves outward on a shifted stretch
CORNER_RADIUS = 2.0  # m, loop corners
CURVE_POINTS = 10  # waypoints per 90° curve, as the shipped Tiled template (>= 9, SPEC §3)
S_CURVE_POINTS = 13  # as the shipped s_curve template
# Waypoints are multiples of 2**-16 m: the map writer's pixel transform (x 32 px/m, plus half the map
# width) and the loader's inverse are then exact, so a saved scenario loads back to equal segments.
GRID = 2.0**-16

Vector = tuple[float, float]


def quantized(segments: Sequence[Segment]) -> list[Segment]:
    """``segments`` with every waypoint rounded to :data:`GRID`; ends that met still meet exactly."""
    return [
        Segment(
            s.id, s.shape, s.direction, tuple((round(x / GRID) * GRID, round(y / GRID) * GRID) for x, y in s.waypoints)
        )
        for s in segments
    ]


def arc(cx: float, cy: float, radius: float, start_deg: float, sweep_deg: float = 90.0) -> tuple[Point, ...]:
    """A circular arc about ``(cx, cy)``, counter-clockwise for a positive sweep."""
    angles = np.radians(start_deg + np.linspace(0.0, sweep_deg, CURVE_POINTS))
    return tuple((cx + radius * math.cos(a), cy + radius * math.sin(a)) for a in angles)


def s_curve(start: Point, along: Vector, side: Vector, length: float, lateral: float) -> tuple[Point, ...]:
    """A lane change: ``length`` along ``along`` while moving ``lateral`` towards ``side`` (unit vectors).

    The cosine profile leaves and arrives parallel to ``along``, so both ends join straights smoothly.
    """
    x0, y0 = start
    points = []
    for k in range(S_CURVE_POINTS):
        t = k / (S_CURVE_POINTS - 1)
        shift = lateral * (1.0 - math.cos(math.pi * t)) / 2.0
        points.append((x0 + along[0] * length * t + side[0] * shift, y0 + along[1] * length * t + side[1] * shift))
    return tuple(points)


class _Builder:
    """Collects segments, numbering them 1.. in the order they are added."""

    def __init__(self, direction: Direction = Direction.BOTH) -> None:
        self.direction = direction
        self.segments: list[Segment] = []

    def add(self, shape: Shape, points: tuple[Point, ...]) -> None:
        self.segments.append(Segment(len(self.segments) + 1, shape, self.direction, points))


def warehouse(junctions_per_side: int) -> list[Segment]:
    """A lattice: ``8 * junctions_per_side**2`` two-way segments, ids 1.. in generation order.

    Each junction has a horizontal and a vertical straight crossing it and four 90° curves (radius 1 m)
    joining its arms; long straights (*aisles*) lead east and north to the neighbouring junctions (dead
    ends on the lattice's east and north edges): 8 segments per junction, aisles 7th and 8th.
    """
    build = _Builder()
    r = 1.0
    for i in range(junctions_per_side):
        for j in range(junctions_per_side):
            x, y = i * SPACING, j * SPACING
            build.add(Shape.STRAIGHT, ((x - r, y), (x + r, y)))
            build.add(Shape.STRAIGHT, ((x, y - r), (x, y + r)))
            build.add(Shape.CURVE, arc(x + r, y + r, r, 180.0))  # each centred on a corner of the junction square
            build.add(Shape.CURVE, arc(x - r, y + r, r, 270.0))
            build.add(Shape.CURVE, arc(x - r, y - r, r, 0.0))
            build.add(Shape.CURVE, arc(x + r, y - r, r, 90.0))
            build.add(Shape.STRAIGHT, ((x + r, y), (x + SPACING - r, y)))
            build.add(Shape.STRAIGHT, ((x, y + r), (x, y + SPACING - r)))
    return build.segments


def grid(nodes_per_side: int, spacing: float = 2.0) -> list[Segment]:
    """A square grid of two-way straights joining neighbouring nodes ``spacing`` metres apart.

    Nodes sit at ``(i * spacing, j * spacing)``; the horizontal straights come first (row by row, west to
    east), then the vertical ones (column by column, south to north): ``2 * n * (n - 1)`` segments, ids 1..
    Every junction is a crossing of up to four straights, so only vehicles that turn in place drive it.
    """
    if nodes_per_side < 2:
        msg = f"nodes_per_side={nodes_per_side!r} must be >= 2"
        raise ValueError(msg)
    build = _Builder()
    n = nodes_per_side
    for j in range(n):
        for i in range(n - 1):
            build.add(Shape.STRAIGHT, ((i * spacing, j * spacing), ((i + 1) * spacing, j * spacing)))
    for i in range(n):
        for j in range(n - 1):
            build.add(Shape.STRAIGHT, ((i * spacing, j * spacing), (i * spacing, (j + 1) * spacing)))
    return build.segments


def loop(sections: int, *, one_way: bool = False, shift: tuple[int, int, int] | None = None) -> list[Segment]:
    """A ring: four sides of ``sections`` straights each, joined by 90° curves, centred on the origin.

    Segments run counter-clockwise (side by side, each followed by its corner), so a one-way loop is all
    ``forward``. ``shift = (side, first, last)`` moves sections ``first..last`` of a side (0 = bottom,
    then counter-clockwise) outward by ``LOOP_SHIFT``: an s-curve out over ``first``, straights, an
    s-curve back over ``last``; needs ``first < last``. Outward, the shifted lane nears nothing.
    """
    if shift is not None and not (0 <= shift[0] < 4 and 0 <= shift[1] < shift[2] < sections):
        msg = f"shift={shift!r} must be (side 0-3, first, last) with 0 <= first < last < sections={sections!r}"
        raise ValueError(msg)
    build = _Builder(Direction.FORWARD if one_way else Direction.BOTH)
    half = CORNER_RADIUS + sections * SECTION / 2  # from the centre to each side's lane
    x, y = -half + CORNER_RADIUS, -half  # start of the bottom side
    along: Vector = (1.0, 0.0)
    for side in range(4):
        outward: Vector = (along[1], -along[0])  # right of the direction of travel, counter-clockwise
        first, last = (shift[1], shift[2]) if shift is not None and shift[0] == side else (-1, -1)
        for q in range(sections):
            p = (x + along[0] * q * SECTION, y + along[1] * q * SECTION)
            if q == first:
                build.add(Shape.S_CURVE, s_curve(p, along, outward, SECTION, LOOP_SHIFT))
            elif q == last:
                out = (p[0] + outward[0] * LOOP_SHIFT, p[1] + outward[1] * LOOP_SHIFT)
                build.add(Shape.S_CURVE, s_curve(out, along, outward, SECTION, -LOOP_SHIFT))
            else:
                lane = LOOP_SHIFT if first < q < last else 0.0
                a = (p[0] + outward[0] * lane, p[1] + outward[1] * lane)
                b = (a[0] + along[0] * SECTION, a[1] + along[1] * SECTION)
                build.add(Shape.STRAIGHT, (a, b))
        x, y = x + along[0] * sections * SECTION, y + along[1] * sections * SECTION
        centre = (x - outward[0] * CORNER_RADIUS, y - outward[1] * CORNER_RADIUS)
        start_deg = math.degrees(math.atan2(outward[1], outward[0]))
        build.add(Shape.CURVE, arc(centre[0], centre[1], CORNER_RADIUS, start_deg))
        along = (-along[1], along[0])  # turn left; the next side starts where the corner ends
        x, y = centre[0] + along[1] * CORNER_RADIUS, centre[1] - along[0] * CORNER_RADIUS
    return build.segments


def corridor(between: int, bays: Sequence[tuple[int, int]]) -> list[Segment]:
    """A line of ``between + 2`` straights (two ends, ``between`` between them) with passing bays.

    ``bays`` holds ``(first, side)`` pairs: a bay runs beside straights ``first..first + 2`` on the left
    (side 1) or right (side -1), ``LANE_GAP`` away: an s-curve out, a straight, an s-curve back. Bays
    must not overlap; a bay may start or end at an end of the line, which then joins the bay with a cusp.
    """
    count = between + 2
    taken: set[int] = set()
    for first, side in bays:
        span = set(range(first, first + 3))
        if first < 0 or first + 3 > count or span & taken or side not in (1, -1):
            msg = f"bays={list(bays)!r} must be non-overlapping (first, side +-1) within {count} straights"
            raise ValueError(msg)
        taken |= span
    build = _Builder()
    x0 = -count * SECTION / 2
    for q in range(count):
        build.add(Shape.STRAIGHT, ((x0 + q * SECTION, 0.0), (x0 + (q + 1) * SECTION, 0.0)))
    along: Vector = (1.0, 0.0)
    for first, side in bays:
        start = x0 + first * SECTION
        lane = side * LANE_GAP
        build.add(Shape.S_CURVE, s_curve((start, 0.0), along, (0.0, 1.0), SECTION, lane))
        build.add(Shape.STRAIGHT, ((start + SECTION, lane), (start + 2 * SECTION, lane)))
        build.add(Shape.S_CURVE, s_curve((start + 2 * SECTION, lane), along, (0.0, 1.0), SECTION, -lane))
    return build.segments
