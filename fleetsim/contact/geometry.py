"""Vehicle footprints as oriented rectangles: the signed distance between two, and where it is taken.

A footprint is a rectangle centred on the vehicle's pose ``(x, y)``, its long side along the heading:
``half_length`` ahead and behind, ``half_width`` to either side (the type's length and width halved, plus
any safety margin), held as the tuple :data:`Footprint`.

:func:`signed_distance` judges a pair:

- apart, the exact distance between the two rectangles: the shortest distance from a corner of either
  to the other (for convex polygons the closest points lie on a corner of one of them), taken in the
  other's own frame, where it is how far the corner lies beyond the half length and beyond the half
  width; and the midpoint of that corner and its closest point;
- overlapping, minus the penetration depth: the least distance one rectangle must move to be clear of
  the other, the smallest overlap along the four axes of the separating-axis test (for rectangles the
  test's axes are their sides' normals, and the smallest overlap along them is the depth), and the
  midpoint of the two centres.

:func:`separation` is the separating-axis test alone, a lower bound of the distance and cheaper;
:func:`interpolate` gives the pose between two steps (centre along the straight line, heading along the
shorter turn, :func:`turn`).

These work on one pair at a time in plain Python on purpose. The broad phase of :mod:`.monitor` leaves
only a few pairs per step to judge, and there plain floating-point arithmetic is some hundred times
faster than array operations, whose fixed cost per call dwarfs the work on a handful of rows; on many
pairs it is still only about a microsecond each.
"""

from __future__ import annotations

import math

__all__ = ["Footprint", "interpolate", "separation", "signed_distance", "turn"]

Footprint = tuple[float, float, float, float, float]  # x, y, heading (radians), half length, half width

# A rectangle's corners as (along the length, along the width) multiples of its half sizes, in the order
# they are looked at; and those that can be its closest to another rectangle, keyed by the side of each
# axis beyond which the other lies wholly (1 or -1; 0: on neither, it overlaps that axis's span).
_CORNERS = ((1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0))
_FACING = {
    (u, v): tuple(c for c in _CORNERS if u in (0, c[0]) and v in (0, c[1])) for u in (-1, 0, 1) for v in (-1, 0, 1)
}


def turn(start: float, end: float) -> float:
    """The shorter turn (radians, -pi..pi) from heading ``start`` to ``end``."""
    return math.remainder(end - start, math.tau)


def _separations(
    a: Footprint, b: Footprint, ca: float, sa: float, cb: float, sb: float
) -> tuple[float, float, float, float]:
    """Along each one's length and width axis (a's two, then b's): the centres' offset less its own half
    size and the other's reach."""
    ax, ay, _, al, aw = a
    bx, by, _, bl, bw = b
    dx, dy = bx - ax, by - ay
    c, s = abs(ca * cb + sa * sb), abs(ca * sb - sa * cb)  # |cos|, |sin| of the angle between them
    return (
        abs(dx * ca + dy * sa) - al - bl * c - bw * s,
        abs(dy * ca - dx * sa) - aw - bl * s - bw * c,
        abs(dx * cb + dy * sb) - bl - al * c - aw * s,
        abs(dy * cb - dx * sb) - bw - al * s - aw * c,
    )


def separation(a: Footprint, b: Footprint) -> float:
    """The separating-axis test's separation: a lower bound of the distance between the rectangles when
    positive (it is the distance along the best of their side normals), minus the depth of their overlap
    when not. Cheaper than :func:`signed_distance`: no corners."""
    return max(_separations(a, b, math.cos(a[2]), math.sin(a[2]), math.cos(b[2]), math.sin(b[2])))


def _corner_to(cx: float, cy: float, owner: Footprint, oc: float, os: float) -> tuple[float, float, float]:
    """The squared distance from the point ``(cx, cy)`` to the rectangle ``owner`` (its heading's cosine
    and sine ``oc``, ``os``), and the midpoint of the point and its closest point on it."""
    ox, oy, _, ol, ow = owner
    rx, ry = cx - ox, cy - oy
    lx, ly = rx * oc + ry * os, ry * oc - rx * os  # the point in the owner's frame
    ex, ey = max(abs(lx) - ol, 0.0), max(abs(ly) - ow, 0.0)
    qx, qy = min(max(lx, -ol), ol), min(max(ly, -ow), ow)  # its closest point on the owner
    return ex * ex + ey * ey, 0.5 * (cx + ox + qx * oc - qy * os), 0.5 * (cy + oy + qx * os + qy * oc)


def signed_distance(a: Footprint, b: Footprint, beyond: float = math.inf) -> tuple[float, float, float]:
    """The distance between the rectangles (negative: minus the depth of their overlap) and where it is
    taken: ``(distance, x, y)``. Farther apart than ``beyond``, a lower bound of the distance (the
    separating-axis separation, :func:`separation`) and no place (NaN) are enough."""
    ca, sa, cb, sb = math.cos(a[2]), math.sin(a[2]), math.cos(b[2]), math.sin(b[2])
    along = _separations(a, b, ca, sa, cb, sb)
    apart = max(along)
    if apart <= 0.0:
        return apart, 0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])
    if apart > beyond:
        return apart, math.nan, math.nan
    # Mostly the closest points are a corner and the side whose normal separates best: the other's corner
    # deepest towards that side. If that corner lies as far from the side's rectangle as the separation,
    # a lower bound, that is the distance.
    axis = along.index(apart)
    owner, other, oc, os, tc, ts = (a, b, ca, sa, cb, sb) if axis < 2 else (b, a, cb, sb, ca, sa)
    nx, ny = (oc, os) if axis % 2 == 0 else (-os, oc)  # the side's normal ...
    if nx * (other[0] - owner[0]) + ny * (other[1] - owner[1]) < 0.0:  # ... pointing at the other
        nx, ny = -nx, -ny
    length = other[3] if nx * tc + ny * ts < 0.0 else -other[3]  # the other's corner deepest along -normal
    width = other[4] if ny * tc - nx * ts < 0.0 else -other[4]
    squared, at_x, at_y = _corner_to(
        other[0] + length * tc - width * ts, other[1] + length * ts + width * tc, owner, oc, os
    )
    if squared <= apart * apart * (1.0 + 1e-12):
        return math.sqrt(squared), at_x, at_y
    # Else corner to corner, or a corner beyond the side's ends: the closest of the corners to the other
    # rectangle (for convex polygons the closest points lie on a corner of one of them). Where the other
    # lies wholly beyond one of a rectangle's sides (its separation along that side's normal positive),
    # the rectangle's closest points lie on that side: only its corners there need looking at (the
    # others are farther by the rectangle's whole length or width).
    dx, dy = b[0] - a[0], b[1] - a[1]
    a_corners = _FACING[
        (0 if along[0] <= 0.0 else 1 if dx * ca + dy * sa > 0.0 else -1),
        (0 if along[1] <= 0.0 else 1 if dy * ca - dx * sa > 0.0 else -1),
    ]
    b_corners = _FACING[
        (0 if along[2] <= 0.0 else 1 if dx * cb + dy * sb < 0.0 else -1),
        (0 if along[3] <= 0.0 else 1 if dy * cb - dx * sb < 0.0 else -1),
    ]
    best = math.inf
    for (x, y, _, length, width), co, si, (ox, oy, _, ol, ow), oc, os, corners in (
        (a, ca, sa, b, cb, sb, a_corners),  # a's corners against b
        (b, cb, sb, a, ca, sa, b_corners),  # b's against a
    ):
        lc, ls, wc, ws = length * co, length * si, width * co, width * si
        for u, v in corners:
            cx, cy = x + u * lc - v * ws, y + u * ls + v * wc
            rx, ry = cx - ox, cy - oy
            lx, ly = rx * oc + ry * os, ry * oc - rx * os  # the corner in the other's frame
            ex, ey = max(abs(lx) - ol, 0.0), max(abs(ly) - ow, 0.0)
            squared = ex * ex + ey * ey
            if squared < best:
                qx, qy = min(max(lx, -ol), ol), min(max(ly, -ow), ow)  # its closest point on the other
                best = squared
                at_x = 0.5 * (cx + ox + qx * oc - qy * os)
                at_y = 0.5 * (cy + oy + qx * os + qy * oc)
    return math.sqrt(best), at_x, at_y


def interpolate(start: Footprint, end: Footprint, tau: float) -> Footprint:
    """The footprint a fraction ``tau`` (0..1) of the way from ``start`` to ``end``."""
    x, y, heading, length, width = start
    return (x + tau * (end[0] - x), y + tau * (end[1] - y), heading + tau * turn(heading, end[2]), length, width)
