"""Greedy placement of text beside segments, one rule for the SVG pictures and the RViz alert labels.

Labels are placed one at a time, in the caller's fixed order: each takes the first of its candidate spots
(:func:`spots_beside`: its segment's middle first, then further out and along it) where its box overlaps
no label placed before it. A label that finds no free spot is the caller's to drop (a map's segment id:
fewer labels rather than unreadable ones) or to keep at its last spot (an alert must be shown). Boxes
are kept in a grid of cells, so placing a label costs the same on a map of ten segments or ten thousand.

A list of labels placed again and again as it changes a little (a recording's alert labels, step after
step) is placed by :class:`LabelLayout`, which gives the same places as placing it from scratch while
trying a spot against the grid again only when the label that took it last time moved or went.
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
        return self.taker(box, cells) is None

    def taker(self, box: Box, cells: Sequence[Cell] | None = None) -> Box | None:
        """A box placed so far that ``box`` overlaps, if any (``cells``: its :meth:`cells_of`, if known)."""
        # Plain loops, no generators: a recording asks this hundreds of thousands of times.
        placed = self._cells
        x0, y0, x1, y1 = box
        for key in self.cells_of(box) if cells is None else cells:
            for other in placed.get(key, ()):
                if x0 < other[2] and other[0] < x1 and y0 < other[3] and other[1] < y1:  # they overlap
                    return other
        return None

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


class _Tried:
    """A label's spots as far as they were tried: each one's box and cells, and the box that took it
    (``None``: free when last tried)."""

    __slots__ = ("boxes", "cells", "label", "takers")

    def __init__(self, label: Label) -> None:
        if not label.spots:
            msg = f"label={label!r} must have at least one spot"
            raise ValueError(msg)
        self.label = label
        self.boxes: list[Box] = []
        self.cells: list[list[Cell]] = []
        self.takers: list[Box | None] = []


class LabelLayout:
    """The places of a list of labels placed again and again as it changes (a recording's alert labels,
    step after step), each time exactly as placing it from scratch with :class:`LabelSpace` does (a
    label with no free spot takes its last one, over another label).

    A label keeps from one call to the next the box that took each spot it tried. If that box is placed
    before it again, the spot is taken again (a set lookup), so a spot is tried against the grid again only
    when the label that took it moved or went: a list that changes a little costs little more than a
    lookup per spot.
    """

    def __init__(self, cell: float, letter: float) -> None:
        self.cell = cell
        self.letter = letter
        self._tried: dict[Hashable, _Tried] = {}  # the last call's labels by key

    def place(self, labels: Sequence[Label]) -> list[Placed]:
        """Each label's place, in order."""
        space = LabelSpace(self.cell)
        boxes: set[Box] = set()  # those in space
        tried_now: dict[Hashable, _Tried] = {}
        places = []
        for label in labels:
            tried = tried_now.get(label.key) or self._tried.get(label.key) or _Tried(label)
            tried_now[label.key] = tried
            place = self._first_free(space, boxes, tried)
            space.add(place.box, tried.cells[place.spot])
            boxes.add(place.box)
            places.append(place)
        self._tried = tried_now
        return places

    def _first_free(self, space: LabelSpace, boxes: set[Box], tried: _Tried) -> Placed:
        """The label's first spot free in ``space`` (whose boxes are ``boxes``), else its last; ``tried``
        learns what took each spot."""
        spots, text, letter = tried.label.spots, tried.label.text, self.letter
        known, takers = len(tried.boxes), tried.takers
        for spot in range(len(spots)):
            if spot < known:
                taker = takers[spot]
                if taker is not None and taker in boxes:
                    continue  # taken again by the same box
                box, cells = tried.boxes[spot], tried.cells[spot]
                taker = takers[spot] = space.taker(box, cells)
            else:
                box = box_around(spots[spot], text, letter)
                cells = space.cells_of(box)
                taker = space.taker(box, cells)
                tried.boxes.append(box)
                tried.cells.append(cells)
                takers.append(taker)
            if taker is None:
                return Placed(spot, box)
        return Placed(len(spots) - 1, tried.boxes[-1])
