"""Draft benchmark: conflict sets on a ~10,000-segment warehouse grid, broad phase vs all pairs.

Usage: python benchmarks/conflicts_layout_draft.py [--segments N] [--radius R] [--all-pairs full|sample|skip]

The map is a lattice of junctions 6 m apart. Each junction has a horizontal and a vertical straight
crossing it and four 90° curves (10 waypoints, radius 1 m) joining its arms; long straights join
neighbouring junctions: 8 segments per junction. ``--all-pairs sample`` times the reference on a slice of
rows and extrapolates by pair count (the reference's cost is proportional to it); ``full`` runs it all.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from typing import TypeVar

import numpy as np

from fleetsim.enums import Direction, Shape
from fleetsim.layout import Segment, build_layout
from fleetsim.layout.conflicts import SubSegments, all_pairs_conflicts, polyline_distances, swept_conflicts
from fleetsim.layout.geometry import ragged_arange

T = TypeVar("T")

SPACING = 6.0
CURVE_RADIUS = 1.0
CURVE_POINTS = 10


def _arc(cx: float, cy: float, start_deg: float) -> tuple[tuple[float, float], ...]:
    angles = np.radians(start_deg + np.linspace(0.0, 90.0, CURVE_POINTS))
    return tuple((cx + CURVE_RADIUS * math.cos(a), cy + CURVE_RADIUS * math.sin(a)) for a in angles)


def warehouse(junctions_per_side: int) -> list[Segment]:
    segments: list[Segment] = []

    def add(shape: Shape, points: tuple[tuple[float, float], ...]) -> None:
        segments.append(Segment(len(segments) + 1, shape, Direction.BOTH, points))

    r = CURVE_RADIUS
    for i in range(junctions_per_side):
        for j in range(junctions_per_side):
            x, y = i * SPACING, j * SPACING
            add(Shape.STRAIGHT, ((x - r, y), (x + r, y)))
            add(Shape.STRAIGHT, ((x, y - r), (x, y + r)))
            add(Shape.CURVE, _arc(x + r, y + r, 180.0))  # centred on a corner of the junction square
            add(Shape.CURVE, _arc(x - r, y + r, 270.0))
            add(Shape.CURVE, _arc(x - r, y - r, 0.0))
            add(Shape.CURVE, _arc(x + r, y - r, 90.0))
            add(Shape.STRAIGHT, ((x + r, y), (x + SPACING - r, y)))
            add(Shape.STRAIGHT, ((x, y + r), (x, y + SPACING - r)))
    return segments


def _time(label: str, fn: Callable[[], T]) -> tuple[T, float]:
    start = time.perf_counter()
    result = fn()
    elapsed = time.perf_counter() - start
    print(f"{label:<40} {elapsed:8.3f} s")
    return result, elapsed


def _sampled_all_pairs(segments: list[Segment], threshold: float, rows: int) -> float:
    """Seconds the reference would take, extrapolated from ``rows`` evenly spread rows of the pair matrix."""
    subs = SubSegments.of(segments)
    n = len(segments)
    picked = np.linspace(0, n - 2, rows).astype(np.int64)
    later = n - picked - 1
    a = np.repeat(picked, later)
    b = a + 1 + ragged_arange(later)
    start = time.perf_counter()
    polyline_distances(subs, a, b)
    elapsed = time.perf_counter() - start
    return elapsed * (n * (n - 1) / 2) / len(a)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--segments", type=int, default=10_000)
    parser.add_argument("--radius", type=float, default=0.5 * math.hypot(1.0, 0.6))
    parser.add_argument("--all-pairs", choices=["full", "sample", "skip"], default="sample")
    args = parser.parse_args()
    side = max(1, math.ceil(math.sqrt(args.segments / 8)))
    segments = warehouse(side)
    pieces = sum(len(s.waypoints) - 1 for s in segments)
    print(f"{len(segments)} segments, {pieces} straight pieces, vehicle radius {args.radius:.3f} m")
    threshold, touch = 2.0 * args.radius, 0.05
    fast, t_fast = _time("swept_conflicts (grid broad phase)", lambda: swept_conflicts(segments, threshold, touch))
    layout, _ = _time("build_layout (all of it)", lambda: build_layout(segments, vehicle_radius=args.radius))
    _time("Layout.lint", layout.lint)
    sizes = [len(v) for v in fast.values()]
    print(f"conflict set size: mean {np.mean(sizes):.1f}, max {max(sizes)}")
    if args.all_pairs == "full":
        ref, t_ref = _time("all_pairs_conflicts", lambda: all_pairs_conflicts(segments, threshold, touch=touch))
        assert ref == fast, "broad phase disagrees with the all-pairs reference"
    elif args.all_pairs == "sample":
        t_ref = _sampled_all_pairs(segments, threshold, rows=40)
        print(f"{'all_pairs_conflicts (extrapolated)':<40} {t_ref:8.3f} s")
    else:
        return
    print(f"all pairs / broad phase: {t_ref / t_fast:.0f}x")


if __name__ == "__main__":
    main()
