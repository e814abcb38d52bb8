"""Write segments as a VDA 5050 LIF 1.0 file, so a fleetsim layout can be handed to a LIF consumer.

Segment ends that meet (within the connection tolerance) share one node, placed at the first such end in
segment order. Each segment becomes one edge per direction it allows: ``forward`` first waypoint to last,
``backward`` last to first, ``both`` one edge each way (LIF edges are directed). A segment of more than
two waypoints carries them as a degree-1 NURBS trajectory through its waypoints, which
:mod:`fleetsim.load.lif.reader` samples back to the same polyline. Edge ids are the segment's names when they are
unique, else ``E<id>`` (``E<id>-back`` for the second direction). The timestamp is the current time in UTC,
or ``SOURCE_DATE_EPOCH`` when that is set (for reproducible files), unless the caller gives one.

Station sets become LIF stations, one per set: its ``stationId`` is the set's name and its interaction
nodes are the nodes its segments end at (a one-way segment's end node; a two-way segment's last node),
which is how :mod:`fleetsim.load.lif.stations` reads them back. LIF has no station weights: they are
not written.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterable, Mapping
from datetime import datetime, timezone
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np

from fleetsim.enums import Direction, Traverse
from fleetsim.layout.geometry import close_point_pairs
from fleetsim.layout.segment import Point, Segment
from fleetsim.load.common.text import write_text_atomically
from fleetsim.orders import Station

__all__ = ["DEFAULT_ROBOT_TYPE", "lif_document", "write_lif"]

DEFAULT_ROBOT_TYPE = "fleetsim/vehicle"


def write_lif(
    path: str | os.PathLike[str],
    segments: Iterable[Segment],
    *,
    layout_id: str = "layout",
    robot_type: str = DEFAULT_ROBOT_TYPE,
    connection_tolerance: float = 0.05,
    project: str = "fleetsim",
    stations: Mapping[str, Iterable[Station]] | None = None,
    timestamp: str | None = None,
) -> Path:
    """Write ``segments`` as a LIF 1.0 file with one layout; returns the path."""
    out = Path(path)
    document = lif_document(
        segments,
        layout_id=layout_id,
        robot_type=robot_type,
        connection_tolerance=connection_tolerance,
        project=project,
        stations=stations,
        timestamp=timestamp,
    )
    write_text_atomically(out, json.dumps(document, indent=1) + "\n")
    return out


def _timestamp() -> str:
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    moment = (
        datetime.fromtimestamp(int(epoch), timezone.utc) if epoch and epoch.isdigit() else datetime.now(timezone.utc)
    )
    return moment.strftime("%Y-%m-%dT%H:%M:%S.") + f"{moment.microsecond // 10000:02d}Z"


def lif_document(
    segments: Iterable[Segment],
    *,
    layout_id: str = "layout",
    robot_type: str = DEFAULT_ROBOT_TYPE,
    connection_tolerance: float = 0.05,
    project: str = "fleetsim",
    stations: Mapping[str, Iterable[Station]] | None = None,
    timestamp: str | None = None,
) -> dict[str, Any]:
    """The LIF 1.0 document of ``segments`` (see the module docstring); ``stations``: station sets by
    name; ``timestamp``: the ``exportTimestamp`` to write instead of the current time."""
    ordered = sorted(segments, key=lambda segment: segment.id)
    if not ordered:
        raise ValueError("segments must not be empty: a LIF layout needs edges")
    node_of_end, positions = _nodes(ordered, connection_tolerance)
    nodes = [
        {
            "nodeId": f"N{index + 1}",
            "nodePosition": {"x": x, "y": y},
            "vehicleTypeNodeProperties": [{"vehicleTypeId": robot_type}],
        }
        for index, (x, y) in enumerate(positions)
    ]
    names = _edge_names(ordered)
    edges = []
    for k, segment in enumerate(ordered):
        first, last = node_of_end[2 * k], node_of_end[2 * k + 1]
        ways = [(segment.waypoints, first, last)] if segment.direction is not Direction.BACKWARD else []
        if segment.direction is not Direction.FORWARD:
            ways.append((segment.waypoints[::-1], last, first))
        for (points, start, end), edge_id in zip(
            ways, names[segment.id], strict=False
        ):  # a one-way segment has one edge: the first name
            edges.append(_edge(edge_id, start, end, points, robot_type))
    return {
        "metaInformation": {
            "projectIdentification": project,
            "creator": "fleetsim",
            "exportTimestamp": _timestamp() if timestamp is None else timestamp,
            "lifVersion": "1.0.0",
        },
        "layouts": [
            {
                "layoutId": layout_id,
                "layoutVersion": "1",
                "nodes": nodes,
                "edges": edges,
                "stations": _stations(ordered, node_of_end, stations or {}),
            }
        ],
    }


def _stations(
    segments: list[Segment], node_of_end: list[int], stations: Mapping[str, Iterable[Station]]
) -> list[dict[str, Any]]:
    """One LIF station per station set, at the nodes its segments end at."""
    index = {segment.id: k for k, segment in enumerate(segments)}
    written = []
    for name in sorted(stations):
        nodes: list[str] = []
        for station in stations[name]:
            if station.segment not in index:
                msg = f"station set {name!r} names segment {station.segment}, which is not among the segments"
                raise ValueError(msg)
            k = index[station.segment]
            at_last = segments[k].allows(Traverse.FORWARD)  # where a vehicle driving it comes to its end
            node = f"N{node_of_end[2 * k + (1 if at_last else 0)] + 1}"
            if node not in nodes:
                nodes.append(node)
        if nodes:
            written.append({"stationId": name, "interactionNodeIds": nodes, "stationName": name})
    return written


def _nodes(segments: list[Segment], tolerance: float) -> tuple[list[int], list[Point]]:
    """Node index of each segment end (first, last, first, last, ...) and each node's position."""
    ends = np.array([point for segment in segments for point in (segment.first, segment.last)], dtype=np.float64)
    parent = list(range(len(ends)))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    pairs, _ = close_point_pairs(ends, tolerance)
    for i, j in pairs.tolist():
        a, b = root(i), root(j)
        if a != b:
            parent[max(a, b)] = min(a, b)  # the lowest end of a group is its root: the node's position
    index_of_root: dict[int, int] = {}
    positions: list[Point] = []
    node_of_end = []
    for end in range(len(ends)):
        r = root(end)
        if r not in index_of_root:
            index_of_root[r] = len(positions)
            positions.append((float(ends[r][0]), float(ends[r][1])))
        node_of_end.append(index_of_root[r])
    return node_of_end, positions


def _edge_names(segments: list[Segment]) -> dict[int, tuple[str, str]]:
    """Per segment, the ids of its edge along its waypoints and of its edge against them."""
    wanted = {s.id: (s.names[0] if s.names else f"E{s.id}", s.names[1] if len(s.names) > 1 else "") for s in segments}
    taken: dict[str, int] = {}
    for along, against in wanted.values():
        for name in (along, against):
            if name:
                taken[name] = taken.get(name, 0) + 1
    result = {}
    for sid, (along, against) in wanted.items():
        if taken.get(along, 0) > 1:
            along = f"E{sid}"
        if not against or taken.get(against, 0) > 1:
            against = f"{along}-back"
        result[sid] = (along, against)
    return result


def _edge(edge_id: str, start: int, end: int, points: tuple[Point, ...], robot_type: str) -> dict[str, Any]:
    prop: dict[str, Any] = {"vehicleTypeId": robot_type, "rotationAllowed": True}
    if len(points) > 2:
        # Degree 1 through every waypoint: knots at the running length, so each piece keeps its share.
        along = [0.0]
        for a, b in pairwise(points):
            along.append(along[-1] + math.dist(a, b))
        total = along[-1]
        inner = [value / total for value in along[1:-1]]
        prop["trajectory"] = {
            "degree": 1,
            "knotVector": [0.0, 0.0, *inner, 1.0, 1.0],
            "controlPoints": [{"x": x, "y": y} for x, y in points],
        }
    return {
        "edgeId": edge_id,
        "startNodeId": f"N{start + 1}",
        "endNodeId": f"N{end + 1}",
        "vehicleTypeEdgeProperties": [prop],
    }
