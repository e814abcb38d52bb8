"""SVG pictures of a layout: segment ids (and the site's names), direction arrows and a highlighted neighbourhood.

With a highlighted segment the picture is the thesis's figure 24: the segment in yellow, the segments
it leads to in green, and the segments it conflicts with (a vehicle on one could hit a vehicle on the
other) in grey.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from itertools import pairwise
from xml.sax.saxutils import escape

from fleetsim.enums import Traverse
from fleetsim.errors import LayoutError
from fleetsim.layout.layout import Layout
from fleetsim.layout.segment import Point, Segment
from fleetsim.recording.labels import LabelSpace, spots_beside

__all__ = ["render_layout_svg"]

_PLAIN = "#3b4a6b"
_HIGHLIGHT = "#f2c200"
_SUCCESSOR = "#2e9e3f"
_CONFLICT = "#9a9a9a"
# A label's candidate spots: offsets from its segment in letter heights, fractions of the way along it.
_LABEL_OFFSETS = (0.9, 2.1, 3.3)
_LABEL_FRACTIONS = (0.5, 0.3, 0.7, 0.15, 0.85)


@dataclass(frozen=True, slots=True)
class _Frame:
    """World metres (y up) to SVG user units (y down), with a margin around the layout.

    ``top`` user units are left free above the layout (for a caption).
    """

    min_x: float
    max_y: float
    scale: float
    width: float
    height: float
    top: float = 0.0

    def point(self, p: Point) -> tuple[float, float]:
        return (p[0] - self.min_x) * self.scale, (self.max_y - p[1]) * self.scale + self.top

    def points(self, points: Iterable[Point]) -> str:
        """An SVG ``points`` attribute value."""
        return " ".join(f"{x:.2f},{y:.2f}" for x, y in map(self.point, points))


def _frame(layout: Layout, margin: float, pixels_per_metre: float, top: float = 0.0) -> _Frame:
    xs = [x for seg in layout.segments.values() for x, _ in seg.waypoints]
    ys = [y for seg in layout.segments.values() for _, y in seg.waypoints]
    min_x, max_x = min(xs) - margin, max(xs) + margin
    min_y, max_y = min(ys) - margin, max(ys) + margin
    return _Frame(
        min_x=min_x,
        max_y=max_y,
        scale=pixels_per_metre,
        width=(max_x - min_x) * pixels_per_metre,
        height=(max_y - min_y) * pixels_per_metre + top,
        top=top,
    )


def _document(frame: _Frame, title: str, body: Iterable[str]) -> str:
    """A standalone SVG document of ``frame``'s size on a white background; ``title`` is escaped."""
    return "\n".join(
        [
            '<?xml version="1.0" encoding="UTF-8"?>',
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{frame.width:.0f}" height="{frame.height:.0f}" '
            f'viewBox="0 0 {frame.width:.2f} {frame.height:.2f}">',
            f"<title>{escape(title)}</title>",
            '<rect width="100%" height="100%" fill="white"/>',
            *body,
            "</svg>",
            "",
        ]
    )


def _point_at(segment: Segment, fraction: float) -> tuple[Point, float]:
    """The point ``fraction`` of the way along the polyline and the heading (radians) there."""
    target = fraction * segment.length
    travelled = 0.0
    for a, b in pairwise(segment.waypoints):
        piece = math.dist(a, b)
        if piece > 0 and travelled + piece >= target:
            t = (target - travelled) / piece
            return (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])), math.atan2(b[1] - a[1], b[0] - a[0])
        travelled += piece
    a, b = segment.waypoints[-2], segment.waypoints[-1]
    return b, math.atan2(b[1] - a[1], b[0] - a[0])


def _arrow(frame: _Frame, tip: Point, heading: float, size: float, colour: str, attributes: str = "") -> str:
    """A filled triangle pointing along ``heading`` (world radians) with its tip at ``tip``.

    ``attributes`` are put into the element as they are (a class, an opacity).
    """
    back = heading + math.pi
    corners = [
        tip,
        (tip[0] + size * math.cos(back + 0.45), tip[1] + size * math.sin(back + 0.45)),
        (tip[0] + size * math.cos(back - 0.45), tip[1] + size * math.sin(back - 0.45)),
    ]
    return f'<polygon {attributes + " " if attributes else ""}points="{frame.points(corners)}" fill="{colour}"/>'


def _segment_svg(frame: _Frame, segment: Segment, colour: str, width: float, arrow: float) -> list[str]:
    parts = [
        f'<polyline class="segment" data-segment="{segment.id}" points="{frame.points(segment.waypoints)}" fill="none" '
        f'stroke="{colour}" stroke-width="{width:.2f}" stroke-linecap="round" stroke-linejoin="round"/>'
    ]
    # One arrow per allowed traverse, placed a little either side of the middle so both show.
    for traverse, fraction in ((Traverse.FORWARD, 0.62), (Traverse.BACKWARD, 0.38)):
        if not segment.allows(traverse):
            continue
        tip, heading = _point_at(segment, fraction)
        if traverse is Traverse.BACKWARD:
            heading += math.pi
        parts.append(_arrow(frame, tip, heading, arrow, "#111111" if colour == _HIGHLIGHT else colour))
    return parts


def _segment_labels(frame: _Frame, layout: Layout, font: float) -> list[str]:
    """Each segment's label, its id and the site's name for it (when the map has one), beside it.

    Placed in id order by :mod:`fleetsim.recording.labels`: first beside the middle on the left (where it
    never sits on the stroke), else the first free spot further out or along the segment. On a dense map
    a label with no free spot is left out rather than drawn over another one.
    """
    letter = font / frame.scale  # placement in world metres
    offsets = [k * letter for k in _LABEL_OFFSETS]
    space = LabelSpace(4.0 * letter)
    parts = []
    for sid in sorted(layout.segments):
        segment = layout.segments[sid]
        text = str(sid) if segment.name is None else f"{sid} ({segment.name})"
        placed = space.place(spots_beside(segment, offsets, _LABEL_FRACTIONS), text, letter)
        if placed is None:
            continue
        _, box = placed
        x, y = frame.point(((box[0] + box[2]) / 2, (box[1] + box[3]) / 2))
        parts.append(
            f'<text class="segment-label" data-segment="{sid}" x="{x:.2f}" y="{y:.2f}" font-size="{font:.1f}" '
            f'text-anchor="middle" dominant-baseline="middle">{escape(text)}</text>'
        )
    return parts


def _colours(layout: Layout, highlight: int | None) -> dict[int, str]:
    colours = dict.fromkeys(layout.segments, _PLAIN)
    if highlight is None:
        return colours
    for sid in sorted(layout.conflicts(highlight)):
        colours[sid] = _CONFLICT
    for traverse in Traverse:
        if layout.segments[highlight].allows(traverse):
            for next_sid, _, _ in layout.successors(highlight, traverse):
                colours[next_sid] = _SUCCESSOR
    colours[highlight] = _HIGHLIGHT
    return colours


def _legend(frame: _Frame, font: float, highlight: int) -> list[str]:
    entries = ((_HIGHLIGHT, f"segment {highlight}"), (_SUCCESSOR, "leads to"), (_CONFLICT, "conflicts with"))
    parts = []
    for row, (colour, text) in enumerate(entries):
        y = font * (1.5 + 1.4 * row)
        parts.append(
            f'<rect x="{font:.1f}" y="{y - font * 0.5:.1f}" width="{font:.1f}" height="{font:.1f}" fill="{colour}"/>'
        )
        parts.append(
            f'<text x="{font * 2.5:.1f}" y="{y:.1f}" font-size="{font:.1f}" dominant-baseline="middle">{escape(text)}</text>'
        )
    return parts


def render_layout_svg(layout: Layout, *, highlight: int | None = None, pixels_per_metre: float = 40.0) -> str:
    """Draw ``layout`` as an SVG document: ids, direction arrows, and ``highlight``'s neighbourhood."""
    if highlight is not None and highlight not in layout.segments:
        source = layout.source if layout.source is not None else "layout"
        msg = f"{source}: highlight={highlight!r} is not a segment id of this map"
        raise LayoutError(msg)
    frame = _frame(layout, margin=1.5, pixels_per_metre=pixels_per_metre)
    width = 0.12 * pixels_per_metre
    arrow = 0.35
    font = 0.4 * pixels_per_metre
    colours = _colours(layout, highlight)
    # Draw plain segments first, then the highlighted neighbourhood on top of them.
    order = sorted(layout.segments, key=lambda sid: (colours[sid] != _PLAIN, colours[sid] == _HIGHLIGHT, sid))
    body: list[str] = []
    for sid in order:
        segment = layout.segments[sid]
        body.extend(_segment_svg(frame, segment, colours[sid], width * (1.6 if sid == highlight else 1.0), arrow))
    body.append('<g font-family="sans-serif" fill="#111">')
    body.extend(_segment_labels(frame, layout, font * 0.6))
    body.append("</g>")
    if highlight is not None:
        body.append('<g font-family="sans-serif" fill="#111">')
        body.extend(_legend(frame, font * 0.6, highlight))
        body.append("</g>")
    return _document(frame, str(layout.source) if layout.source is not None else "layout", body)
