"""Plane geometry the layout needs, vectorised with numpy.

Two kinds of tool live here: exact distances (segment to segment, batched over many pairs) and a
uniform-grid broad phase that finds every pair of overlapping axis-aligned boxes without comparing all
pairs. Both are free of layout vocabulary so they can be tested on their own.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

__all__ = [
    "FloatArray",
    "IntArray",
    "away_direction",
    "close_point_pairs",
    "expanded_boxes",
    "overlapping_box_pairs",
    "point_segment_distances",
    "ragged_arange",
    "segment_distances",
]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

# Broad-phase boxes are padded by this much so that pairs exactly at the reach are not lost to rounding.
_PAD = 1e-9
# The grid keeps at most this many cell entries per box on average; coarser cells beyond that.
_MAX_ENTRIES_PER_BOX = 16
# Cells never get finer than extent / 2**20, so cell keys stay far below int64 overflow.
_MAX_CELLS_PER_AXIS = 2**20


def _squared_to_segment(
    px: FloatArray,
    py: FloatArray,
    sx: FloatArray,
    sy: FloatArray,
    dx: FloatArray,
    dy: FloatArray,
    inv: FloatArray,
) -> FloatArray:
    """Squared distance from points to segments ``s + t·d``; ``inv`` is 1/|d|², or 0 for a zero-length one.

    A zero ``inv`` pins the parameter to 0, so a zero-length segment is measured as its point.
    """
    t = np.clip(((px - sx) * dx + (py - sy) * dy) * inv, 0.0, 1.0)
    ex = sx + t * dx - px
    ey = sy + t * dy - py
    return ex * ex + ey * ey


def _inverse_squared_length(dx: FloatArray, dy: FloatArray) -> FloatArray:
    length2 = dx * dx + dy * dy
    # Below the smallest normal float, 1/length² overflows to inf and 0·inf gives NaN: treat such a
    # piece as the point it practically is.
    return np.divide(1.0, length2, out=np.zeros_like(length2), where=length2 > np.finfo(np.float64).tiny)


def point_segment_distances(p: FloatArray, s0: FloatArray, s1: FloatArray) -> FloatArray:
    """Distance from each point ``p[k]`` to the closed segment ``s0[k]``–``s1[k]`` (arrays (k, 2))."""
    dx, dy = s1[:, 0] - s0[:, 0], s1[:, 1] - s0[:, 1]
    inv = _inverse_squared_length(dx, dy)
    return np.sqrt(_squared_to_segment(p[:, 0], p[:, 1], s0[:, 0], s0[:, 1], dx, dy, inv))


def segment_distances(a0: FloatArray, a1: FloatArray, b0: FloatArray, b1: FloatArray) -> FloatArray:
    """Exact distance between segments ``a0[k]a1[k]`` and ``b0[k]b1[k]``; 0 where they cross.

    If two segments do not cross, their distance is attained at an endpoint of one of them, so it is the
    least of four point–segment distances. That also covers zero-length, parallel and collinear pieces
    (collinear overlap puts an endpoint on the other piece). Only a proper crossing needs its own test.
    """
    ax, ay, bx, by = a0[:, 0], a0[:, 1], b0[:, 0], b0[:, 1]
    adx, ady = a1[:, 0] - ax, a1[:, 1] - ay
    bdx, bdy = b1[:, 0] - bx, b1[:, 1] - by
    a_inv, b_inv = _inverse_squared_length(adx, ady), _inverse_squared_length(bdx, bdy)
    nearest = np.minimum(
        np.minimum(
            _squared_to_segment(ax, ay, bx, by, bdx, bdy, b_inv),
            _squared_to_segment(a1[:, 0], a1[:, 1], bx, by, bdx, bdy, b_inv),
        ),
        np.minimum(
            _squared_to_segment(bx, by, ax, ay, adx, ady, a_inv),
            _squared_to_segment(b1[:, 0], b1[:, 1], ax, ay, adx, ady, a_inv),
        ),
    )
    # Orientation of each endpoint relative to the other segment's line; opposite signs on both = crossing.
    o1 = adx * (by - ay) - ady * (bx - ax)
    o2 = adx * (b1[:, 1] - ay) - ady * (b1[:, 0] - ax)
    o3 = bdx * (ay - by) - bdy * (ax - bx)
    o4 = bdx * (a1[:, 1] - by) - bdy * (a1[:, 0] - bx)
    crossing = (o1 * o2 < 0.0) & (o3 * o4 < 0.0)
    return np.where(crossing, 0.0, np.sqrt(nearest))


def _cell_ranges(boxes: FloatArray, origin: FloatArray, cell: float) -> tuple[IntArray, IntArray]:
    """The lowest and highest grid cell (column, row) each box covers."""
    lo = np.floor((boxes[:, :2] - origin) / cell).astype(np.int64)
    hi = np.floor((boxes[:, 2:] - origin) / cell).astype(np.int64)
    return lo, hi


def _grid(boxes: FloatArray) -> tuple[IntArray, IntArray]:
    """Cell ranges on a grid whose cell is about a typical box, coarsened until the grid stays small."""
    origin = boxes[:, :2].min(axis=0)
    sizes = np.maximum(boxes[:, 2] - boxes[:, 0], boxes[:, 3] - boxes[:, 1])
    extent = float(np.max(boxes[:, 2:].max(axis=0) - origin))
    cell = max(float(np.median(sizes)), extent / _MAX_CELLS_PER_AXIS)
    if cell <= 0.0:
        cell = 1.0  # every box is the same point: any cell will do
    budget = _MAX_ENTRIES_PER_BOX * len(boxes)
    while True:
        lo, hi = _cell_ranges(boxes, origin, cell)
        if int(np.sum((hi - lo + 1).prod(axis=1))) <= budget:
            return lo, hi
        cell *= 2.0


def ragged_arange(counts: IntArray) -> IntArray:
    """``concatenate([arange(c) for c in counts])`` without a Python loop."""
    total = int(counts.sum())
    starts = np.cumsum(counts) - counts
    return np.arange(total, dtype=np.int64) - np.repeat(starts, counts)


def overlapping_box_pairs(boxes: FloatArray) -> IntArray:
    """Every pair ``(i, j)``, ``i < j``, of closed boxes ``(xmin, ymin, xmax, ymax)`` that overlap.

    Uniform grid: each box is entered in every cell it covers; boxes sharing a cell are candidates. A pair
    is reported only from the cell holding the lower-left corner of the boxes' intersection, so it is
    found once without a dedup pass. Rows come in a deterministic order, not sorted.
    """
    n = len(boxes)
    if n < 2:
        return np.empty((0, 2), dtype=np.int64)
    lo, hi = _grid(boxes)
    height = int(hi[:, 1].max()) + 1
    spans_y = hi[:, 1] - lo[:, 1] + 1
    counts = (hi[:, 0] - lo[:, 0] + 1) * spans_y
    owner = np.repeat(np.arange(n, dtype=np.int64), counts)
    offset = ragged_arange(counts)
    cx = lo[owner, 0] + offset // spans_y[owner]
    cy = lo[owner, 1] + offset % spans_y[owner]
    order = np.argsort(cx * height + cy, kind="stable")
    cx, cy, owner = cx[order], cy[order], owner[order]
    keys = cx * height + cy
    group_end = np.searchsorted(keys, keys, side="right")
    partners = group_end - np.arange(len(keys)) - 1
    first = np.repeat(np.arange(len(keys), dtype=np.int64), partners)
    second = first + 1 + ragged_arange(partners)
    i, j = owner[first], owner[second]
    # The intersection's lower-left corner lies in cell (max of the two lo cells): integer-only test.
    home = (np.maximum(lo[i, 0], lo[j, 0]) == cx[first]) & (np.maximum(lo[i, 1], lo[j, 1]) == cy[first])
    i, j = i[home], j[home]
    a, b = boxes[i], boxes[j]
    overlap = (a[:, 0] <= b[:, 2]) & (b[:, 0] <= a[:, 2]) & (a[:, 1] <= b[:, 3]) & (b[:, 1] <= a[:, 3])
    return np.stack([np.minimum(i, j)[overlap], np.maximum(i, j)[overlap]], axis=1)


def expanded_boxes(lo: FloatArray, hi: FloatArray, grow: float) -> FloatArray:
    """Boxes ``(xmin, ymin, xmax, ymax)`` from corners, grown per side by ``grow`` plus a rounding pad."""
    pad = grow + _PAD
    return np.concatenate([lo - pad, hi + pad], axis=1)


def close_point_pairs(points: FloatArray, radius: float) -> tuple[IntArray, FloatArray]:
    """Pairs ``(i, j)``, ``i < j``, of points at most ``radius`` apart, sorted, with their distances.

    Points become boxes of side ``radius`` (so the grid cell is the radius: a hash grid), then the exact
    distance decides.
    """
    pairs = overlapping_box_pairs(expanded_boxes(points, points, radius / 2.0))
    pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    gaps = np.hypot(*(points[pairs[:, 0]] - points[pairs[:, 1]]).T)
    keep = gaps <= radius
    return pairs[keep], gaps[keep]


def away_direction(waypoints: Sequence[tuple[float, float]], at_last: bool, skip: float) -> tuple[float, float] | None:
    """Unit vector from one end of a polyline towards its nearest other waypoint along the line.

    Waypoints within ``skip`` of the end are passed over (they give a noisy direction); if every waypoint
    is that close, the farthest one is used; ``None`` when all coincide with the end.
    """
    ordered = list(reversed(waypoints)) if at_last else list(waypoints)
    ex, ey = ordered[0]
    farthest: tuple[float, float, float] | None = None
    for x, y in ordered[1:]:
        gap = math.hypot(x - ex, y - ey)
        if gap > skip:
            return ((x - ex) / gap, (y - ey) / gap)
        if gap > 0.0 and (farthest is None or gap > farthest[2]):
            farthest = (x - ex, y - ey, gap)
    if farthest is None:
        return None
    return (farthest[0] / farthest[2], farthest[1] / farthest[2])
