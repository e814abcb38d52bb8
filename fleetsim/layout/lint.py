"""Layout lint: drawing mistakes that load fine but make a map behave unexpectedly (SPEC §3 ★).

Codes (all warnings):

- ``dangling-end``: a segment end that meets no other segment end — a dead end, often a segment that
  was meant to snap onto a neighbour. The two ends of a closed loop meet each other, so they count.
- ``unreachable``: a segment none of whose states can be reached from the main strongly connected part
  of the state graph (the part covering the most segments; ties go to the smallest segment id).
- ``near-miss``: two ends of different segments farther apart than the connection tolerance but closer
  than ten times it — almost certainly meant to connect.
- ``gap``: a dangling end whose nearest end of another segment is at least ten connection tolerances
  away (else it is a near miss) but within a vehicle length: a gap a vehicle cannot cross, often meant
  to be a joint. Only when a vehicle length is given (a scenario's longest vehicle type; ``fleetsim
  inspect`` uses the default type's); linting a bare layout skips it.
- ``no-connection``: two ends touch, but the segments' one-way directions both lead into, or both out
  of, the joint, so no connection exists either way (they still conflict), and one of the two ends
  connects to no other end there either (a one-way fork or merge, whose branches each connect to the
  lane they fork from, is not reported).
- ``zero-length``: a segment shorter than the connection tolerance.

Duplicate segment ids are not linted: they cannot reach a :class:`~fleetsim.layout.layout.Layout`,
because :func:`~fleetsim.layout.layout.build_layout` raises :class:`~fleetsim.errors.LayoutError` for
them (and the map loader reports them with the file and object ids).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Literal, TypeAlias

import networkx as nx

from fleetsim.enums import Traverse
from fleetsim.layout.connections import (
    Endpoint,
    Touch,
    can_connect,
    dangling_ends,
    touching_endpoints,
    traverse_rank,
)
from fleetsim.layout.segment import Segment

__all__ = ["LintFinding", "Severity", "lint_layout"]

Severity = Literal["warning", "error"]

State = tuple[int, Traverse]
StateGraph: TypeAlias = "nx.DiGraph[State]"  # networkx graphs are generic to type checkers only

# Ends this many connection tolerances apart (or closer) are reported as near misses.
_NEAR_MISS_FACTOR = 10.0


@dataclass(frozen=True, slots=True)
class LintFinding:
    """One lint result: a stable ``code``, the segments concerned and a message for the map's author.

    Attributes:
        code: ``dangling-end``, ``unreachable``, ``near-miss``, ``gap``, ``no-connection`` or
            ``zero-length`` (the Maps page of the documentation says what each means).
        severity: ``"warning"`` for every code today (a map with findings still loads).
        segments: Ids of the segments concerned, ascending.
        message: The finding in words, with the ends' coordinates and distances in metres.
    """

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


def _dangling_ends(dangling: Sequence[Endpoint]) -> Iterator[LintFinding]:
    for end in dangling:
        msg = f"{_describe(end)} at {_point(end.point)} meets no other segment end (a dead end)"
        yield LintFinding("dangling-end", "warning", (end.segment.id,), msg)


def _gaps(
    segments: Sequence[Segment], dangling: Sequence[Endpoint], tolerance: float, vehicle_length: float
) -> Iterator[LintFinding]:
    """Each dangling end's nearest end of another segment, when it lies within a vehicle length."""
    loose = {(end.segment.id, end.at_last) for end in dangling}
    nearest: dict[tuple[int, bool], Touch] = {}
    for t in touching_endpoints(segments, vehicle_length):
        if t.a.segment.id == t.b.segment.id:
            continue
        for end, other in ((t.a, t.b), (t.b, t.a)):
            key = (end.segment.id, end.at_last)
            if key in loose and (key not in nearest or t.gap < nearest[key].gap):
                nearest[key] = Touch(end, other, t.gap)
    reported: set[frozenset[tuple[int, bool]]] = set()
    for t in nearest.values():
        pair = frozenset({(t.a.segment.id, t.a.at_last), (t.b.segment.id, t.b.at_last)})
        if t.gap < _NEAR_MISS_FACTOR * tolerance or pair in reported:
            continue  # a near miss says it already
        reported.add(pair)
        msg = (
            f"{_describe(t.a)} at {_point(t.a.point)} is a dead end {t.gap:.2f} m from {_describe(t.b)} "
            f"at {_point(t.b.point)}, within a vehicle length ({vehicle_length:g} m): "
            "did you mean to connect them?"
        )
        yield LintFinding("gap", "warning", _ids(t), msg)


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
    # A one-way fork or merge is no mistake: its branches do not connect to each other, but each connects
    # to the lane that forks. Only an end that connects to nothing at its joint makes the pair suspect.
    connected = {
        (end.segment.id, end.at_last)
        for t in touches
        if can_connect(t.a, t.b) or can_connect(t.b, t.a)
        for end in (t.a, t.b)
    }
    for t in touches:
        if t.a.segment.id == t.b.segment.id or can_connect(t.a, t.b) or can_connect(t.b, t.a):
            continue
        if (t.a.segment.id, t.a.at_last) in connected and (t.b.segment.id, t.b.at_last) in connected:
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


def _unreachable(segments: Sequence[Segment], graph: StateGraph) -> Iterator[LintFinding]:
    main = _main_component(graph)
    if main is None:
        return
    reached = {sid for sid, _ in nx.descendants(graph, main[0])} | {sid for sid, _ in main}
    anchor = main[0][0]
    for sid in (segment.id for segment in segments):
        if sid not in reached:
            msg = (
                f"segment {sid} cannot be reached from the main part of the map "
                f"(the strongly connected part through segment {anchor})"
            )
            yield LintFinding("unreachable", "warning", (sid,), msg)


def _finding_key(f: LintFinding) -> tuple[bool, str, tuple[int, ...], str]:
    return (f.severity != "error", f.code, f.segments, f.message)


def lint_layout(
    segments: Sequence[Segment], graph: StateGraph, tolerance: float, vehicle_length: float | None = None
) -> tuple[LintFinding, ...]:
    """Every finding for a layout's ``segments`` (by id) and connection ``graph``, whose ends meet within
    ``tolerance`` metres: errors first, then by code, segments and message.

    ``vehicle_length`` (metres) enables the ``gap`` check: dangling ends that far from another end.
    """
    near = touching_endpoints(segments, _NEAR_MISS_FACTOR * tolerance)
    touches = [t for t in near if t.gap <= tolerance]
    dangling = dangling_ends(segments, touches)
    findings = [
        *_dangling_ends(dangling),
        *(_gaps(segments, dangling, tolerance, vehicle_length) if vehicle_length else ()),
        *_near_misses(near, tolerance),
        *_no_connections(touches),
        *_zero_length(segments, tolerance),
        *_unreachable(segments, graph),
    ]
    return tuple(sorted(findings, key=_finding_key))
