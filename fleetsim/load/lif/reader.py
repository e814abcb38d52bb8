"""VDA 5050 LIF (Layout Interchange Format) files as driving maps: LIF 1.0 and the 2.0 structure.

A LIF file holds layouts (1.0: ``layouts``; 2.0: ``origins[].layouts``) of nodes with positions and
directed edges between them, each edge with properties per mobile robot type (1.0:
``vehicleTypeEdgeProperties`` keyed by ``vehicleTypeId``; 2.0: ``mobileRobotTypeEdgeProperties`` listing
``mobileRobotTypes`` by ``manufacturer`` and ``seriesName``) and an optional NURBS ``trajectory``.

The chosen layout's edges usable by the chosen robot type become segments: the trajectory sampled within
the chord tolerance, or the straight line between the nodes. Two edges joining the same nodes in opposite
directions along the same path make one two-way segment; every other edge a one-way (``forward``)
segment. Segment ids are 1, 2, ... in the file order of the (first) edges; each segment keeps the edge
ids as its names. The layout's stations become station sets (:mod:`fleetsim.load.lif.stations`).
Everything fleetsim does not model is noted once per kind (:mod:`.import_notes`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fleetsim.enums import Direction, Shape
from fleetsim.errors import Location, MapError
from fleetsim.layout.geometry import point_segment_distances
from fleetsim.layout.nurbs import Nurbs, sample_nurbs
from fleetsim.layout.segment import Point, Segment
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.import_notes import ImportNotes
from fleetsim.load.common.json_at import JsonAt
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.lif.stations import lif_station_sets

__all__ = ["END_TOLERANCE", "is_lif_document", "load_lif"]

# A trajectory may end this close to its node (it is then snapped onto it); farther is an error.
END_TOLERANCE = 0.05
# Two opposite edges whose paths stay this close (two sampled curves, each within 1 cm) are one segment.
SAME_PATH_TOLERANCE = 0.02

_SILENT = {  # descriptive members: nothing to model, nothing to warn about
    "origin": {"originId", "originDescription", "originDescriptor", "layouts"},
    "layout": {
        "layoutId",
        "layoutName",
        "layoutVersion",
        "layoutLevelId",
        "layoutDescription",
        "layoutDescriptor",
        "nodes",
        "edges",
        "stations",
    },
    "node": {
        "nodeId",
        "nodeName",
        "nodeDescription",
        "nodeDescriptor",
        "mapId",
        "nodePosition",
        "vehicleTypeNodeProperties",
        "mobileRobotTypeNodeProperties",
    },
    "edge": {
        "edgeId",
        "edgeName",
        "edgeDescription",
        "edgeDescriptor",
        "startNodeId",
        "endNodeId",
        "vehicleTypeEdgeProperties",
        "mobileRobotTypeEdgeProperties",
    },
    "node property": {"vehicleTypeId", "mobileRobotTypes"},
    "edge property": {"vehicleTypeId", "mobileRobotTypes", "trajectory"},
    "node position": {"x", "y"},
}
# Values that restrict nothing (LIF's own defaults, or "anything goes"): fleetsim loses nothing by them.
_HARMLESS: dict[str, object] = {
    "rotationAllowed": True,
    "reentryAllowed": True,
    "rotationAtStartNodeAllowed": "BOTH",
    "rotationAtEndNodeAllowed": "BOTH",
}


def is_lif_document(document: object) -> bool:
    """A JSON document is LIF when its top level has ``metaInformation`` and ``layouts`` or ``origins``."""
    return (
        isinstance(document, dict)
        and "metaInformation" in document
        and ("layouts" in document or "origins" in document)
    )


@dataclass(frozen=True, slots=True)
class _Structure:
    """Key names that differ between LIF 1.0 and 2.0."""

    version: str
    node_properties: str
    edge_properties: str


_V1 = _Structure("1.0", "vehicleTypeNodeProperties", "vehicleTypeEdgeProperties")
_V2 = _Structure("2.0", "mobileRobotTypeNodeProperties", "mobileRobotTypeEdgeProperties")


@dataclass(frozen=True, slots=True)
class _Edge:
    at: JsonAt
    edge_id: str
    start: str
    end: str
    waypoints: tuple[Point, ...]


def load_lif(path: Path, document: object, options: MapOptions) -> SiteMap:
    """The segments of one layout and robot type of a parsed LIF document (see the module docstring).

    The problems of every node and edge of the chosen layout are reported together: an edge whose
    node is in no layout of the file, an edge id used twice, malformed values.
    """
    root = JsonAt(path, "", document)
    notes = ImportNotes(path)
    structure = _structure(root)
    layouts = _layouts(root, structure, notes)
    layout = _choose_layout(root, layouts, options, notes)
    layout_id = layout.need("layoutId").identifier()
    errors = ErrorCollector()
    nodes = _nodes(layout, structure, notes, errors)
    edges_at = list(layout.need("edges").items())
    _check_edges(edges_at, structure, nodes, _nodes_elsewhere(layouts, layout), errors)
    errors.raise_if_any()
    robot_type = _choose_robot_type(edges_at, structure, options, layout_id, path)
    edges: list[_Edge] = []
    for at in edges_at:
        with errors.collecting():
            edge = _edge(at, structure, robot_type, nodes, notes)
            if edge is not None:
                edges.append(edge)
    errors.raise_if_any()
    for option in ("level", "graph"):
        if getattr(options, option) is not None:
            notes.note("option-ignored", f"map option {option!r} (an RMF option)", "map_options")
    segments = _segments(edges)
    if not segments:
        whose = f" usable by {robot_type!r}" if robot_type else ""
        raise layout.error(f"layout {layout_id!r} has no edges{whose}: there is nothing to drive on")
    stations = lif_station_sets(layout, set(nodes), segments, notes)
    part = f"layout {layout_id!r}" + (f", robot type {robot_type!r}" if robot_type else "")
    return SiteMap(path, "lif", segments, notes.warnings(), None, part, stations)


# -- structure and choices ------------------------------------------------------------------------


def _structure(root: JsonAt) -> _Structure:
    root.need("metaInformation").object_value()
    if root.has("layouts") and root.has("origins"):
        raise root.error("the file has both 'layouts' (LIF 1.0) and 'origins' (LIF 2.0); keep one")
    return _V2 if root.has("origins") else _V1


def _layouts(root: JsonAt, structure: _Structure, notes: ImportNotes) -> list[JsonAt]:
    if structure is _V1:
        return list(root.need("layouts").items(allow_empty=False))
    layouts: list[JsonAt] = []
    for origin in root.need("origins").items(allow_empty=False):
        origin.need("originId").identifier()
        _note_unknown(origin, "origin", notes)
        layouts.extend(origin.need("layouts").items())
    return layouts


def _choose_layout(root: JsonAt, layouts: list[JsonAt], options: MapOptions, notes: ImportNotes) -> JsonAt:
    if not layouts:
        raise root.error("the file holds no layout")
    ids: list[str] = []
    for layout in layouts:
        layout_id = layout.need("layoutId").identifier()
        if layout_id in ids:
            raise layout.get("layoutId").error(f"layoutId {layout_id!r} is used twice")  # type: ignore[union-attr]
        ids.append(layout_id)
    if options.layout is None:
        if len(layouts) > 1:
            listed = ", ".join(map(repr, ids))
            raise root.error(
                f"the file holds {len(ids)} layouts ({listed}); choose one with map_options: {{layout: ID}}"
            )
        chosen = layouts[0]
    elif options.layout in ids:
        chosen = layouts[ids.index(options.layout)]
    else:
        listed = ", ".join(map(repr, ids))
        raise MapError(
            f"map_options.layout={options.layout!r} is not a layout of this file ({listed})"
            f"{did_you_mean(options.layout, ids)}",
            Location(root.path),
        )
    for layout, layout_id in zip(layouts, ids, strict=True):
        if layout is not chosen:
            notes.note("not-modelled", "another layout (another level or area)", f"{layout.pointer} ({layout_id!r})")
    _note_unknown(chosen, "layout", notes)
    return chosen


def _robot_types(prop: JsonAt, structure: _Structure) -> list[str]:
    if structure is _V1:
        return [prop.need("vehicleTypeId").identifier()]
    names = []
    for robot in prop.need("mobileRobotTypes").items(allow_empty=False):
        names.append(f"{robot.need('manufacturer').identifier()}/{robot.need('seriesName').identifier()}")
    return names


def _edge_properties(edge: JsonAt, structure: _Structure) -> dict[str, JsonAt]:
    """Robot type → that type's property object of this edge."""
    found: dict[str, JsonAt] = {}
    for prop in edge.need(structure.edge_properties).items():
        for robot_type in _robot_types(prop, structure):
            if robot_type in found:
                raise prop.error(f"robot type {robot_type!r} has two property objects on this edge")
            found[robot_type] = prop
    return found


def _choose_robot_type(
    edges: list[JsonAt], structure: _Structure, options: MapOptions, layout_id: str, path: Path
) -> str:
    per_edge = [_edge_properties(edge, structure) for edge in edges]
    types = sorted({name for props in per_edge for name in props})
    if options.robot_type is not None:
        if options.robot_type not in types:
            listed = ", ".join(map(repr, types)) or "none"
            msg = (
                f"map_options.robot_type={options.robot_type!r} has no edges in layout {layout_id!r} "
                f"(robot types there: {listed}){did_you_mean(options.robot_type, types)}"
            )
            raise MapError(msg, Location(path))
        return options.robot_type
    if len(types) <= 1:
        return types[0] if types else ""
    for edge, props in zip(edges, per_edge, strict=True):
        trajectories = {
            json.dumps(p.value.get("trajectory") if isinstance(p.value, dict) else None, sort_keys=True)
            for p in props.values()
        }
        if set(props) != set(types) or len(trajectories) > 1:
            listed = ", ".join(map(repr, types))
            msg = (
                f"edges differ per robot type ({listed}; this edge first); choose whose edges form the "
                "map with map_options: {robot_type: MANUFACTURER/SERIES}"
            )
            raise edge.error(msg)
    return types[0]


# -- nodes and edges ------------------------------------------------------------------------------


def _nodes(layout: JsonAt, structure: _Structure, notes: ImportNotes, errors: ErrorCollector) -> dict[str, Point]:
    """The positions of the layout's nodes by id (a broken node's problem goes to ``errors``)."""
    nodes: dict[str, Point] = {}
    for node in layout.need("nodes").items():
        with errors.collecting():
            node_id = node.need("nodeId").identifier()
            if node_id in nodes:
                raise node.need("nodeId").error(f"nodeId {node_id!r} is used twice in this layout")
            nodes[node_id] = (math.nan, math.nan)  # known from here on, so no edge to it is called dangling
            position = node.need("nodePosition")
            nodes[node_id] = (position.need("x").number(), position.need("y").number())
            _note_unknown(node, "node", notes)
            _note_unknown(position, "node position", notes)
            properties = node.get(structure.node_properties)
            for prop in properties.items() if properties is not None else ():
                _note_unknown(prop, "node property", notes)
    return nodes


def _nodes_elsewhere(layouts: list[JsonAt], chosen: JsonAt) -> dict[str, str]:
    """Node id → the id of the (first) other layout holding it. Other layouts are not checked, only read."""
    found: dict[str, str] = {}
    for layout in layouts:
        members = layout.value
        if layout is chosen or not isinstance(members, dict) or not isinstance(members.get("nodes"), list):
            continue
        layout_id = str(members.get("layoutId"))
        for node in members["nodes"]:
            if isinstance(node, dict) and isinstance(node.get("nodeId"), str):
                found.setdefault(node["nodeId"], layout_id)
    return found


def _check_edges(
    edges: list[JsonAt],
    structure: _Structure,
    nodes: dict[str, Point],
    elsewhere: dict[str, str],
    errors: ErrorCollector,
) -> None:
    """Every edge's id (unique in the layout), nodes (each in some layout of the file) and property objects."""
    first_at: dict[str, str] = {}  # edge id → pointer of the edge that has it
    for at in edges:
        with errors.collecting():
            edge_id = at.need("edgeId").identifier()
            if edge_id in first_at:
                msg = f"edgeId {edge_id!r} is used twice in this layout: by {first_at[edge_id]} and by {at.pointer}"
                errors.add(at.error(msg))
            else:
                first_at[edge_id] = at.pointer
            for key in ("startNodeId", "endNodeId"):
                with errors.collecting():
                    node_id = at.need(key).identifier()
                    if node_id not in nodes and node_id not in elsewhere:
                        known = sorted(nodes)
                        msg = (
                            f"edge {edge_id!r}: {key} {node_id!r} is not a node of any layout of this file"
                            f"{did_you_mean(node_id, known)}"
                        )
                        raise at.error(msg)
        with errors.collecting():
            _edge_properties(at, structure)


def _edge(
    at: JsonAt, structure: _Structure, robot_type: str, nodes: dict[str, Point], notes: ImportNotes
) -> _Edge | None:
    edge_id = at.need("edgeId").identifier()
    start, end = at.need("startNodeId"), at.need("endNodeId")
    start_id, end_id = start.identifier(), end.identifier()
    prop = _edge_properties(at, structure).get(robot_type) if robot_type else None
    if prop is None:
        if robot_type:
            notes.note("skipped-edge", f"an edge not usable by {robot_type!r}", at.pointer)
        return None
    if start_id not in nodes:
        raise start.error(f"startNodeId {start_id!r} is not a node of this layout (a start node must be)")
    if end_id not in nodes:
        notes.note("skipped-edge", "an edge to a node of another layout", f"{at.pointer} ({edge_id!r})")
        return None
    _note_unknown(at, "edge", notes)
    _note_unknown(prop, "edge property", notes)
    a, b = nodes[start_id], nodes[end_id]
    trajectory = prop.get("trajectory")
    if trajectory is None:
        if a == b:
            raise at.error(f"edge {edge_id!r} joins node {start_id!r} to itself without a trajectory: it has no length")
        return _Edge(at, edge_id, start_id, end_id, (a, b))
    points = _sampled(trajectory)
    for label, node_id, node, point in (("starts", start_id, a, points[0]), ("ends", end_id, b, points[-1])):
        gap = math.dist(node, point)
        if gap > END_TOLERANCE:
            msg = (
                f"the trajectory {label} at ({point[0]:g}, {point[1]:g}), {gap:.3g} m from its node "
                f"{node_id!r} at ({node[0]:g}, {node[1]:g}); it must start and end at its nodes"
            )
            raise trajectory.error(msg)
    return _Edge(at, edge_id, start_id, end_id, (a, *points[1:-1], b))


def _sampled(trajectory: JsonAt) -> tuple[Point, ...]:
    degree_at = trajectory.get("degree")
    degree = degree_at.integer() if degree_at is not None else 1
    knots = [knot.number() for knot in trajectory.need("knotVector").items()]
    control: list[Point] = []
    weights: list[float] = []
    for point in trajectory.need("controlPoints").items():
        control.append((point.need("x").number(), point.need("y").number()))
        weight = point.get("weight")
        weights.append(weight.number() if weight is not None else 1.0)
    for knot, at in zip(knots, trajectory.need("knotVector").items(), strict=True):
        if not 0.0 <= knot <= 1.0:
            raise at.error(f"knot {knot!r} is outside [0, 1]")
    try:
        curve = Nurbs.of(degree, knots, control, weights)
    except ValueError as error:
        raise trajectory.error(f"not a valid NURBS: {error}") from None
    return sample_nurbs(curve)


def _note_unknown(at: JsonAt, kind: str, notes: ImportNotes) -> None:
    members = at.object_value()
    for key in at.keys():  # noqa: SIM118 - JsonAt.keys(), not a dict's
        if key not in _SILENT[kind] and not (key in _HARMLESS and members[key] == _HARMLESS[key]):
            notes.note("not-modelled", f"{kind} attribute {key!r}", f"{at.pointer}/{key}")


# -- segments -------------------------------------------------------------------------------------


def _same_path(a: tuple[Point, ...], b: tuple[Point, ...]) -> bool:
    """Whether polylines ``a`` and ``b`` stay within the tolerance of each other (both ways)."""
    return _farthest(a, b) <= SAME_PATH_TOLERANCE and _farthest(b, a) <= SAME_PATH_TOLERANCE


def _farthest(points: tuple[Point, ...], line: tuple[Point, ...]) -> float:
    p = np.array(points)
    starts, ends = np.array(line[:-1]), np.array(line[1:])
    k, m = len(p), len(starts)
    gaps = point_segment_distances(np.repeat(p, m, axis=0), np.tile(starts, (k, 1)), np.tile(ends, (k, 1)))
    return float(gaps.reshape(k, m).min(axis=1).max())


def _segments(edges: list[_Edge]) -> tuple[Segment, ...]:
    """One segment per edge, or per pair of opposite edges along the same path, in file order."""
    open_edges: dict[tuple[str, str], list[int]] = {}  # (start, end) → indexes of unpaired edges
    partner: dict[int, int] = {}
    for index, edge in enumerate(edges):
        candidates = open_edges.get((edge.end, edge.start), [])
        match = next((c for c in candidates if _same_path(edges[c].waypoints, edge.waypoints[::-1])), None)
        if match is None:
            open_edges.setdefault((edge.start, edge.end), []).append(index)
        else:
            candidates.remove(match)
            partner[match] = index
    paired = set(partner.values())
    segments: list[Segment] = []
    for index, edge in enumerate(edges):
        if index in paired:
            continue
        other = partner.get(index)
        direction = Direction.BOTH if other is not None else Direction.FORWARD
        names = (edge.edge_id,) if other is None else (edge.edge_id, edges[other].edge_id)
        shape = Shape.STRAIGHT if len(edge.waypoints) == 2 else Shape.PATH
        segments.append(
            Segment(len(segments) + 1, shape, direction, edge.waypoints, names, ends=(edge.start, edge.end))
        )
    return tuple(segments)
