"""Open-RMF building maps (``*.building.yaml``, written by traffic-editor) as driving maps.

A building has levels; a level has vertices (``[x, y, z, name, {params}]``), measurements (two vertices
and their ``distance`` in metres) and lanes (``[start, end, {params}]``) in numbered navigation graphs
(``graph_idx``). One level and one graph become the map: each lane a straight segment, two-way when it is
``bidirectional``, else one-way from its start vertex to its end vertex. Segment ids follow lane order.
Station vertices (a dispenser, an ingestor, a parking spot, a charger) give station sets
(:mod:`fleetsim.load.rmf.stations`).

Coordinates become metres as traffic-editor's map tools do: with ``coordinate_system: reference_image``
(the default) vertices are pixels of the level's floor plan, scaled by the mean of the level's
measurements (metres per pixel) with image y pointing down (``Y = −y·scale``); with ``cartesian_meters``
they are metres already. A lane is named after its end waypoints, ``START--END`` (unnamed vertices read as
``v<index>``); a two-way lane answers to ``END--START`` too. YAML is loaded safely.

The file is not trusted: every value is checked for its type and range before it is used, and each
problem is a :class:`~fleetsim.errors.MapError` at its YAML line with its key path
(``levels.L1.lanes[3][2].graph_idx``). The problems of every vertex, measurement and lane of the chosen
level are reported together (:class:`~fleetsim.load.common.collect.ErrorCollector`).
"""

from __future__ import annotations

import math
from collections.abc import Hashable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from fleetsim.enums import Direction, Shape
from fleetsim.errors import MapError
from fleetsim.layout.segment import Point, Segment
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.import_notes import ImportNotes
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.common.yaml_source import Locate, YamlPath, load_yaml_with_marks
from fleetsim.load.rmf.stations import STATION_PARAMETERS, rmf_station_sets, station_parameter

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
_VERTEX = "[x, y, z, name, {params}]"
_EDGE = "[start vertex, end vertex, {params}]"


def key_path(where: YamlPath) -> str:
    """``("levels", "L1", "lanes", 3, 2)`` → ``"levels.L1.lanes[3][2]"`` (list positions in brackets)."""
    text = ""
    for step in where:
        if isinstance(step, int) and not isinstance(step, bool):
            text += f"[{step}]"
        else:
            text += f".{step}" if text else str(step)
    return text


class _Building:
    """The parsed document with its locator, for located errors, collected errors and notes."""

    def __init__(self, path: Path, locate: Locate) -> None:
        self.path, self.locate = path, locate
        self.notes = ImportNotes(path)
        self.errors = ErrorCollector()
        self.stations: dict[int, list[str]] = {}  # vertex index → the station sets its parameters name

    def error(self, where: YamlPath, problem: str) -> MapError:
        location = self.locate(where)
        return MapError(problem, replace(location, field=key_path(where)) if where else location)

    def line(self, where: YamlPath) -> str:
        return f"line {self.locate(where).line}"

    def mapping(self, value: object, where: YamlPath, what: str) -> dict[Any, Any]:
        if not isinstance(value, dict):
            raise self.error(where, f"{what} is {_shown(value)}; it must be a mapping")
        return value

    def items(self, value: object, where: YamlPath, what: str, form: str) -> list[Any]:
        """A list (absent or empty: no items)."""
        if value is None:
            return []
        if not isinstance(value, list):
            raise self.error(where, f"{what} is {_shown(value)}; it must be a list of {form}")
        return value

    def number(self, value: object, where: YamlPath, what: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.error(where, f"{what} is {_shown(value)}; it must be a finite number")
        return float(value)

    def text(self, value: object, where: YamlPath, what: str) -> str:
        if not isinstance(value, str):
            raise self.error(where, f"{what} is {_shown(value)}; it must be a string")
        return value


def _shown(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def load_building(path: Path, options: MapOptions) -> SiteMap:
    """The segments of one level and graph of an RMF building map (see the module docstring)."""
    data, locate = load_yaml_with_marks(path, error_type=MapError)
    building = _Building(path, locate)
    root = building.mapping(data, (), "the building map")
    system = _system(building, root)
    levels = building.mapping(root.get("levels"), ("levels",), "levels")
    if not levels:
        raise building.error(("levels",), "the building has no levels")
    name = _choose_level(building, levels, options)
    graph = 0 if options.graph is None else options.graph
    _note_building(building, root, name)
    where: YamlPath = ("levels", name)
    level = building.mapping(levels[name], where, f"level {name!r}")
    _note_level(building, level, where)
    vertices = _vertices(building, level, where)
    points, scale = _metres(building, level, where, vertices, system)
    lanes = _lanes(building, level, where, graph, points, [v[1] if v else "" for v in vertices])
    building.errors.raise_if_any()  # before "no lanes": a broken lane is the likelier cause
    if not lanes.segments:
        found = ", ".join(map(str, sorted(lanes.graphs))) or "none"
        raise building.error(
            where,
            f"level {name!r} has no lanes in graph {graph} (graphs with lanes: {found}); "
            "choose one with map_options: {graph: N}",
        )
    for option in ("layout", "robot_type"):
        if getattr(options, option) is not None:
            building.notes.note("option-ignored", f"map option {option!r} (a LIF option)", "map_options")
    labels = [v[1] if v else "" for v in vertices]
    ended = [(segment, *ends) for segment, ends in zip(lanes.segments, lanes.vertex_ends, strict=True)]
    lines = lambda index: building.line((*where, "vertices", index))  # noqa: E731 - where a station vertex is
    stations = rmf_station_sets(building.stations, labels, ended, building.notes, lines)
    return SiteMap(
        path, "rmf", tuple(lanes.segments), building.notes.warnings(), scale, f"level {name!r}, graph {graph}", stations
    )


def _system(building: _Building, root: dict[Any, Any]) -> str:
    system = root.get("coordinate_system", "reference_image")
    if not isinstance(system, str) or system not in _SYSTEMS:
        building.errors.add(
            building.error(
                ("coordinate_system",),
                f"coordinate_system {_shown(system)} is not supported (fleetsim reads {' and '.join(_SYSTEMS)})",
            )
        )
        return "cartesian_meters"  # read on, to report the level's problems too
    return system


def _choose_level(building: _Building, levels: dict[Any, Any], options: MapOptions) -> Hashable:
    """The chosen level's key as written (a level named ``1`` is the number 1 in YAML)."""
    by_name: dict[str, Hashable] = {str(key): key for key in levels}
    if options.level is None:
        first: Hashable = next(iter(levels))
        return first
    if options.level not in by_name:
        listed = ", ".join(map(repr, by_name))
        raise building.error(
            ("levels",),
            f"map_options.level={options.level!r} is not a level of this building "
            f"({listed}){did_you_mean(options.level, list(by_name))}",
        )
    return by_name[options.level]


def _note_building(building: _Building, root: dict[Any, Any], chosen: Hashable) -> None:
    for key, value in root.items():
        if key == "lifts":
            with building.errors.collecting():
                lifts = {} if value is None else building.mapping(value, ("lifts",), "lifts")
                for lift in lifts:
                    building.notes.note("not-modelled", "a lift", f"{building.line(('lifts', lift))} ({lift!r})")
        elif key not in _QUIET_BUILDING:
            building.notes.note("not-modelled", f"building key {key!r}", building.line((key,)))
    for name in root["levels"]:
        if name != chosen:
            building.notes.note("not-modelled", "another level", f"{building.line(('levels', name))} ({name!r})")


def _note_level(building: _Building, level: dict[Any, Any], where: YamlPath) -> None:
    for key, value in level.items():
        if key == "doors":
            with building.errors.collecting():
                doors = building.items(value, (*where, "doors"), "doors", "[vertex, vertex, {params}]")
                for index, _ in enumerate(doors):
                    building.notes.note("not-modelled", "a door", building.line((*where, "doors", index)))
        elif key not in _QUIET_LEVEL:
            building.notes.note("not-modelled", f"level key {key!r}", building.line((*where, key)))


# -- vertices and scale ---------------------------------------------------------------------------


def _vertices(building: _Building, level: dict[Any, Any], where: YamlPath) -> list[tuple[Point, str] | None]:
    """Each vertex's position (as written) and label; ``None`` for a broken vertex (its error collected).

    A ``vertices`` that is no list at all is raised with what was collected before it: every lane and
    measurement would otherwise be reported as naming a vertex that does not exist.
    """
    where = (*where, "vertices")
    try:
        raw = building.items(level.get("vertices"), where, "vertices", _VERTEX)
    except MapError as error:
        building.errors.add(error)
        building.errors.raise_if_any()
        raise  # unreachable: the collector holds the error
    vertices: list[tuple[Point, str] | None] = []
    for index, vertex in enumerate(raw):
        vertices.append(None)
        with building.errors.collecting():
            vertices[-1] = _vertex(building, vertex, (*where, index), index)
    return vertices


def _vertex(building: _Building, vertex: object, at: YamlPath, index: int) -> tuple[Point, str]:
    if not isinstance(vertex, list) or len(vertex) < 2:
        raise building.error(at, f"vertex {index} is {_shown(vertex)}; it must be a list {_VERTEX}")
    x = building.number(vertex[0], (*at, 0), f"vertex {index} x")
    y = building.number(vertex[1], (*at, 1), f"vertex {index} y")
    label = building.text(vertex[3], (*at, 3), f"vertex {index} name") if len(vertex) > 3 else ""
    params = building.mapping(vertex[4], (*at, 4), f"vertex {index} parameters") if len(vertex) > 4 else {}
    for key in params:
        if key not in STATION_PARAMETERS:
            building.notes.note("not-modelled", f"vertex parameter {key!r}", building.line((*at, 4, key)))
            continue
        try:
            set_name = station_parameter(key, _param(building, params[key], (*at, 4, key)))
        except ValueError as problem:
            raise building.error((*at, 4, key), f"vertex {index} {problem}") from None
        building.stations.setdefault(index, []).extend([set_name] if set_name else [])
    return (x, y), label.strip() or f"v{index}"


def _scale(
    building: _Building, level: dict[Any, Any], where: YamlPath, vertices: list[tuple[Point, str] | None]
) -> float | None:
    """Metres per pixel: the mean over the level's measurements of distance / pixel length."""
    where = (*where, "measurements")
    measurements = building.items(level.get("measurements"), where, "measurements", _EDGE)
    ratios = []
    for index, measurement in enumerate(measurements):
        with building.errors.collecting():
            ratio = _ratio(building, measurement, (*where, index), index, vertices)
            if ratio is not None:
                ratios.append(ratio)
    return math.fsum(ratios) / len(ratios) if ratios else None


def _ratio(
    building: _Building, measurement: object, at: YamlPath, index: int, vertices: list[tuple[Point, str] | None]
) -> float | None:
    """One measurement's metres per pixel; ``None`` when it joins a broken vertex (reported already)."""
    start, end, raw = _ends(building, measurement, at, len(vertices), "measurement")
    params = building.mapping(raw, (*at, 2), "measurement parameters")
    distance_at = (*at, 2, "distance")
    distance = building.number(
        _param(building, params.get("distance"), distance_at), distance_at, "measurement distance"
    )
    a, b = vertices[start], vertices[end]
    if a is None or b is None:
        return None
    pixels = math.dist(a[0], b[0])
    ratio = distance / pixels if pixels > 0 else 0.0
    if not (distance > 0 and pixels > 0 and math.isfinite(ratio) and ratio > 0):
        raise building.error(
            at,
            f"measurement {index} joins vertices {start} and {end} {pixels:g} px apart "
            f"at distance {distance:g} m; both must be positive (and give a finite scale)",
        )
    return ratio


def _metres(
    building: _Building,
    level: dict[Any, Any],
    where: YamlPath,
    vertices: list[tuple[Point, str] | None],
    system: str,
) -> tuple[list[Point | None], float | None]:
    """The vertices in metres, and the scale (metres per pixel) of a level drawn on an image."""
    scale: float | None = None
    if system == "reference_image":
        with building.errors.collecting():
            scale = _scale(building, level, where, vertices)
        if scale is None:
            # traffic-editor's tools then read pixels as metres, with a warning; so does fleetsim.
            building.notes.note(
                "not-modelled",
                "a level without measurements (its scale is unknown: pixels are read as metres)",
                building.line(where),
            )
    factor = 1.0 if scale is None else scale
    flip = -1.0 if system == "reference_image" else 1.0
    points: list[Point | None] = []
    for index, vertex in enumerate(vertices):
        point = None if vertex is None else (vertex[0][0] * factor, flip * vertex[0][1] * factor)
        if point is not None and not all(map(math.isfinite, point)):
            at = (*where, "vertices", index)
            building.errors.add(building.error(at, f"vertex {index} lies at infinity once scaled by {factor:g} m/px"))
            point = None
        points.append(point)
    return points, scale


# -- lanes ----------------------------------------------------------------------------------------


def _param(building: _Building, value: object, where: YamlPath) -> object:
    """The value of a ``[type, value]`` parameter."""
    if not isinstance(value, list) or len(value) != 2:
        raise building.error(where, f"parameter {where[-1]!r} is {_shown(value)}; it must be [type, value]")
    return value[1]


def _ends(building: _Building, edge: object, at: YamlPath, count: int, what: str) -> tuple[int, int, object]:
    """The two vertex indexes of a measurement or lane, and its parameters as written."""
    if not isinstance(edge, list) or len(edge) != 3:
        raise building.error(at, f"{what} {_shown(edge)} must be a list {_EDGE}")
    ends = []
    for position in (0, 1):
        index = edge[position]
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < count:
            indexes = f"0 to {count - 1}" if count else "the level has no vertices"
            raise building.error((*at, position), f"{what} vertex {_shown(index)} is not a vertex index ({indexes})")
        ends.append(index)
    return ends[0], ends[1], edge[2]


@dataclass(slots=True)
class _Lanes:
    """The segments made of one graph's lanes so far, the graphs any lane is in, the labels used."""

    segments: list[Segment] = field(default_factory=list)
    vertex_ends: list[tuple[int, int]] = field(default_factory=list)  # each segment's start and end vertex
    graphs: set[int] = field(default_factory=set)
    used: dict[str, int] = field(default_factory=dict)


def _lanes(
    building: _Building,
    level: dict[Any, Any],
    where: YamlPath,
    graph: int,
    points: list[Point | None],
    labels: list[str],
) -> _Lanes:
    where = (*where, "lanes")
    lanes = _Lanes()
    with building.errors.collecting():
        for index, lane in enumerate(building.items(level.get("lanes"), where, "lanes", _EDGE)):
            with building.errors.collecting():
                _lane(building, lane, (*where, index), index, graph, points, labels, lanes)
    return lanes


def _lane(
    building: _Building,
    lane: object,
    at: YamlPath,
    index: int,
    graph: int,
    points: list[Point | None],
    labels: list[str],
    lanes: _Lanes,
) -> None:
    start, end, raw = _ends(building, lane, at, len(points), "lane")
    params = building.mapping(raw, (*at, 2), "lane parameters")
    values = {key: _param(building, value, (*at, 2, key)) for key, value in params.items()}
    lane_graph = values.get("graph_idx", 0)
    if isinstance(lane_graph, bool) or not isinstance(lane_graph, int) or lane_graph < 0:
        raise building.error(
            (*at, 2, "graph_idx"), f"graph_idx is {_shown(lane_graph)}; it must be a whole number >= 0"
        )
    lanes.graphs.add(lane_graph)
    if lane_graph != graph:
        building.notes.note("not-modelled", f"a lane of another graph (graph_idx {lane_graph})", building.line(at))
        return
    two_way = values.get("bidirectional", False)
    if not isinstance(two_way, bool):
        raise building.error((*at, 2, "bidirectional"), f"bidirectional is {_shown(two_way)}; it must be true or false")
    for key, value in values.items():
        if key not in ("graph_idx", "bidirectional") and _LANE_DEFAULTS.get(key, object()) != value:
            building.notes.note("not-modelled", f"lane parameter {key!r}", building.line((*at, 2, key)))
    a, b = points[start], points[end]
    if a is None or b is None:
        return  # a broken vertex: its error is collected already
    if a == b:
        raise building.error(at, f"lane {index} joins vertices {start} and {end}, which are at the same place")
    label = f"{labels[start]}--{labels[end]}"
    count = lanes.used[label] = lanes.used.get(label, 0) + 1
    names: tuple[str, ...] = (label if count == 1 else f"{label}#{count}",)
    if two_way:
        names += (f"{labels[end]}--{labels[start]}",)
    direction = Direction.BOTH if two_way else Direction.FORWARD
    ends = (labels[start], labels[end])
    lanes.segments.append(Segment(len(lanes.segments) + 1, Shape.STRAIGHT, direction, (a, b), names, ends=ends))
    lanes.vertex_ends.append((start, end))
