"""Where a vehicle is on a segment driven one way, laid out once for the motion's every step: the pieces
between a segment's waypoints (:class:`Track`) and the headings where segments start and end
(:class:`HeadingTable`), one table per layout shared by the drivers."""

from __future__ import annotations

import math
from typing import NamedTuple

from fleetsim.enums import Progress, Traverse
from fleetsim.layout.layout import Layout
from fleetsim.layout.segment import Segment
from fleetsim.planning.plans import FleetLeg

__all__ = ["HeadingTable", "Track", "nose", "wrap"]


def wrap(angle: float) -> float:
    """An angle in (-π, π]."""
    return math.remainder(angle, math.tau)


def nose(travel_heading: float, progress: Progress) -> float:
    return wrap(travel_heading + (math.pi if progress is Progress.REVERSE else 0.0))


class Track(NamedTuple):
    """One segment driven one way, laid out for locating a point by distance on every step.

    The pieces' headings and :meth:`Segment.pose_at`'s bisection fix-ups are computed once, so
    :meth:`Driver.cruise` locates a point with the same arithmetic at a fraction of the cost.
    """

    length: float
    backward: bool
    along: tuple[float, ...]  # the segment's running distance at each waypoint
    piece_of: tuple[int, ...]  # bisect_right(along, d) → the index of the piece holding d
    # Per piece: (running distance at its start, ax, ay, bx − ax, by − ay, its length, travel heading,
    # where the nose points driving forward on it, where it points backing).
    pieces: tuple[tuple[float, float, float, float, float, float, float, float, float], ...]

    @classmethod
    def of(cls, segment: Segment, traverse: Traverse) -> Track:
        along = segment.along
        last = len(segment.waypoints) - 2
        piece_of = []
        for found in range(len(along) + 1):
            index = min(max(found - 1, 0), last)
            while index > 0 and along[index + 1] == along[index]:
                index -= 1
            piece_of.append(index)
        backward = traverse is Traverse.BACKWARD
        pieces = []
        for index in range(last + 1):
            (ax, ay), (bx, by) = segment.waypoints[index], segment.waypoints[index + 1]
            heading = math.atan2(ay - by, ax - bx) if backward else math.atan2(by - ay, bx - ax)
            noses = (nose(heading, Progress.FORWARD), nose(heading, Progress.REVERSE))
            pieces.append((along[index], ax, ay, bx - ax, by - ay, along[index + 1] - along[index], heading, *noses))
        return cls(segment.length, backward, along, tuple(piece_of), tuple(pieces))


class HeadingTable:
    """Travel headings where each (segment, traverse) starts and ends, and its :class:`Track`; one per
    layout, shared by the drivers."""

    def __init__(self, layout: Layout) -> None:
        self._layout = layout
        self._ends: dict[tuple[int, Traverse], tuple[float, float]] = {}
        self._tracks: dict[tuple[int, Traverse], Track] = {}

    def track(self, segment: int, traverse: Traverse) -> Track:
        key = (segment, traverse)
        found = self._tracks.get(key)
        if found is None:
            found = self._tracks[key] = Track.of(self._layout.segments[segment], traverse)
        return found

    def ends(self, segment: int, traverse: Traverse) -> tuple[float, float]:
        key = (segment, traverse)
        found = self._ends.get(key)
        if found is None:
            seg = self._layout.segments[segment]
            found = (seg.pose_at(0.0, traverse)[2], seg.pose_at(seg.length, traverse)[2])
            self._ends[key] = found
        return found

    def turn_between(self, before: FleetLeg, after: FleetLeg) -> float:
        """How far the nose turns (radians, signed) from the end of ``before`` to the start of ``after``."""
        end = nose(self.ends(before.segment, before.traverse)[1], before.progress)
        start = nose(self.ends(after.segment, after.traverse)[0], after.progress)
        return wrap(start - end)
