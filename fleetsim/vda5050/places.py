"""The map as VDA 5050 sees it: nodes where segment ends meet, edges along segments.

A VDA 5050 order is a path of nodes and edges; fleetsim's map is segments that meet at their ends. The
mapping, stable for a map file whatever the run:

- **Nodes** are the places where segment ends meet (within the layout's connection tolerance), and the
  ends that meet nothing. A node takes the site's own name when the map has one: the LIF node id on a LIF
  map, the vertex name on an Open-RMF map. Otherwise (Tiled maps, an unnamed or ambiguous place) it is
  named after its lowest segment end: ``s7.first`` is the node at segment 7's first waypoint, ``s7.last``
  at its last (the lowest segment id; ``first`` before ``last``). Another name of the same place (a second
  LIF node within the tolerance) is accepted in orders as an alias.
- **Edges** are segments. On a LIF or Open-RMF map each direction of a segment is the site's own edge (the
  LIF edge id; ``a--b`` for an RMF lane), so a two-way segment has two edge ids and a one-way segment one.
  On a Tiled map the edge id is ``e7`` for segment 7 in either direction: the edge's ``startNodeId`` and
  ``endNodeId`` say which way it is driven. A segment whose two ends meet (a loop) is driven forward
  (first to last waypoint) under its ``e`` id when it allows that, else backward.

:func:`site_graph` builds the mapping for a layout; the leg of an order's edge and the node ids of a leg
come from it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from fleetsim.enums import Direction, Traverse
from fleetsim.layout.connections import touching_endpoints
from fleetsim.layout.layout import Layout
from fleetsim.layout.segment import Segment

__all__ = ["EdgeProblem", "Place", "SiteGraph", "site_graph"]

End = tuple[int, bool]  # (segment id, at its last waypoint)


@dataclass(frozen=True, slots=True)
class Place:
    """A node: where the segment ends in ``ends`` meet, at (``x``, ``y``) (their mean), in metres."""

    node_id: str
    x: float
    y: float
    ends: tuple[End, ...]
    aliases: tuple[str, ...] = ()


class EdgeProblem(ValueError):
    """An order's edge that is no segment of the map, or that does not join its nodes; ``reference`` is
    the order key it concerns (``edgeId``, ``startNodeId`` or ``endNodeId``)."""

    def __init__(self, message: str, reference: str) -> None:
        super().__init__(message)
        self.reference = reference


@dataclass(frozen=True)
class SiteGraph:
    """Nodes and edges of one layout (see the module docstring)."""

    map_id: str
    places: Mapping[str, Place]
    site_named: bool  # edges are the site's own (LIF, RMF), one id per direction
    _node_of_end: Mapping[End, str]
    _aliases: Mapping[str, str]
    _edges: Mapping[str, tuple[int, Traverse | None]]  # None: the direction comes from the nodes
    _edge_of: Mapping[tuple[int, Traverse], str]
    _segments: Mapping[int, Segment]

    def node(self, node_id: str) -> Place | None:
        """The place ``node_id`` names (its id or an alias), or None."""
        return self.places.get(self._aliases.get(node_id, node_id))

    def node_at(self, segment: int, at_last: bool) -> str:
        """The id of the node at one end of ``segment``."""
        return self._node_of_end[(segment, at_last)]

    def entry_node(self, segment: int, traverse: Traverse) -> str:
        """The node a vehicle driving ``segment`` with ``traverse`` enters it through."""
        return self.node_at(segment, traverse is Traverse.BACKWARD)

    def exit_node(self, segment: int, traverse: Traverse) -> str:
        """The node it leaves ``segment`` through."""
        return self.node_at(segment, traverse is Traverse.FORWARD)

    def edge_id(self, segment: int, traverse: Traverse) -> str:
        """The id of the edge that drives ``segment`` with ``traverse``. On a Tiled map that is the
        segment's one edge id in either direction (a one-way segment's wrong way included: an order may
        name it, and the checks reject it as ``wrong-way``); a site's one-way edge has no reverse, and
        asking for it is a :class:`KeyError`."""
        try:
            return self._edge_of[(segment, traverse)]
        except KeyError:
            raise KeyError(f"segment {segment} has no edge driven {traverse.value} in map {self.map_id!r}") from None

    def traverses(self, segment: int) -> tuple[Traverse, ...]:
        """The ways ``segment`` may be driven (forward first): each is an edge a master control may use."""
        allowed = self._segments[segment]
        return tuple(
            t for t in (Traverse.FORWARD, Traverse.BACKWARD) if allowed.allows(t) and (segment, t) in self._edge_of
        )

    def segment_length(self, segment: int) -> float:
        """Metres along ``segment``."""
        return self._segments[segment].length

    def leg_of(self, edge_id: str, start_node: str, end_node: str) -> tuple[int, Traverse]:
        """The segment and traverse an order's edge drives; :class:`EdgeProblem` when the edge is no
        edge of the map, a node is no node of it, or the edge does not join ``start_node`` to ``end_node``."""
        known = self._edges.get(edge_id)
        if known is None:
            raise EdgeProblem(f"edge {edge_id!r} is no edge of map {self.map_id!r}", "edgeId")
        segment, fixed = known
        start, end = self._canonical(start_node, "startNodeId"), self._canonical(end_node, "endNodeId")
        first, last = self.node_at(segment, False), self.node_at(segment, True)
        if fixed is not None:  # a site's edge: one direction, its own nodes
            entry, exit_ = self.entry_node(segment, fixed), self.exit_node(segment, fixed)
            if (start, end) == (entry, exit_):
                return segment, fixed
            joins = f"from {entry!r} to {exit_!r}"
        else:  # a Tiled edge: the nodes say which way
            if (start, end) == (first, last) and (
                first != last or self._segments[segment].direction is not Direction.BACKWARD
            ):
                return segment, Traverse.FORWARD
            if (start, end) == (last, first):
                return segment, Traverse.BACKWARD
            joins = f"{first!r} and {last!r}"
        wrong = "startNodeId" if start not in (first, last) else "endNodeId"
        raise EdgeProblem(f"edge {edge_id!r} joins {joins}, not {start_node!r} to {end_node!r}", wrong)

    def _canonical(self, node_id: str, key: str) -> str:
        canonical = self._aliases.get(node_id, node_id)
        if canonical not in self.places:
            raise EdgeProblem(f"node {node_id!r} is no node of map {self.map_id!r}", key)
        return canonical


def site_graph(layout: Layout, *, map_id: str) -> SiteGraph:
    """The VDA 5050 nodes and edges of ``layout`` (``map_id``: the ``mapId`` of node positions)."""
    segments = [layout.segments[sid] for sid in sorted(layout.segments)]
    groups = _meeting_ends(segments, layout.connection_tolerance)
    site_named = bool(segments) and all(s.ends is not None for s in segments)
    named = [_site_names(group, layout.segments) for group in groups]
    uses: dict[str, int] = {}
    for names in named:
        for name in dict.fromkeys(names):
            uses[name] = uses.get(name, 0) + 1
    places: dict[str, Place] = {}
    node_of_end: dict[End, str] = {}
    aliases: dict[str, str] = {}
    for group, names in zip(groups, named, strict=True):
        own = [n for n in dict.fromkeys(names) if uses[n] == 1]  # a name two places share names neither
        node_id = own[0] if own else _generated(group[0])
        points = [_point(layout.segments[sid], at_last) for sid, at_last in group]
        x = math.fsum(p[0] for p in points) / len(points)
        y = math.fsum(p[1] for p in points) / len(points)
        places[node_id] = Place(node_id, x, y, tuple(group), tuple(own[1:]))
        for alias in own[1:]:
            aliases[alias] = node_id
        for end in group:
            node_of_end[end] = node_id
    edges: dict[str, tuple[int, Traverse | None]] = {}
    edge_of: dict[tuple[int, Traverse], str] = {}
    for segment in segments:
        if site_named:  # names: the forward edge's id, then (a two-way segment) the backward one's
            ids = segment.names[:2] if segment.names else (f"e{segment.id}",)
            for traverse, edge_id in zip((Traverse.FORWARD, Traverse.BACKWARD), ids, strict=False):
                edges[edge_id] = (segment.id, traverse)
                edge_of[(segment.id, traverse)] = edge_id
        else:
            edges[f"e{segment.id}"] = (segment.id, None)
            edge_of[(segment.id, Traverse.FORWARD)] = edge_of[(segment.id, Traverse.BACKWARD)] = f"e{segment.id}"
    return SiteGraph(
        map_id,
        MappingProxyType(places),
        site_named,
        MappingProxyType(node_of_end),
        MappingProxyType(aliases),
        MappingProxyType(edges),
        MappingProxyType(edge_of),
        layout.segments,
    )


def _meeting_ends(segments: list[Segment], tolerance: float) -> list[list[End]]:
    """The segment ends grouped by where they meet (ends that touch, transitively), each group sorted,
    groups in the order of their lowest end."""
    parent: dict[End, End] = {(s.id, at_last): (s.id, at_last) for s in segments for at_last in (False, True)}

    def root(end: End) -> End:
        while parent[end] != end:
            parent[end] = parent[parent[end]]
            end = parent[end]
        return end

    for touch in touching_endpoints(segments, tolerance):
        a, b = root((touch.a.segment.id, touch.a.at_last)), root((touch.b.segment.id, touch.b.at_last))
        if a != b:
            parent[max(a, b)] = min(a, b)
    groups: dict[End, list[End]] = {}
    for end in sorted(parent):
        groups.setdefault(root(end), []).append(end)
    return sorted(groups.values())


def _site_names(group: list[End], segments: Mapping[int, Segment]) -> list[str]:
    names = []
    for sid, at_last in group:
        ends = segments[sid].ends
        if ends is not None and ends[at_last]:
            names.append(ends[at_last])
    return names


def _generated(end: End) -> str:
    sid, at_last = end
    return f"s{sid}.{'last' if at_last else 'first'}"


def _point(segment: Segment, at_last: bool) -> tuple[float, float]:
    return segment.last if at_last else segment.first
