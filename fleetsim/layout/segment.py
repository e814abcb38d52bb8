"""A segment: one piece of the driving map (SPEC §2)."""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass, field
from itertools import pairwise

from fleetsim.enums import Direction, Shape, Traverse

__all__ = ["Point", "Segment", "polyline_length"]

Point = tuple[float, float]


def polyline_length(waypoints: tuple[Point, ...]) -> float:
    """Sum of the straight pieces between consecutive waypoints, in metres."""
    return math.fsum(math.dist(a, b) for a, b in pairwise(waypoints))


@dataclass(frozen=True, slots=True)
class Segment:
    """An immutable segment: Tiled object id, world waypoints in metres, shape and allowed direction.

    Attributes:
        id: The segment's id (a Tiled object's id; assigned in file order for LIF and RMF sites).
        shape: ``STRAIGHT``, ``CURVE``, ``S_CURVE`` or ``PATH`` (any polyline).
        direction: Which traverses are allowed: ``FORWARD`` (along the waypoints only), ``BACKWARD``
            (against them only) or ``BOTH``.
        waypoints: The polyline in metres, map frame (y up), first to last.
        names: What the site calls it (a Tiled object's name, a LIF edge id, an RMF lane's waypoints): the
            first is its name, a second one the id of the opposite LIF edge merged into a two-way segment.
            ``vehicles.csv`` and ``tasks.csv`` may name a segment by any of them.
        ends: What the site calls the places at its first and last waypoint, when it names them (a LIF
            edge's start and end node ids, an RMF lane's vertices); VDA 5050 orders use them as node ids.
        length: Metres along the polyline.
    """

    id: int
    shape: Shape
    direction: Direction
    waypoints: tuple[Point, ...]
    names: tuple[str, ...] = ()
    ends: tuple[str, str] | None = field(default=None, compare=False)
    length: float = field(init=False, compare=False)
    # Distance along the polyline at each waypoint, for locating a point by its distance.
    _along: tuple[float, ...] = field(init=False, compare=False, repr=False)

    def __post_init__(self) -> None:
        if len(self.waypoints) < 2:
            msg = f"segment {self.id} needs at least 2 waypoints, got {len(self.waypoints)}"
            raise ValueError(msg)
        along = [0.0]
        for a, b in pairwise(self.waypoints):
            along.append(along[-1] + math.dist(a, b))
        object.__setattr__(self, "_along", tuple(along))
        object.__setattr__(self, "length", polyline_length(self.waypoints))

    def pose_at(self, distance: float, traverse: Traverse) -> tuple[float, float, float]:
        """``(x, y, travel heading)`` after driving ``distance`` metres along the segment with ``traverse``.

        The heading (radians, counter-clockwise from +x) is the direction of travel on the piece the point
        lies on; a vehicle backing faces the other way. ``distance`` is clamped to ``[0, length]``.
        """
        along = min(max(distance, 0.0), self.length)
        if traverse is Traverse.BACKWARD:
            along = self.length - along
        # The piece holding the point; zero-length pieces are skipped by bisect on the running distance.
        index = min(max(bisect_right(self._along, along) - 1, 0), len(self.waypoints) - 2)
        while index > 0 and self._along[index + 1] == self._along[index]:
            index -= 1
        (ax, ay), (bx, by) = self.waypoints[index], self.waypoints[index + 1]
        piece = self._along[index + 1] - self._along[index]
        t = (along - self._along[index]) / piece if piece > 0 else 0.0
        heading = math.atan2(by - ay, bx - ax)
        if traverse is Traverse.BACKWARD:
            heading = math.atan2(ay - by, ax - bx)
        return ax + t * (bx - ax), ay + t * (by - ay), heading

    @property
    def name(self) -> str | None:
        """The segment's name in the site's own files, or ``None``."""
        return self.names[0] if self.names else None

    @property
    def along(self) -> tuple[float, ...]:
        """Metres along the polyline at each waypoint (0 first, ``length`` last up to rounding)."""
        return self._along

    @property
    def first(self) -> Point:
        """``(x, y)`` in metres: the first waypoint, where a ``FORWARD`` traverse enters."""
        return self.waypoints[0]

    @property
    def last(self) -> Point:
        """``(x, y)`` in metres: the last waypoint, where a ``FORWARD`` traverse leaves."""
        return self.waypoints[-1]

    def entry(self, traverse: Traverse) -> Point:
        """``(x, y)`` in metres: where a vehicle driving ``traverse`` enters this segment."""
        return self.first if traverse is Traverse.FORWARD else self.last

    def exit(self, traverse: Traverse) -> Point:
        """``(x, y)`` in metres: where a vehicle driving ``traverse`` leaves this segment."""
        return self.last if traverse is Traverse.FORWARD else self.first

    def allows(self, traverse: Traverse) -> bool:
        """Whether ``direction`` lets a leg drive this segment with ``traverse`` (else check code ``wrong-way``)."""
        return self.direction.allows(traverse)
