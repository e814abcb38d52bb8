"""Which segments conflict: a vehicle on one could touch a vehicle on the other (SPEC §4).

A vehicle is a circle of radius ``r``. Two polylines conflict under the swept model when their minimum
distance is below ``2r + margin``; under the thesis's bounding-box model when their boxes, grown by
``r + margin/2`` per side, overlap. In both models a segment conflicts with itself and with every segment
it touches (distance <= the connection tolerance), even for a point-sized vehicle.

The fast path runs a uniform-grid broad phase over the boxes of the individual *sub-segments* (the
straight pieces between consecutive waypoints), grown by half the reach, and computes exact distances only
for sub-segment pairs that survive it. ``all_pairs_conflicts`` is the brute-force reference: the same
exact-distance kernel on every pair of segments, for tests and benchmarks.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import numpy.typing as npt

from fleetsim.enums import ConflictModel
from fleetsim.layout.geometry import (
    FloatArray,
    IntArray,
    expanded_boxes,
    overlapping_box_pairs,
    ragged_arange,
    segment_distances,
)
from fleetsim.layout.segment import Segment

__all__ = [
    "ConflictSets",
    "SubSegments",
    "all_pairs_conflicts",
    "bbox_conflicts",
    "conflict_sets",
    "polyline_distances",
    "swept_conflicts",
]

ConflictSets = Mapping[int, frozenset[int]]
BoolArray = npt.NDArray[np.bool_]

# Exact distances are evaluated this many sub-segment pairs at a time, to bound temporary arrays.
_CHUNK = 1 << 20


@dataclass(frozen=True, slots=True)
class SubSegments:
    """All segments' straight pieces, flattened: piece ``k`` runs ``starts[k]`` → ``ends[k]``.

    Segment ``s`` (by position in ``ids``) owns pieces ``offsets[s]`` up to ``offsets[s + 1]``.
    """

    ids: IntArray
    starts: FloatArray
    ends: FloatArray
    owner: IntArray
    offsets: IntArray

    @classmethod
    def of(cls, segments: Sequence[Segment]) -> SubSegments:
        points = [np.asarray(s.waypoints, dtype=np.float64) for s in segments]
        counts = np.array([len(p) - 1 for p in points], dtype=np.int64)
        if not points:
            empty = np.empty((0, 2), dtype=np.float64)
            return cls(np.empty(0, np.int64), empty, empty, np.empty(0, np.int64), np.zeros(1, np.int64))
        return cls(
            ids=np.array([s.id for s in segments], dtype=np.int64),
            starts=np.concatenate([p[:-1] for p in points]),
            ends=np.concatenate([p[1:] for p in points]),
            owner=np.repeat(np.arange(len(segments), dtype=np.int64), counts),
            offsets=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
        )

    @property
    def counts(self) -> IntArray:
        return np.diff(self.offsets)

    def boxes(self, grow: float) -> FloatArray:
        return expanded_boxes(np.minimum(self.starts, self.ends), np.maximum(self.starts, self.ends), grow)

    def segment_boxes(self, grow: float) -> FloatArray:
        """Each segment's bounding box, grown by ``grow`` per side."""
        lo = np.minimum.reduceat(np.minimum(self.starts, self.ends), self.offsets[:-1])
        hi = np.maximum.reduceat(np.maximum(self.starts, self.ends), self.offsets[:-1])
        return expanded_boxes(lo, hi, grow)


def _chunks(total: int, weights: IntArray | None = None) -> Iterator[slice]:
    """Consecutive slices of ``range(total)`` whose summed ``weights`` stay near ``_CHUNK``."""
    if weights is None:
        bounds = np.arange(0, total, _CHUNK)
    else:
        bounds = np.unique(np.searchsorted(np.cumsum(weights), np.arange(0, int(weights.sum()), _CHUNK)))
    edges = [*bounds.tolist(), total]
    for lo, hi in pairwise(edges):
        if hi > lo:
            yield slice(lo, hi)


def _piece_distances(subs: SubSegments, i: IntArray, j: IntArray) -> FloatArray:
    return segment_distances(subs.starts[i], subs.ends[i], subs.starts[j], subs.ends[j])


def polyline_distances(subs: SubSegments, a: IntArray, b: IntArray) -> FloatArray:
    """Exact minimum distance between polylines ``a[k]`` and ``b[k]`` (positions in ``subs.ids``).

    Every piece of one is measured against every piece of the other, batched across all pairs.
    """
    counts = subs.counts
    result = np.empty(len(a), dtype=np.float64)
    for part in _chunks(len(a), counts[a] * counts[b]):
        pa, pb = a[part], b[part]
        per_pair = counts[pa] * counts[pb]
        pair = np.repeat(np.arange(len(pa), dtype=np.int64), per_pair)
        t = ragged_arange(per_pair)
        width = counts[pb][pair]
        i = subs.offsets[pa][pair] + t // width
        j = subs.offsets[pb][pair] + t % width
        d = _piece_distances(subs, i, j)
        result[part] = np.minimum.reduceat(d, np.cumsum(per_pair) - per_pair)
    return result


def _within(d: FloatArray, threshold: float, touch: float) -> BoolArray:
    return (d < threshold) | (d <= touch)


def _close_segment_pairs(subs: SubSegments, threshold: float, touch: float) -> IntArray:
    """Segment pairs (positions, ``i < j``) with some pieces closer than ``threshold`` or within ``touch``."""
    reach = max(threshold, touch)
    candidates = overlapping_box_pairs(subs.boxes(reach / 2.0))
    i, j = candidates[:, 0], candidates[:, 1]
    other = subs.owner[i] != subs.owner[j]
    i, j = i[other], j[other]
    found: list[IntArray] = []
    for part in _chunks(len(i)):
        hit = _within(_piece_distances(subs, i[part], j[part]), threshold, touch)
        found.append(np.stack([subs.owner[i[part]][hit], subs.owner[j[part]][hit]], axis=1))
    return _unique_pairs(found)


def _unique_pairs(parts: list[IntArray]) -> IntArray:
    """Distinct unordered pairs, as sorted rows ``(i, j)`` with ``i < j``."""
    if not parts:
        return np.empty((0, 2), dtype=np.int64)
    pairs = np.concatenate(parts)
    lo, hi = pairs.min(axis=1), pairs.max(axis=1)
    # One int64 code per pair sorts far faster than np.unique(axis=0) on rows.
    base = int(hi.max()) + 1 if len(hi) else 1
    codes = np.unique(lo * base + hi)
    return np.stack([codes // base, codes % base], axis=1)


def _as_sets(subs: SubSegments, pairs: IntArray) -> dict[int, frozenset[int]]:
    """Symmetric conflict sets keyed by segment id (in ``subs.ids`` order), each including itself."""
    n = len(subs.ids)
    everyone = np.arange(n, dtype=np.int64)
    rows = np.concatenate([pairs[:, 0], pairs[:, 1], everyone])
    cols = np.concatenate([pairs[:, 1], pairs[:, 0], everyone])
    order = np.lexsort((cols, rows))
    members = subs.ids[cols[order]].tolist()
    bounds = np.searchsorted(rows[order], np.arange(n + 1)).tolist()
    ids = subs.ids.tolist()
    return {ids[k]: frozenset(members[bounds[k] : bounds[k + 1]]) for k in range(n)}


def swept_conflicts(segments: Sequence[Segment], threshold: float, touch: float = 0.0) -> dict[int, frozenset[int]]:
    """Conflict sets under the swept model: polyline distance < ``threshold`` or <= ``touch``."""
    subs = SubSegments.of(segments)
    return _as_sets(subs, _close_segment_pairs(subs, threshold, touch))


def bbox_conflicts(segments: Sequence[Segment], grow: float, touch: float = 0.0) -> dict[int, frozenset[int]]:
    """Conflict sets under the thesis's model: boxes grown by ``grow`` per side overlap, or touching."""
    subs = SubSegments.of(segments)
    overlapping = overlapping_box_pairs(subs.segment_boxes(grow))
    touching = _close_segment_pairs(subs, 0.0, touch)
    return _as_sets(subs, _unique_pairs([overlapping, touching]))


def all_pairs_conflicts(
    segments: Sequence[Segment], threshold: float, *, touch: float = 0.0
) -> dict[int, frozenset[int]]:
    """Reference for :func:`swept_conflicts`: exact polyline distance on every pair of segments."""
    subs = SubSegments.of(segments)
    n = len(subs.ids)
    found: list[IntArray] = []
    rows_per_block = max(1, _CHUNK // max(n, 1))
    for start in range(0, n, rows_per_block):
        rows = np.arange(start, min(start + rows_per_block, n), dtype=np.int64)
        later = n - rows - 1
        a = np.repeat(rows, later)
        b = a + 1 + ragged_arange(later)
        hit = _within(polyline_distances(subs, a, b), threshold, touch)
        found.append(np.stack([a[hit], b[hit]], axis=1))
    return _as_sets(subs, _unique_pairs(found))


def conflict_sets(
    segments: Sequence[Segment],
    model: ConflictModel,
    vehicle_radius: float,
    safety_margin: float,
    touch: float,
) -> dict[int, frozenset[int]]:
    """The layout's conflict sets for the chosen model and settings."""
    if model is ConflictModel.BBOX:
        return bbox_conflicts(segments, vehicle_radius + safety_margin / 2.0, touch)
    return swept_conflicts(segments, 2.0 * vehicle_radius + safety_margin, touch)
