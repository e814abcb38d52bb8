"""Load a driving map drawn in Tiled (TMX or JSON) into segments in world metres (SPEC §3).

Parsed by hand with :mod:`json` and :mod:`xml.etree` because the available Tiled parsers mishandle object
templates. The pipeline: read the document → walk (nested) object layers summing offsets → resolve each
object against its template → keep visible polylines whose class is a shape → transform to the world
frame (origin at the map centre, y up, so RViz shows what Tiled shows).

A polyline of class ``path`` is a free-form segment of any number of points. A polyline whose class
names no shape is an error (with a "did you mean"): a typo must not silently drop
a segment. A polyline with no class at all, and every other object, is ignored.

Every broken object is reported, each by its first problem, together with the header's and the layers'
problems, in the order of the file (a :class:`~fleetsim.load.common.collect.ErrorCollector`); a map with any
error gives no segments at all.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from fleetsim.enums import Direction, Shape
from fleetsim.errors import Location, MapError
from fleetsim.layout.segment import Point, Segment
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.stations import NO_STATIONS, StationSets, station_sets
from fleetsim.load.common.text import read_text_file
from fleetsim.load.tiled.header import MapHeader, read_header
from fleetsim.load.tiled.stations import segment_stations, station_note
from fleetsim.load.tiled.templates import (
    ObjectFields,
    PropertyValue,
    TemplateCache,
    as_bool,
    as_number,
    json_properties,
    parse_json,
    parse_xml,
    read_json_object,
    read_xml_object,
    xml_properties,
)
from fleetsim.orders import Station

__all__ = ["MAP_SUFFIXES", "MAX_OBJECT_ID", "TiledMap", "load_map", "parse_direction", "parse_shape"]

MAP_SUFFIXES = (".json", ".tmj", ".tmx")
MAX_OBJECT_ID = 2**31 - 1  # Tiled keeps object ids in a signed 32-bit int

_SHAPES = {
    "straight": Shape.STRAIGHT,
    "curve": Shape.CURVE,
    "s_curve": Shape.S_CURVE,
    "scurve": Shape.S_CURVE,
    "path": Shape.PATH,
}
_DIRECTIONS = {
    "both": Direction.BOTH,
    "bidirectional": Direction.BOTH,
    "two_way": Direction.BOTH,
    "forward": Direction.FORWARD,
    "backward": Direction.BACKWARD,
}
# The order of the values of the `direction` enum in fleetsim.tiled-project (int storage = index).
_DIRECTION_ENUM = (Direction.BOTH, Direction.FORWARD, Direction.BACKWARD)


@dataclass(frozen=True, slots=True)
class TiledMap:
    """A loaded map: its segments (sorted by id, world metres), its station sets (the segments' ``station``
    properties, :mod:`fleetsim.load.tiled.stations`) and what the loader had to say."""

    path: Path
    segments: tuple[Segment, ...]
    meters_per_pixel: float
    width_px: float
    height_px: float
    warnings: tuple[str, ...]
    stations: StationSets = field(default_factory=lambda: NO_STATIONS)


@dataclass(frozen=True, slots=True)
class _Placed:
    """An object as read from its layer, with the summed offsets of the layers around it."""

    fields: ObjectFields
    offset: Point
    layer: str  # "group/layer", for messages
    index: int  # position within its layer, for messages about objects without an id


def _word(text: str) -> str:
    return text.strip().lower().replace("-", "_")


def parse_shape(shape_class: str) -> Shape | None:
    """The shape a Tiled class names (case-insensitive, ``scurve``/``s-curve`` too), else ``None``."""
    return _SHAPES.get(_word(shape_class))


def parse_direction(raw: PropertyValue, where: Location) -> Direction:
    """A ``direction`` property value: a name (or alias), or an index into the Tiled enum."""
    if raw is None:
        return Direction.BOTH
    if isinstance(raw, int) and not isinstance(raw, bool):
        if 0 <= raw < len(_DIRECTION_ENUM):
            return _DIRECTION_ENUM[raw]
        msg = f"the direction property is {raw!r}; as an enum index it must be 0, 1 or 2 (both, forward, backward)"
        raise MapError(msg, where)
    direction = _DIRECTIONS.get(_word(raw)) if isinstance(raw, str) else None
    if direction is not None:
        return direction
    msg = f"unknown direction {raw!r} (expected both, forward or backward)"
    raise MapError(msg, where)


def load_map(path: str | os.PathLike[str]) -> TiledMap:
    """Load a Tiled map; every problem with the file is a [`MapError`][fleetsim.errors.MapError].

    The problems of every object are reported together (with those of the map's header and layers):
    one is raised as itself, several as one [`LoadErrors`][fleetsim.errors.LoadErrors], at most 50 per
    file. A file that cannot be read as a map at all stops at that one error.
    """
    map_path = Path(path)
    suffix = map_path.suffix.lower()
    if suffix not in MAP_SUFFIXES:
        msg = f"this is not a Tiled map file: a map is saved as {', '.join(MAP_SUFFIXES[:-1])} or {MAP_SUFFIXES[-1]}, and this file ends in {map_path.suffix or 'no suffix'!r}"
        raise MapError(msg, Location(map_path))
    text = read_text_file(map_path, MapError)
    errors = ErrorCollector()
    if suffix == ".tmx":
        header, placed = _read_tmx(text, map_path, errors)
    else:
        header, placed = _read_json(text, map_path, errors)
    segments, warnings, stations = _segments(placed, header, map_path, errors)
    return TiledMap(
        path=map_path,
        segments=segments,
        meters_per_pixel=header.meters_per_pixel,
        width_px=header.width_px,
        height_px=header.height_px,
        warnings=warnings,
        stations=stations,
    )


# --- documents -----------------------------------------------------------------------------------
# The layer walkers are generators that _segments consumes, so the errors of layers and of objects
# are collected in the order of the file.


def _read_tmx(text: str, path: Path, errors: ErrorCollector) -> tuple[MapHeader, Iterator[_Placed]]:
    root = parse_xml(text, path)
    if root.tag != "map":
        raise MapError(f"root element <{root.tag}> must be <map>", Location(path))
    properties: dict[str, PropertyValue] = {}
    with errors.collecting():
        properties = xml_properties(root, Location(path))
    header = read_header(root.attrib, properties, path, errors)
    return header, _tmx_layers(root, (0.0, 0.0), "", path, errors)


def _layer_offset(attrs: Mapping[str, object], offset: Point, name: str, where: Location) -> Point:
    dx = as_number(attrs.get("offsetx", 0), f"layer {name!r} offsetx", where)
    dy = as_number(attrs.get("offsety", 0), f"layer {name!r} offsety", where)
    return (offset[0] + dx, offset[1] + dy)


def _visible_offset(
    attrs: Mapping[str, object], default_visible: object, offset: Point, name: str, where: Location
) -> Point | None:
    """The layer's summed offset, or ``None`` for a hidden layer."""
    if not as_bool(attrs.get("visible", default_visible), f"layer {name!r} visible", where):
        return None
    return _layer_offset(attrs, offset, name, where)


def _tmx_layers(
    parent: ET.Element, offset: Point, prefix: str, path: Path, errors: ErrorCollector
) -> Iterator[_Placed]:
    where = Location(path)
    for layer in parent:
        if layer.tag not in ("group", "objectgroup"):
            continue  # tile and image layers carry no segments
        name = prefix + layer.get("name", "")
        inner: Point | None = None
        with errors.collecting():  # a bad layer attribute skips the layer, not the map
            inner = _visible_offset(layer.attrib, "1", offset, name, where)
        if inner is None:
            continue
        if layer.tag == "group":
            yield from _tmx_layers(layer, inner, name + "/", path, errors)
            continue
        for index, element in enumerate(layer.findall("object")):
            try:  # not errors.collecting(): this loop runs once per object of a map
                fields = read_xml_object(element, path)
            except MapError as error:
                errors.add(error)
                continue
            yield _Placed(fields, inner, name, index)


def _read_json(text: str, path: Path, errors: ErrorCollector) -> tuple[MapHeader, Iterator[_Placed]]:
    document = parse_json(text, path)
    where = Location(path)
    if not isinstance(document, dict):
        raise MapError("a JSON map must be an object", where)
    if document.get("type", "map") != "map":
        raise MapError(f"this JSON file is not a Tiled map: its type is {document.get('type')!r}, not 'map'", where)
    properties: dict[str, PropertyValue] = {}
    with errors.collecting():
        properties = json_properties(document.get("properties"), where)
    header = read_header(document, properties, path, errors)
    return header, _json_layers(document, (0.0, 0.0), "", path, errors)


def _json_list(container: Mapping[str, object], key: str, where: Location, errors: ErrorCollector) -> list[object]:
    value = container.get(key, [])
    if not isinstance(value, list):
        errors.add(MapError(f"{key} is {value!r}; it must be a list", where))
        return []
    return value


def _json_layers(
    parent: Mapping[str, object], offset: Point, prefix: str, path: Path, errors: ErrorCollector
) -> Iterator[_Placed]:
    where = Location(path)
    for layer in _json_list(parent, "layers", where, errors):
        if not isinstance(layer, dict):
            errors.add(MapError(f"layer {layer!r} must be a JSON object", where))
            continue
        kind = layer.get("type")
        if kind not in ("group", "objectgroup"):
            continue  # tile and image layers carry no segments
        name = prefix + str(layer.get("name", ""))
        inner: Point | None = None
        with errors.collecting():  # a bad layer attribute skips the layer, not the map
            inner = _visible_offset(layer, True, offset, name, where)
        if inner is None:
            continue
        if kind == "group":
            yield from _json_layers(layer, inner, name + "/", path, errors)
            continue
        for index, obj in enumerate(_json_list(layer, "objects", where, errors)):
            try:  # not errors.collecting(): this loop runs once per object of a map
                fields = read_json_object(obj, path)
            except MapError as error:
                errors.add(error)
                continue
            yield _Placed(fields, inner, name, index)


# --- segments ------------------------------------------------------------------------------------


def _describe(placed: _Placed) -> str:
    return f"object #{placed.index + 1} in layer {placed.layer!r}"


def _check_unique_id(item: _Placed, first_with: dict[int, _Placed], path: Path) -> None:
    """``item``'s id is not one an earlier object has (all objects count, hidden ones and non-segments too)."""
    object_id = item.fields.id
    if object_id is None:
        return
    if object_id in first_with:
        msg = (
            f"id={object_id!r} is used by two objects ({_describe(first_with[object_id])} and "
            f"{_describe(item)}); object ids must be unique"
        )
        raise MapError(msg, Location(path, object_id=object_id))
    first_with[object_id] = item


def _world_points(
    polyline: tuple[Point, ...], fields: ObjectFields, offset: Point, header: MapHeader
) -> tuple[Point, ...]:
    """Rotate the polyline about the object's origin (clockwise on screen), shift, scale, flip y."""
    x = (fields.x or 0.0) + offset[0]
    y = (fields.y or 0.0) + offset[1]
    cos, sin = _cos_sin(fields.rotation or 0.0)
    half_w, half_h, s = header.width_px / 2, header.height_px / 2, header.meters_per_pixel
    # In Tiled's y-down frame the usual rotation matrix turns clockwise on screen.
    return tuple(
        ((x + px * cos - py * sin - half_w) * s, (half_h - (y + px * sin + py * cos)) * s) for px, py in polyline
    )


_QUARTER_TURNS = {0.0: (1.0, 0.0), 90.0: (0.0, 1.0), 180.0: (-1.0, 0.0), 270.0: (0.0, -1.0)}


def _cos_sin(degrees: float) -> tuple[float, float]:
    """Exact for quarter turns, so a rotated straight stays exactly axis-aligned."""
    exact = _QUARTER_TURNS.get(degrees % 360.0)
    if exact is not None:
        return exact
    radians = math.radians(degrees)
    return math.cos(radians), math.sin(radians)


def _segment(fields: ObjectFields, shape: Shape, placed: _Placed, header: MapHeader, path: Path) -> Segment:
    if fields.id is None:
        raise MapError(f"{_describe(placed)} is a {shape.value} polyline without an id", Location(path))
    where = Location(path, object_id=fields.id)
    if not 0 < fields.id <= MAX_OBJECT_ID:
        msg = f"the object's id is {fields.id!r}; Tiled ids are positive integers up to {MAX_OBJECT_ID}"
        raise MapError(msg, where)
    polyline = fields.polyline or ()
    if len(polyline) < 2:
        msg = f"polyline has {len(polyline)} point(s); a segment needs at least 2"
        raise MapError(msg, where)
    if polyline.count(polyline[0]) == len(polyline):
        msg = f"polyline has zero length (all {len(polyline)} points at {polyline[0]!r})"
        raise MapError(msg, where)
    direction = parse_direction(fields.properties.get("direction"), where)
    names: tuple[str, ...] = (fields.name.strip(),) if fields.name and fields.name.strip() else ()
    other = fields.properties.get("other_name")  # the second name of a merged two-way LIF edge pair
    if names and isinstance(other, str) and other.strip():
        names += (other.strip(),)
    return Segment(fields.id, shape, direction, _world_points(polyline, fields, placed.offset, header), names)


def _unknown_class(fields: ObjectFields, placed: _Placed, path: Path) -> MapError:
    """A polyline whose class names no shape: a typo would otherwise silently drop a segment."""
    shape_class = fields.shape_class or ""
    hint = did_you_mean(_word(shape_class), [shape.value for shape in Shape])
    what = "" if fields.id is not None else f"{_describe(placed)}: "  # the location names the id
    msg = (
        f"{what}unknown class {shape_class!r} on a polyline{hint} (segments are polylines of class "
        "straight, curve, s_curve or path; clear the class to have fleetsim ignore this polyline)"
    )
    return MapError(msg, Location(path, object_id=fields.id))


def _segments(
    placed: Iterable[_Placed], header: MapHeader, path: Path, errors: ErrorCollector
) -> tuple[tuple[Segment, ...], tuple[str, ...], StationSets]:
    """Every object's segment, or every object's error: nothing is returned for a map with any error."""
    templates = TemplateCache(path)
    first_with: dict[int, _Placed] = {}
    segments: list[Segment] = []
    warnings: list[str] = []
    stations: list[tuple[str, Station]] = []
    for item in placed:
        try:  # each object is reported once, by its first problem
            _check_unique_id(item, first_with, path)
            _take(item, templates, header, path, (segments, warnings, stations))
        except MapError as error:
            errors.add(error)
    errors.raise_if_any()
    if not segments:
        msg = "the map has no segments (visible polyline objects of class straight, curve, s_curve or path)"
        raise MapError(msg, Location(path))
    segments.sort(key=lambda segment: segment.id)
    return tuple(segments), tuple(warnings), station_sets(stations)


_Found = tuple[list[Segment], list[str], list[tuple[str, Station]]]  # segments, warnings, station set members


def _take(item: _Placed, templates: TemplateCache, header: MapHeader, path: Path, found: _Found) -> None:
    """Add ``item``'s segment and stations (or a warning about it); a broken object raises its MapError."""
    segments, warnings, stations = found
    fields = templates.resolve(item.fields)
    if fields is None or fields.visible is False:
        return  # None: its template is broken, which was reported at its first instance
    shape = parse_shape(fields.shape_class) if fields.shape_class else None
    where = Location(path, object_id=fields.id)
    if fields.geometry != "polyline":
        geometry = fields.geometry or "rectangle"
        if shape is not None:
            warnings.append(f"{where}: class {fields.shape_class!r} on a {geometry}, not a polyline; ignored")
        note = station_note(geometry, fields.properties, where)
        warnings += [note] if note is not None else []
        return
    if shape is None:
        if fields.shape_class:
            raise _unknown_class(fields, item, path)
        note = station_note("polyline without a class", fields.properties, where)
        warnings += [note] if note is not None else []
        return  # a polyline without a class is a drawing aid, not a segment
    segment = _segment(fields, shape, item, header, path)
    segments.append(segment)
    stations += segment_stations(segment.id, fields.properties, where)
