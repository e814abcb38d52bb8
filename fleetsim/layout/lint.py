"""Layout lint: drawing mistakes that load fine but make a map behave unexpectedly (SPEC §3 ★).

Codes (all warnings):

- ``dangling-end``: a segment end that meets no other segment end — a dead end, often a segment that
  was meant to snap onto a neighbour. The two ends of a closed loop meet each other, so they count.
- ``unreachable``: a segment none of whose states can be reached from the main strongly connected part
  of the state graph (the part covering the most segments; ties go to the smallest segment id).
- ``near-miss``: two ends of different segments farther apart than the connection tolerance but closer
  than ten times it — almost certainly meant to connect.
- ``no-connection``: two ends touch, but the segments' one-way directions both lead into, or both out
  of, the joint, so no connection exists either way (they still conflict).
- ``zero-length``: a segment shorter than the connection tolerance.

Duplicate segment ids are not linted: they cannot reach a :class:`~fleetsim.layout.layout.Layout`,
because :func:`~fleetsim.layout.layout.build_layout` raises :class:`~fleetsim.errors.LayoutError` for
them (and the map loader reports them with the file and object ids).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, TypeAlias

import networkx as nx

from fleetsim.enums import Traverse
from fleetsim.layout.connections import Endpoint, Touch, can_connect, touching_endpoints, traverse_rank
from fleetsim.layout.segment import Segment

if TYPE_CHECKING:
    from fleetsim.layout.layout import Layout

__all__ = ["LintFinding", "Severity", "lint_layout"]

Severity = Literal["warning", "error"]

State = tuple[int, Traverse]
StateGraph: TypeAlias = "nx.DiGraph[State]"  # networkx graphs are generic to type checkers only

# Ends this many connection tolerances apart (or closer) are reported as near misses.
_NEAR_MISS_FACTOR = 10.0


@dataclass(frozen=True, slots=True)
class LintFinding:
    """One lint result: a stable ``code``, the segments concerned and a message for the map's author."""

    code: str
    severity: Severity
    segments: tuple[int, ...]
    message: str

    def __str__(self) -> str:
        return f"{self.severity}: {self.code}: {self.message}"


def _point(p: tuple[float, float]) -> str:
    return f"({p[0]:.3f}, {p[1]:.3f})"


def _describe(end: Endpoint) -> str:
    return f"the {end.name} end of segment {end.segment.id}"


def _dangling_ends(segments: Sequence[Segment], touches: Sequence[Touch]) -> Iterator[LintFinding]:
    met = {(e.segment.id, e.at_last) for t in touches for e in (t.a, t.b)}
    for segment in segments:
        for at_last in (False, True):
            if (segment.id, at_last) not in met:
                end = Endpoint(segment, at_last)
                msg = f"{_describe(end)} at {_point(end.point)} meets no other segment end (a dead end)"
                yield LintFinding("dangling-end", "warning", (segment.id,), msg)


def _near_misses(near: Sequence[Touch], tolerance: float) -> Iterator[LintFinding]:
    limit = _NEAR_MISS_FACTOR * tolerance
    for t in near:
        if t.a.segment.id != t.b.segment.id and tolerance < t.gap < limit:
            msg = (
                f"{_describe(t.a)} and {_describe(t.b)} are {t.gap:.3f} m apart, more than the "
                f"connection tolerance {tolerance:g} m: move them together to connect them"
            )
            yield LintFinding("near-miss", "warning", _ids(t), msg)


def _ids(t: Touch) -> tuple[int, ...]:
    return tuple(sorted((t.a.segment.id, t.b.segment.id)))


def _no_connections(touches: Sequence[Touch]) -> Iterator[LintFinding]:
    for t in touches:
        if t.a.segment.id == t.b.segment.id or can_connect(t.a, t.b) or can_connect(t.b, t.a):
            continue
        flow = "into" if t.a.segment.allows(t.a.leaving) else "out of"
        msg = (
            f"segments {t.a.segment.id} ({t.a.segment.direction}) and {t.b.segment.id} "
            f"({t.b.segment.direction}) touch at {_point(t.a.point)} but do not connect: "
            f"both one-way directions lead {flow} the joint"
        )
        yield LintFinding("no-connection", "warning", _ids(t), msg)


def _zero_length(segments: Sequence[Segment], tolerance: float) -> Iterator[LintFinding]:
    for segment in segments:
        if segment.length < tolerance:
            msg = (
                f"segment {segment.id} is {segment.length:.3f} m long, shorter than the connection "
                f"tolerance {tolerance:g} m"
            )
            yield LintFinding("zero-length", "warning", (segment.id,), msg)


def _state_key(state: State) -> tuple[int, int]:
    return (state[0], traverse_rank(state[1]))


def _main_component(graph: StateGraph) -> list[State] | None:
    """The strongly connected component covering the most segments, as sorted states.

    Ties go to the smallest segment id, then to the smallest states, so the choice never depends on
    networkx's iteration order.
    """
    components = [sorted(c, key=_state_key) for c in nx.strongly_connected_components(graph)]
    if not components:
        return None

    def key(states: list[State]) -> tuple[int, int, list[tuple[int, int]]]:
        return (-len({sid for sid, _ in states}), states[0][0], [_state_key(s) for s in states])

    return min(components, key=key)


def _unreachable(layout: Layout) -> Iterator[LintFinding]:
    main = _main_component(layout.graph)
    if main is None:
        return
    reached = {sid for sid, _ in nx.descendants(layout.graph, main[0])} | {sid for sid, _ in main}
    anchor = main[0][0]
    for sid in layout.segments:
        if sid not in reached:
            msg = (
                f"segment {sid} cannot be reached from the main part of the map "
                f"(the strongly connected part through segment {anchor})"
            )
            yield LintFinding("unreachable", "warning", (sid,), msg)


def _finding_key(f: LintFinding) -> tuple[bool, str, tuple[int, ...], str]:
    return (f.severity != "error", f.code, f.segments, f.message)


def lint_layout(layout: Layout) -> tuple[LintFinding, ...]:
    """Every finding for ``layout``, errors first, then by code, segments and message."""
    segments = tuple(layout.segments.values())
    tolerance = layout.connection_tolerance
    near = touching_endpoints(segments, _NEAR_MISS_FACTOR * tolerance)
    touches = [t for t in near if t.gap <= tolerance]
    findings = [
        *_dangling_ends(segments, touches),
        *_near_misses(near, tolerance),
        *_no_connections(touches),
        *_zero_length(segments, tolerance),
        *_unreachable(layout),
    ]
    return tuple(sorted(findings, key=_finding_key))
