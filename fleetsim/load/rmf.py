"""Open-RMF building maps (``*.building.yaml``, written by traffic-editor) as driving maps.

A building has levels; a level has vertices (``[x, y, z, name, {params}]``), measurements (two vertices
and their ``distance`` in metres) and lanes (``[start, end, {params}]``) in numbered navigation graphs
(``graph_idx``). One level and one graph become the map: each lane a straight segment, two-way when it is
``bidirectional``, else one-way from its start vertex to its end vertex. Segment ids follow lane order.

Coordinates become metres as traffic-editor's map tools do: with ``coordinate_system: reference_image``
(the default) vertices are pixels of the level's floor plan, scaled by the mean of the level's
measurements (metres per pixel) with image y pointing down (``Y = −y·scale``); with ``cartesian_meters``
they are metres already. A lane is named after its end waypoints, ``START--END`` (unnamed vertices read as
``v<index>``); a two-way lane answers to ``END--START`` too. YAML is loaded safely.
"""

from __future__ import annotations

import math
from collections.abc import Hashable
from pathlib import Path
from typing import Any

from fleetsim.enums import Direction, Shape
from fleetsim.errors import MapError
from fleetsim.layout.segment import Point, Segment
from fleetsim.load.import_notes import ImportNotes
from fleetsim.load.map_options import MapOptions, SiteMap
from fleetsim.load.scenario_files import did_you_mean
from fleetsim.load.yaml_source import Locate, load_yaml_with_marks

__all__ = ["load_building"]

_SYSTEMS = ("reference_image", "cartesian_meters")
# Building and level keys that describe the building's looks, not where vehicles drive: no warning.
_QUIET_BUILDING = {
    "name",
    "building_name",
    "coordinate_system",
    "levels",
    "reference_level_name",
    "crowd_sim",
    "graphs",
    "version",
    "parameters",
}
_QUIET_LEVEL = {
    "vertices",
    "lanes",
    "measurements",
    "drawing",
    "elevation",
    "fiducials",
    "floors",
    "walls",
    "models",
    "layers",
    "holes",
    "features",
    "constraints",
    "flattened_x_offset",
    "flattened_y_offset",
    "x_meters",
    "y_meters",
}
# Lane parameters whose default values mean "nothing to model".
_LANE_DEFAULTS: dict[str, object] = {
    "orientation": "",
    "speed_limit": 0,
    "mutex": "",
    "demo_mock_floor_name": "",
    "demo_mock_lift_name": "",
}


class _Building:
    """The parsed document with its locator, for located errors and notes."""

    def __init__(self, path: Path, data: Any, locate: Locate) -> None:
        self.path, self.data, self.locate = path, data, locate
        self.notes = ImportNotes(path)

    def error(self, where: tuple[Hashable, ...], problem: str) -> MapError:
        return MapError(problem, self.locate(where))

    def line(self, where: tuple[Hashable, ...]) -> str:
        return f"line {self.locate(where).line}"

    def mapping(self, value: object, where: tuple[Hashable, ...], what: str) -> dict[Any, Any]:
        if not isinstance(value, dict):
            raise self.error(where, f"{what} is {value!r}; it must be a mapping")
        return value

    def number(self, value: object, where: tuple[Hashable, ...], what: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.error(where, f"{what} is {value!r}; it must be a finite number")
        return float(value)


def load_building(path: Path, options: MapOptions) -> SiteMap:
    """The segments of one level and graph of an RMF building map (see the module docstring)."""
    data, locate = load_yaml_with_marks(path, error_type=MapError)
    building = _Building(path, data, locate)
    root = building.mapping(data, (), "the building map")
    system = root.get("coordinate_system", "reference_image")
    if system not in _SYSTEMS:
        raise building.error(
            ("coordinate_system",),
            f"coordinate_system {system!r} is not supported (fleetsim reads {' and '.join(_SYSTEMS)})",
        )
    levels = building.mapping(root.get("levels"), ("levels",), "levels")
    if not levels:
        raise building.error(("levels",), "the building has no levels")
    name = _choose_level(building, levels, options)
    graph = 0 if options.graph is None else options.graph
    _note_building(building, root, name)
    level = building.mapping(levels[name], ("levels", name), f"level {name!r}")
    _note_level(building, level, name)
    vertices = _vertices(building, level, name)
    points, scale = _metres(building, level, name, vertices, system)
    segments = _lanes(building, level, name, graph, points, [label for _, label in vertices])
    for option in ("layout", "robot_type"):
        if getattr(options, option) is not None:
            building.notes.note("option-ignored", f"map option {option!r} (a LIF option)", "map_options")
    return SiteMap(path, "rmf", segments, building.notes.warnings(), scale, f"level {name!r}, graph {graph}")


def _choose_level(building: _Building, levels: dict[Any, Any], options: MapOptions) -> str:
    names = [str(name) for name in levels]
    if options.level is None:
        return str(next(iter(levels)))
    if options.level not in levels:
        listed = ", ".join(map(repr, names))
        raise building.error(
            ("levels",),
            f"map_options.level={options.level!r} is not a level of this building "
            f"({listed}){did_you_mean(options.level, names)}",
        )
    return options.level


def _note_building(building: _Building, root: dict[Any, Any], chosen: str) -> None:
    for key in root:
        if key == "lifts" and root[key]:
            for lift in root[key]:
                building.notes.note("not-modelled", "a lift", f"{building.line(('lifts', lift))} ({lift!r})")
        elif key not in _QUIET_BUILDING and key != "lifts":
            building.notes.note("not-modelled", f"building key {key!r}", building.line((key,)))
    for name in root["levels"]:
        if name != chosen:
            building.notes.note("not-modelled", "another level", f"{building.line(('levels', name))} ({name!r})")


def _vertices(building: _Building, level: dict[Any, Any], name: str) -> list[tuple[Point, str]]:
    raw = level.get("vertices") or []
    where: tuple[Hashable, ...] = ("levels", name, "vertices")
    if not isinstance(raw, list):
        raise building.error(where, f"vertices is {raw!r}; it must be a list of [x, y, z, name, {{params}}]")
    vertices = []
    for index, vertex in enumerate(raw):
        at = (*where, index)
        if not isinstance(vertex, list) or len(vertex) < 2:
            raise building.error(at, f"vertex {index} is {vertex!r}; it must be a list [x, y, z, name, {{params}}]")
        x = building.number(vertex[0], (*at, 0), f"vertex {index} x")
        y = building.number(vertex[1], (*at, 1), f"vertex {index} y")
        label = vertex[3] if len(vertex) > 3 else ""
        if not isinstance(label, str):
            raise building.error((*at, 3), f"vertex {index} name is {label!r}; it must be a string")
        params = building.mapping(vertex[4], (*at, 4), f"vertex {index} parameters") if len(vertex) > 4 else {}
        for key in params:
            building.notes.note("not-modelled", f"vertex parameter {key!r}", building.line((*at, 4, key)))
        vertices.append(((x, y), label.strip() or f"v{index}"))
    return vertices


def _scale(building: _Building, level: dict[Any, Any], name: str, vertices: list[tuple[Point, str]]) -> float | None:
    """Metres per pixel: the mean over the level's measurements of distance / pixel length."""
    where: tuple[Hashable, ...] = ("levels", name, "measurements")
    ratios = []
    for index, measurement in enumerate(level.get("measurements") or []):
        at = (*where, index)
        start, end = _ends(building, measurement, at, len(vertices), "measurement")
        params = building.mapping(measurement[2], (*at, 2), "measurement parameters")
        distance = building.number(
            _param(building, params.get("distance"), (*at, 2, "distance")), (*at, 2, "distance"), "measurement distance"
        )
        pixels = math.dist(vertices[start][0], vertices[end][0])
        if pixels == 0 or distance <= 0:
            raise building.error(
                at,
                f"measurement {index} joins vertices {start} and {end} {pixels:g} px apart "
                f"at distance {distance:g} m; both must be positive",
            )
        ratios.append(distance / pixels)
    return math.fsum(ratios) / len(ratios) if ratios else None


def _metres(
    building: _Building, level: dict[Any, Any], name: str, vertices: list[tuple[Point, str]], system: str
) -> tuple[list[Point], float | None]:
    """The vertices in metres, and the scale (metres per pixel) of a level drawn on an image."""
    if system == "cartesian_meters":
        return [point for point, _ in vertices], None
    scale = _scale(building, level, name, vertices)
    if scale is None:
        # traffic-editor's tools then read pixels as metres, with a warning; so does fleetsim.
        building.notes.note(
            "not-modelled",
            "a level without measurements (its scale is unknown: pixels are read as metres)",
            building.line(("levels", name)),
        )
        scale = 1.0
    return [(x * scale, -y * scale) for (x, y), _ in vertices], scale


def _note_level(building: _Building, level: dict[Any, Any], name: str) -> None:
    for key, value in level.items():
        if key == "doors":
            for index, _ in enumerate(value or []):
                building.notes.note("not-modelled", "a door", building.line(("levels", name, "doors", index)))
        elif key not in _QUIET_LEVEL:
            building.notes.note("not-modelled", f"level key {key!r}", building.line(("levels", name, key)))


def _param(building: _Building, value: object, where: tuple[Hashable, ...]) -> object:
    """The value of a ``[type, value]`` parameter."""
    if not isinstance(value, list) or len(value) != 2:
        raise building.error(where, f"parameter {where[-1]!r} is {value!r}; it must be [type, value]")
    return value[1]


def _ends(building: _Building, edge: object, at: tuple[Hashable, ...], count: int, what: str) -> tuple[int, int]:
    if not isinstance(edge, list) or len(edge) != 3:
        raise building.error(at, f"{what} {edge!r} must be a list [start vertex, end vertex, {{params}}]")
    ends = []
    for position in (0, 1):
        index = edge[position]
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < count:
            raise building.error((*at, position), f"{what} vertex {index!r} is not a vertex index (0 to {count - 1})")
        ends.append(index)
    return ends[0], ends[1]


def _lanes(
    building: _Building, level: dict[Any, Any], name: str, graph: int, points: list[Point], labels: list[str]
) -> tuple[Segment, ...]:
    where: tuple[Hashable, ...] = ("levels", name, "lanes")
    segments: list[Segment] = []
    used: dict[str, int] = {}
    graphs: set[int] = set()
    for index, lane in enumerate(level.get("lanes") or []):
        at = (*where, index)
        start, end = _ends(building, lane, at, len(points), "lane")
        params = building.mapping(lane[2], (*at, 2), "lane parameters")
        values = {key: _param(building, value, (*at, 2, key)) for key, value in params.items()}
        lane_graph = values.get("graph_idx", 0)
        if isinstance(lane_graph, bool) or not isinstance(lane_graph, int):
            raise building.error((*at, 2, "graph_idx"), f"graph_idx is {lane_graph!r}; it must be a whole number")
        graphs.add(lane_graph)
        if lane_graph != graph:
            building.notes.note("not-modelled", f"a lane of another graph (graph_idx {lane_graph})", building.line(at))
            continue
        two_way = values.get("bidirectional", False)
        if not isinstance(two_way, bool):
            raise building.error((*at, 2, "bidirectional"), f"bidirectional is {two_way!r}; it must be true or false")
        for key, value in values.items():
            if key not in ("graph_idx", "bidirectional") and _LANE_DEFAULTS.get(key, object()) != value:
                building.notes.note("not-modelled", f"lane parameter {key!r}", building.line((*at, 2, key)))
        if points[start] == points[end]:
            raise building.error(at, f"lane {index} joins vertices {start} and {end}, which are at the same place")
        label = f"{labels[start]}--{labels[end]}"
        used[label] = used.get(label, 0) + 1
        names: tuple[str, ...] = (label if used[label] == 1 else f"{label}#{used[label]}",)
        if two_way:
            names += (f"{labels[end]}--{labels[start]}",)
        direction = Direction.BOTH if two_way else Direction.FORWARD
        segments.append(Segment(len(segments) + 1, Shape.STRAIGHT, direction, (points[start], points[end]), names))
    if not segments:
        found = ", ".join(map(str, sorted(graphs))) or "none"
        raise building.error(
            ("levels", name),
            f"level {name!r} has no lanes in graph {graph} (graphs with lanes: {found}); "
            "choose one with map_options: {graph: N}",
        )
    return tuple(segments)
