"""Small LIF and RMF documents for the import tests, written from the formats' descriptions."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Any

from fleetsim.layout.layout import Layout, build_layout
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.maps.site_map import load_site_map

Json = dict[str, Any]
HALF = math.sqrt(0.5)
META_1 = {
    "projectIdentification": "test",
    "creator": "tests",
    "exportTimestamp": "2026-01-01T00:00:00.00Z",
    "lifVersion": "1.0.0",
}
META_2 = {"lifId": "test", "creator": "tests", "exportTimestamp": "2026-01-01T00:00:00.00Z", "lifVersion": "2.0.0"}


def node(node_id: str, x: float, y: float, *types: str, **extra: Any) -> Json:
    props = [{"vehicleTypeId": t} for t in (types or ("T",))]
    return {"nodeId": node_id, "nodePosition": {"x": x, "y": y}, "vehicleTypeNodeProperties": props, **extra}


def edge(edge_id: str, start: str, end: str, *types: str, trajectory: Json | None = None, **extra: Any) -> Json:
    props = []
    for t in types or ("T",):
        prop: Json = {"vehicleTypeId": t, "rotationAllowed": True}
        if trajectory is not None:
            prop["trajectory"] = copy.deepcopy(trajectory)
        prop.update(extra)
        props.append(prop)
    return {"edgeId": edge_id, "startNodeId": start, "endNodeId": end, "vehicleTypeEdgeProperties": props}


def nurbs(
    degree: int, knots: list[float], points: list[tuple[float, float]], weights: list[float] | None = None
) -> Json:
    control: list[Json] = []
    for index, (x, y) in enumerate(points):
        point: Json = {"x": x, "y": y}
        if weights is not None:
            point["weight"] = weights[index]
        control.append(point)
    return {"degree": degree, "knotVector": knots, "controlPoints": control}


def quarter(a: tuple[float, float], corner: tuple[float, float], b: tuple[float, float]) -> Json:
    """A quarter circle from ``a`` to ``b`` whose tangents meet at ``corner`` (rational quadratic)."""
    return nurbs(2, [0, 0, 0, 1, 1, 1], [a, corner, b], [1.0, HALF, 1.0])


def layout(layout_id: str, nodes: list[Json], edges: list[Json], **extra: Any) -> Json:
    return {"layoutId": layout_id, "layoutVersion": "1", "nodes": nodes, "edges": edges, "stations": [], **extra}


def lif_v1(*layouts: Json) -> Json:
    return {"metaInformation": dict(META_1), "layouts": list(layouts)}


def to_v2(document: Json) -> Json:
    """The same layouts in the LIF 2.0 structure: one origin, mobile robot types by manufacturer/series."""
    converted = copy.deepcopy(document)
    for item in converted["layouts"]:
        for n in item["nodes"]:
            props = n.pop("vehicleTypeNodeProperties")
            n["mobileRobotTypeNodeProperties"] = [
                {"mobileRobotTypes": [_robot(p.pop("vehicleTypeId"))], **p} for p in props
            ]
        for e in item["edges"]:
            props = e.pop("vehicleTypeEdgeProperties")
            for p in props:
                p.pop("rotationAllowed", None)
            e["mobileRobotTypeEdgeProperties"] = [
                {"mobileRobotTypes": [_robot(p.pop("vehicleTypeId"))], **p} for p in props
            ]
    return {"metaInformation": dict(META_2), "origins": [{"originId": "O", "layouts": converted["layouts"]}]}


def _robot(type_id: str) -> Json:
    manufacturer, _, series = type_id.partition(".")
    return {"manufacturer": manufacturer, "seriesName": series or manufacturer}


def save_json(tmp_path: Path, document: object, name: str = "site.lif.json") -> Path:
    path = tmp_path / name
    path.write_text(json.dumps(document), encoding="utf-8")
    return path


def load(tmp_path: Path, document: object, name: str = "site.lif.json", **options: Any) -> SiteMap:
    return load_site_map(save_json(tmp_path, document, name), MapOptions(**options))


def save_yaml(tmp_path: Path, text: str, name: str = "site.building.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def layout_of(site: SiteMap, radius: float = 0.5) -> Layout:
    return build_layout(site.segments, vehicle_radius=radius)


def same_layout(a: Layout, b: Layout, tolerance: float = 1e-6) -> None:
    """Assert two layouts have the same segments (ids, directions, geometry), connections, joints, conflicts."""
    assert list(a.segments) == list(b.segments)
    for sid, segment in a.segments.items():
        other = b.segments[sid]
        assert segment.direction == other.direction, sid
        assert len(segment.waypoints) == len(other.waypoints), (sid, segment.waypoints, other.waypoints)
        for p, q in zip(segment.waypoints, other.waypoints, strict=True):
            assert math.dist(p, q) <= tolerance, (sid, p, q)
    assert [(c.from_segment, c.from_traverse, c.to_segment, c.to_traverse, c.joint) for c in a.connections] == [
        (c.from_segment, c.from_traverse, c.to_segment, c.to_traverse, c.joint) for c in b.connections
    ]
    assert {sid: a.conflicts(sid) for sid in a.segments} == {sid: b.conflicts(sid) for sid in b.segments}
