"""Which segment ends meet, and how a vehicle may drive from one segment onto the next (SPEC §4).

Every segment contributes two endpoints. Endpoints of *different ends* that lie within the connection
tolerance "touch"; each touching pair yields up to two connections (one per driving direction through the
joint), kept only where both segments allow the traverse. A segment whose two ends meet is a loop and
connects to itself.

An end also "touches" itself (SPEC §4 reads "an endpoint of segment B" for any B, A included): a vehicle
at the end of a two-way segment may turn back onto it. That U-turn is a cusp (``opposite``): a vehicle
that only follows curves backs out with its progress flipped, which is how it leaves a dead-end dock.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fleetsim.enums import JointKind, Traverse
from fleetsim.layout.geometry import FloatArray, away_direction, close_point_pairs
from fleetsim.layout.segment import Segment

__all__ = [
    "Connection",
    "Endpoint",
    "Touch",
    "away_vectors",
    "can_connect",
    "dangling_ends",
    "endpoint_array",
    "find_connections",
    "joint_kinds",
    "touching_endpoints",
    "traverse_rank",
]

BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True, slots=True)
class Connection:
    """A vehicle leaving ``from_segment`` driven ``from_traverse`` may enter ``to_segment`` driven
    ``to_traverse``; ``joint`` says how the two meet.

    Connections exist only between ends that meet (within the layout's ``connection_tolerance``) and
    only for traverses both segments allow. The end of a two-way segment also connects to itself: a
    U-turn, a cusp (``OPPOSITE``).

    Attributes:
        from_segment: The id of the segment the vehicle leaves.
        from_traverse: How it drives that segment: ``FORWARD`` leaves through its last waypoint,
            ``BACKWARD`` through its first.
        to_segment: The id of the segment it enters.
        to_traverse: How it drives that one: ``FORWARD`` enters through its first waypoint, ``BACKWARD``
            through its last.
        joint: ``SAME`` (smooth), ``OPPOSITE`` (a cusp: a ``CURVE`` vehicle flips its progress) or
            ``TURN_IN_PLACE`` (a corner only an ``IN_PLACE`` vehicle can take).
    """

    from_segment: int
    from_traverse: Traverse
    to_segment: int
    to_traverse: Traverse
    joint: JointKind


@dataclass(frozen=True, slots=True)
class Endpoint:
    """One end of a segment: ``at_last`` tells whether it is the last waypoint (else the first)."""

    segment: Segment
    at_last: bool

    @property
    def point(self) -> tuple[float, float]:
        return self.segment.last if self.at_last else self.segment.first

    @property
    def name(self) -> str:
        return "last" if self.at_last else "first"

    @property
    def leaving(self) -> Traverse:
        """The traverse that leaves the segment through this end."""
        return Traverse.FORWARD if self.at_last else Traverse.BACKWARD

    @property
    def entering(self) -> Traverse:
        """The traverse that enters the segment through this end."""
        return Traverse.BACKWARD if self.at_last else Traverse.FORWARD


@dataclass(frozen=True, slots=True)
class Touch:
    """Two distinct endpoints within the connection tolerance of each other, ``gap`` metres apart."""

    a: Endpoint
    b: Endpoint
    gap: float


_BY_RANK = (Traverse.FORWARD, Traverse.BACKWARD)


def traverse_rank(traverse: Traverse) -> int:
    """Sort key: forward before backward, everywhere order reaches output."""
    return 0 if traverse is Traverse.FORWARD else 1


def endpoint_array(segments: Sequence[Segment]) -> FloatArray:
    """Row ``2k`` is segment ``k``'s first waypoint and row ``2k + 1`` its last."""
    points = np.empty((2 * len(segments), 2), dtype=np.float64)
    for k, segment in enumerate(segments):
        points[2 * k] = segment.first
        points[2 * k + 1] = segment.last
    return points


def _endpoint(segments: Sequence[Segment], row: int) -> Endpoint:
    return Endpoint(segments[row // 2], at_last=bool(row % 2))


def touching_endpoints(segments: Sequence[Segment], radius: float) -> tuple[Touch, ...]:
    """Every pair of distinct endpoints at most ``radius`` apart, in segment order."""
    pairs, gaps = close_point_pairs(endpoint_array(segments), radius)
    return tuple(
        Touch(_endpoint(segments, int(i)), _endpoint(segments, int(j)), float(gap))
        for (i, j), gap in zip(pairs.tolist(), gaps.tolist(), strict=True)
    )


def dangling_ends(segments: Sequence[Segment], touches: Sequence[Touch]) -> tuple[Endpoint, ...]:
    """The ends of ``segments`` that meet no other end in ``touches`` (dead ends), in segment order.

    The two ends of a closed loop meet each other, so they are not dangling.
    """
    met = {(e.segment.id, e.at_last) for t in touches for e in (t.a, t.b)}
    return tuple(
        Endpoint(segment, at_last)
        for segment in segments
        for at_last in (False, True)
        if (segment.id, at_last) not in met
    )


def away_vectors(segments: Sequence[Segment], skip: float) -> FloatArray:
    """Each endpoint's "away" unit vector (rows as in :func:`endpoint_array`); NaN where undefined."""
    undefined = (math.nan, math.nan)
    return np.array(
        [
            away_direction(segment.waypoints, at_last, skip) or undefined
            for segment in segments
            for at_last in (False, True)
        ],
        dtype=np.float64,
    ).reshape(-1, 2)


def joint_kinds(u: FloatArray, v: FloatArray, angle_tolerance: float) -> list[JointKind]:
    """How segments meet, from the angle between their away vectors ``u[k]`` and ``v[k]``.

    A straight continuation has the away vectors pointing apart (180°); a cusp has them side by side
    (0°). Where a segment is too short to have a direction (NaN), the joint counts as a corner: only a
    vehicle that can turn in place is sure to manage it.
    """
    cross = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    dot = np.einsum("ij,ij->i", u, v)
    angle = np.degrees(np.arctan2(np.abs(cross), dot))  # atan2 stays accurate near 0° and 180°
    kinds = [JointKind.TURN_IN_PLACE] * len(angle)
    for k in np.flatnonzero(angle >= 180.0 - angle_tolerance).tolist():
        kinds[k] = JointKind.SAME
    for k in np.flatnonzero(angle <= angle_tolerance).tolist():
        kinds[k] = JointKind.OPPOSITE
    return kinds


def can_connect(leave: Endpoint, enter: Endpoint) -> bool:
    """Whether a vehicle may leave one segment through ``leave`` and enter the other through ``enter``."""
    return leave.segment.allows(leave.leaving) and enter.segment.allows(enter.entering)


def _allowed(segments: Sequence[Segment]) -> tuple[BoolArray, BoolArray]:
    """Per endpoint row: may a vehicle leave the segment through it, and may it enter through it?"""
    ends = [Endpoint(segment, at_last) for segment in segments for at_last in (False, True)]
    leaving = np.array([e.segment.allows(e.leaving) for e in ends], dtype=bool)
    entering = np.array([e.segment.allows(e.entering) for e in ends], dtype=bool)
    return leaving, entering


def find_connections(segments: Sequence[Segment], tolerance: float, angle_tolerance: float) -> tuple[Connection, ...]:
    """Every connection between ``segments``, sorted by (from state, to state).

    Each touching pair of endpoint rows is tried both ways (leave through one, enter through the other);
    the joint kind is computed for those the directions allow. Vectorised: maps have 10,000+ segments.
    """
    pairs, _ = close_point_pairs(endpoint_array(segments), tolerance)
    rows = np.arange(2 * len(segments), dtype=np.int64)  # each end with itself: the U-turns
    leave = np.concatenate([pairs[:, 0], pairs[:, 1], rows])
    enter = np.concatenate([pairs[:, 1], pairs[:, 0], rows])
    may_leave, may_enter = _allowed(segments)
    ok = may_leave[leave] & may_enter[enter]
    leave, enter = leave[ok], enter[ok]
    ids = np.array([s.id for s in segments], dtype=np.int64)
    # Leaving through the last waypoint is driving forward; entering through the first is forward too.
    from_id, from_rank = ids[leave // 2], 1 - leave % 2
    to_id, to_rank = ids[enter // 2], enter % 2
    order = np.lexsort((to_rank, to_id, from_rank, from_id))
    away = away_vectors(segments, tolerance)
    kinds = joint_kinds(away[leave[order]], away[enter[order]], angle_tolerance)
    columns = (c[order].tolist() for c in (from_id, from_rank, to_id, to_rank))
    return tuple(
        Connection(a, _BY_RANK[ra], b, _BY_RANK[rb], kind) for a, ra, b, rb, kind in zip(*columns, kinds, strict=True)
    )
