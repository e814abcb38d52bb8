"""Greedy placement of text beside segments, one rule for the SVG pictures and the RViz alert labels.

Labels are placed one at a time, in the caller's fixed order: each takes the first of its candidate spots
(:func:`spots_beside`: its segment's middle first, then further out and along it) where its box overlaps
no label placed before it. A label that finds no free spot is the caller's to drop (a map's segment id:
fewer labels rather than unreadable ones) or to keep at its last spot (an alert must be shown). Boxes
are kept in a grid of cells, so placing a label costs the same on a map of ten segments or ten thousand.

A list of labels placed again and again as it changes a little (a recording's alert labels, step after
step) is placed by :class:`LabelLayout`, which gives the same places as placing it from scratch while
trying again only the labels whose neighbourhood changed.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Iterable, Sequence
from typing import NamedTuple

from fleetsim.enums import Traverse
from fleetsim.layout.segment import Point, Segment

__all__ = [
    "CHAR_WIDTH",
    "LINE_HEIGHT",
    "Box",
    "Cell",
    "Label",
    "LabelLayout",
    "LabelSpace",
    "Placed",
    "box_around",
    "nearest_point",
    "spots_beside",
]

Box = tuple[float, float, float, float]  # min x, min y, max x, max y
Cell = tuple[int, int]  # a square of the grid that LabelSpace keeps boxes in
CHAR_WIDTH = 0.6  # a character of sans-serif text is at most about 0.6 of the letter height wide
LINE_HEIGHT = 1.2  # a line of text, letter height included, with room above and below


def box_around(centre: Point, text: str, letter: float) -> Box:
    """The box ``text`` at letter height ``letter`` fills when centred on ``centre``."""
    half_width, half_height = 0.5 * CHAR_WIDTH * letter * len(text), 0.5 * LINE_HEIGHT * letter
    return centre[0] - half_width, centre[1] - half_height, centre[0] + half_width, centre[1] + half_height


def spots_beside(segment: Segment, offsets: Sequence[float], fractions: Sequence[float] = (0.5,)) -> list[Point]:
    """Candidate label centres: for each offset in turn, at each fraction of the way along ``segment``,
    that far (metres) to its left, then to its right."""
    poses = [segment.pose_at(fraction * segment.length, Traverse.FORWARD) for fraction in fractions]
    spots = []
    for offset in offsets:
        for x, y, heading in poses:
            nx, ny = -math.sin(heading), math.cos(heading)  # the segment's left
            spots += [(x + offset * nx, y + offset * ny), (x - offset * nx, y - offset * ny)]
    return spots


def nearest_point(box: Box, point: Point) -> Point:
    """The point of ``box`` (its edge, or inside it) nearest to ``point``."""
    return min(max(point[0], box[0]), box[2]), min(max(point[1], box[1]), box[3])


class LabelSpace:
    """The boxes of the labels placed so far, in a grid of ``cell``-sized squares."""

    def __init__(self, cell: float) -> None:
        if not cell > 0:
            msg = f"cell={cell!r} must be > 0"
            raise ValueError(msg)
        self.cell = cell
        self.boxes: list[Box] = []
        self._cells: dict[Cell, list[Box]] = {}  # the boxes touching each cell

    def cells_of(self, box: Box) -> list[Cell]:
        """The cells ``box`` touches (:meth:`free` and :meth:`add` take them for a box tried again and again)."""
        cell = self.cell
        x0, x1 = math.floor(box[0] / cell), math.floor(box[2] / cell)
        y0, y1 = math.floor(box[1] / cell), math.floor(box[3] / cell)
        return [(i, j) for i in range(x0, x1 + 1) for j in range(y0, y1 + 1)]

    def free(self, box: Box, cells: Sequence[Cell] | None = None) -> bool:
        """Whether ``box`` overlaps no box placed so far (``cells``: its :meth:`cells_of`, if known)."""
        # Plain loops, no generators: a recording asks this hundreds of thousands of times.
        placed = self._cells
        x0, y0, x1, y1 = box
        for key in self.cells_of(box) if cells is None else cells:
            for other in placed.get(key, ()):
                if x0 < other[2] and other[0] < x1 and y0 < other[3] and other[1] < y1:  # they overlap
                    return False
        return True

    def add(self, box: Box, cells: Sequence[Cell] | None = None) -> None:
        """Place ``box`` (``cells``: its :meth:`cells_of`, if known)."""
        placed = self._cells
        for key in self.cells_of(box) if cells is None else cells:
            found = placed.get(key)
            if found is None:
                placed[key] = [box]
            else:
                found.append(box)
        self.boxes.append(box)

    def place(self, spots: Iterable[Point], text: str, letter: float) -> tuple[int, Box] | None:
        """The first spot (its position among ``spots``, its box) where ``text`` overlaps no placed label,
        which it joins; ``None`` when every spot is taken (nothing is added)."""
        for index, spot in enumerate(spots):
            box = box_around(spot, text, letter)
            if self.free(box):
                self.add(box)
                return index, box
        return None


class Label(NamedTuple):
    """A label to place at the first free one of ``spots``; equal ``key``s stand for equal spots and text."""

    key: Hashable
    spots: Sequence[Point]
    text: str


class Placed(NamedTuple):
    """Where a label went: the spot it took (its position among the label's spots) and its box."""

    spot: int
    box: Box
    # The bounding box of every box tried: a label placed before it that changes outside it cannot change
    # where this one goes.
    reach: Box


class _Candidate(NamedTuple):
    """A label at one of its spots: its box, the cells the box touches, and the bounding box of this and
    the spots before it."""

    box: Box
    cells: list[Cell]
    reach: Box


class _Tried:
    """A label and its candidates, worked out as far as they were tried (most labels take an early spot)."""

    __slots__ = ("candidates", "label")

    def __init__(self, label: Label) -> None:
        if not label.spots:
            msg = f"label={label!r} must have at least one spot"
            raise ValueError(msg)
        self.label = label
        self.candidates: list[_Candidate] = []

    def candidate(self, index: int, letter: float, space: LabelSpace) -> _Candidate:
        """The label at its ``index``-th spot (the spots before it worked out already; ``space`` for its
        grid)."""
        candidates = self.candidates
        if index < len(candidates):
            return candidates[index]
        box = box_around(self.label.spots[index], self.label.text, letter)
        reach = _bounding(candidates[-1].reach, box) if candidates else box
        candidates.append(_Candidate(box, space.cells_of(box), reach))
        return candidates[-1]


class LabelLayout:
    """The places of a list of labels, placed greedily in order as by :class:`LabelSpace` (a label with
    no free spot takes its last one, over another label), kept from one call to the next.

    Each call gives exactly what placing its labels from scratch would, but a label placed in the last call
    keeps its place without trying its spots again when nothing placed before it changed within its
    reach (:class:`Placed`): the labels placed before it then overlap its tried boxes as they did. A list
    that changes a little costs about as much as the labels near a change.
    """

    def __init__(self, cell: float, letter: float) -> None:
        self.cell = cell
        self.letter = letter
        self._last: list[tuple[Placed, _Tried]] = []  # the last call's labels in order, and their places
        self._position: dict[Hashable, int] = {}  # key -> its position in _last

    def place(self, labels: Sequence[Label]) -> list[Placed]:
        """Each label's place, in order."""
        last, position = self._last, self._position
        space = LabelSpace(self.cell)
        # A superset of the boxes that differ between the labels placed before the current one now and
        # those placed before its match last time: those dropped, those new, and both boxes of one moved.
        changed = LabelSpace(2.0 * self.cell)  # coarser: it is mostly empty
        placed: list[tuple[Placed, _Tried]] = []
        unmatched = 0  # the last call's labels before this position are matched or counted as changed
        for label in labels:
            at = position.get(label.key, -1)
            if at >= unmatched:  # matched in order: the labels before it are matched or changed
                for dropped, _ in last[unmatched:at]:
                    changed.add(dropped.box)
                unmatched = at + 1
                before, tried = last[at]
                if not changed.boxes or changed.free(before.reach):
                    now = before
                else:
                    now = self._first_free(space, tried)
                    if now.box != before.box:
                        changed.add(before.box)
                        changed.add(now.box)
            else:
                tried = _Tried(label)
                now = self._first_free(space, tried)
                changed.add(now.box)
            space.add(now.box, tried.candidates[now.spot].cells)
            placed.append((now, tried))
        self._last = placed
        self._position = {tried.label.key: number for number, (_, tried) in enumerate(placed)}
        return [now for now, _ in placed]

    def _first_free(self, space: LabelSpace, tried: _Tried) -> Placed:
        """The label's first spot free in ``space``, else its last (not added to ``space``)."""
        letter, free = self.letter, space.free
        for index in range(len(tried.label.spots)):
            box, cells, reach = tried.candidate(index, letter, space)
            if free(box, cells):
                return Placed(index, box, reach)
        return Placed(index, box, reach)


def _bounding(a: Box, b: Box) -> Box:
    return min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3])
