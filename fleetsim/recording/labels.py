"""Greedy placement of text beside segments, one rule for the SVG pictures and the RViz alert labels.

Labels are placed one at a time, in the caller's fixed order: each takes the first of its candidate spots
(:func:`spots_beside`: its segment's middle first, then further out and along it) where its box overlaps
no label placed before it. A label that finds no free spot is the caller's to drop (a map's segment id:
fewer labels rather than unreadable ones) or to keep at its last spot (an alert must be shown). Boxes
are kept in a grid of cells, so placing a label costs the same on a map of ten segments or ten thousand.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from fleetsim.enums import Traverse
from fleetsim.layout.segment import Point, Segment

__all__ = ["CHAR_WIDTH", "LINE_HEIGHT", "Box", "LabelSpace", "box_around", "nearest_point", "spots_beside"]

Box = tuple[float, float, float, float]  # min x, min y, max x, max y
CHAR_WIDTH = 0.6  # a character of sans-serif text is at most about 0.6 of the letter height wide
LINE_HEIGHT = 1.2  # a line of text, letter height included, with room above and below


def box_around(centre: Point, text: str, letter: float) -> Box:
    """The box ``text`` at letter height ``letter`` fills when centred on ``centre``."""
    half_width, half_height = 0.5 * CHAR_WIDTH * letter * len(text), 0.5 * LINE_HEIGHT * letter
    return centre[0] - half_width, centre[1] - half_height, centre[0] + half_width, centre[1] + half_height


def _overlap(a: Box, b: Box) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


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
        self._cells: dict[tuple[int, int], list[int]] = {}

    def _cells_of(self, box: Box) -> Iterable[tuple[int, int]]:
        x0, y0 = math.floor(box[0] / self.cell), math.floor(box[1] / self.cell)
        x1, y1 = math.floor(box[2] / self.cell), math.floor(box[3] / self.cell)
        return ((i, j) for i in range(x0, x1 + 1) for j in range(y0, y1 + 1))

    def free(self, box: Box) -> bool:
        """Whether ``box`` overlaps no box placed so far."""
        return not any(
            _overlap(box, self.boxes[index]) for key in self._cells_of(box) for index in self._cells.get(key, ())
        )

    def add(self, box: Box) -> None:
        for key in self._cells_of(box):
            self._cells.setdefault(key, []).append(len(self.boxes))
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
