"""Reading Tiled objects from TMX or JSON, and resolving their object templates (SPEC §3).

Both map formats are turned into one neutral form, :class:`ObjectFields`, in which every key is either
what the file states or ``None`` for "not stated here". That lets a template instance be resolved key by
key — the instance wins, else the template, else the default — whichever format either file is in.
Every malformed value becomes a :class:`~fleetsim.errors.MapError` naming file, object id and value.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TypeVar

from fleetsim.errors import Location, MapError
from fleetsim.load.common.text import json_problem, read_text_file

__all__ = [
    "ObjectFields",
    "PropertyValue",
    "TemplateCache",
    "as_bool",
    "as_int",
    "as_number",
    "json_properties",
    "parse_json",
    "parse_xml",
    "read_json_object",
    "read_xml_object",
    "xml_properties",
]

PropertyValue = str | int | float | bool | None
Point = tuple[float, float]
T = TypeVar("T")

_NO_PROPERTIES: Mapping[str, PropertyValue] = MappingProxyType({})


@dataclass(frozen=True, slots=True)
class ObjectFields:
    """What one Tiled object (or a template's object) states; ``None`` means "not stated here"."""

    id: int | None = None
    shape_class: str | None = None
    x: float | None = None
    y: float | None = None
    rotation: float | None = None
    visible: bool | None = None
    geometry: str | None = None  # "polyline", "polygon", "ellipse", "point", "text" or "tile"
    polyline: tuple[Point, ...] | None = None  # only set together with geometry "polyline"
    properties: Mapping[str, PropertyValue] = field(default_factory=lambda: _NO_PROPERTIES)
    template: str | None = None
    name: str | None = None  # the object's name; Tiled writes "" for none, read as not stated

    def over(self, template: ObjectFields) -> ObjectFields:
        """This instance resolved against ``template``: each key stated here wins; properties merge."""
        # Geometry and its points travel together: an instance that states a polygon does not keep
        # the template's polyline points.
        shape = self if self.geometry is not None else template
        return ObjectFields(
            id=self.id,
            shape_class=_first(self.shape_class, template.shape_class),
            x=_first(self.x, template.x),
            y=_first(self.y, template.y),
            rotation=_first(self.rotation, template.rotation),
            visible=_first(self.visible, template.visible),
            geometry=shape.geometry,
            polyline=shape.polyline,
            properties=MappingProxyType({**template.properties, **self.properties}),
            template=self.template,
            name=_first(self.name, template.name),
        )


def _first(mine: T | None, theirs: T | None) -> T | None:
    return theirs if mine is None else mine


# --- values --------------------------------------------------------------------------------------
# TMX stores every value as text and JSON as typed values; one set of converters accepts both so the
# two readers stay symmetric. Booleans are never numbers here, although Python says they are.


def as_number(raw: object, name: str, where: Location) -> float:
    """A finite float from a JSON number or a TMX text."""
    value: float | None = None
    if isinstance(raw, (int, float, str)) and not isinstance(raw, bool):
        try:
            value = float(raw)
        except (ValueError, OverflowError):  # OverflowError: a JSON integer beyond any float
            value = None
    if value is None or not math.isfinite(value):
        msg = f"{name} is {raw!r}; it must be a number"
        raise MapError(msg, where)
    return value


def as_int(raw: object, name: str, where: Location) -> int:
    """An integer from a JSON number or a TMX text (an integral float like ``7.0`` is accepted)."""
    if isinstance(raw, int) and not isinstance(raw, bool):
        return raw
    if isinstance(raw, str):
        with contextlib.suppress(ValueError):  # not an integer text: reported below
            return int(raw.strip())
    if isinstance(raw, float) and raw.is_integer():
        return int(raw)
    msg = f"{name} is {raw!r}; it must be an integer"
    raise MapError(msg, where)


_BOOL_TEXT = {"1": True, "true": True, "0": False, "false": False}


def as_bool(raw: object, name: str, where: Location) -> bool:
    """A boolean from JSON ``true``/``false``/``0``/``1`` or TMX ``"1"``/``"0"``/``"true"``/``"false"``."""
    if isinstance(raw, bool):
        return raw
    if isinstance(raw, int) and raw in (0, 1):
        return bool(raw)
    if isinstance(raw, str) and raw.strip().lower() in _BOOL_TEXT:
        return _BOOL_TEXT[raw.strip().lower()]
    msg = f"{name} is {raw!r}; it must be a boolean (true/false or 1/0)"
    raise MapError(msg, where)


def _as_str(raw: object, name: str, where: Location) -> str:
    if not isinstance(raw, str):
        msg = f"{name} is {raw!r}; it must be a string"
        raise MapError(msg, where)
    return raw


def _typed(kind: object, raw: object, name: str, where: Location) -> PropertyValue:
    """A property value converted by its declared Tiled type (TMX writes ``type="int" value="1"``)."""
    label = f"property {name!r} value"
    if kind == "int":
        return as_int(raw, label, where)
    if kind == "float":
        return as_number(raw, label, where)
    if kind == "bool":
        return as_bool(raw, label, where)
    if kind == "class":
        return None  # a Tiled 1.9+ class value (nested members) carries nothing fleetsim reads
    if raw is None or isinstance(raw, (str, int, float, bool)):
        return raw
    msg = f"property {name!r} has the value {raw!r}; it must be a string, number or boolean"
    raise MapError(msg, where)


# --- files ---------------------------------------------------------------------------------------


def parse_json(text: str, path: Path, object_id: int | None = None) -> object:
    """The parsed document; a syntax error is a MapError with the parser's line and column."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        where = Location(path, line=exc.lineno, column=exc.colno, object_id=object_id)
        raise MapError(json_problem(exc), where) from None
    except (ValueError, RecursionError) as exc:  # an integer too long to convert; absurd nesting
        raise MapError(f"unreadable JSON: {exc}", Location(path, object_id=object_id)) from None


def parse_xml(text: str, path: Path, object_id: int | None = None) -> ET.Element:
    """The root element; a syntax error is a MapError with the parser's line and column."""
    try:
        return ET.fromstring(text)
    except ET.ParseError as exc:
        line, column = exc.position
        # expat counts columns from 0; editors count from 1.
        where = Location(path, line=line, column=column + 1, object_id=object_id)
        raise MapError(f"malformed XML: {exc}", where) from None


# --- properties ----------------------------------------------------------------------------------


def xml_properties(element: ET.Element, where: Location) -> dict[str, PropertyValue]:
    """The ``<properties>`` child of a TMX element, typed by each property's ``type`` attribute."""
    result: dict[str, PropertyValue] = {}
    block = element.find("properties")
    if block is None:
        return result
    for prop in block.findall("property"):  # not iter(): class values nest <property>
        name = prop.get("name")
        if name is None:
            raise MapError("a <property> has no name", where)
        # Multi-line strings are stored as element text instead of a value attribute.
        raw = prop.get("value", prop.text or "")
        result[name] = _typed(prop.get("type", "string"), raw, name, where)
    return result


def json_properties(raw: object, where: Location) -> dict[str, PropertyValue]:
    """A JSON ``properties`` list (``[{"name", "type", "value"}, ...]``), typed by ``type``."""
    result: dict[str, PropertyValue] = {}
    if raw is None:
        return result
    if not isinstance(raw, list):
        msg = f"properties is {raw!r}; it must be a list of {{name, type, value}} objects"
        raise MapError(msg, where)
    for prop in raw:
        if not isinstance(prop, dict) or not isinstance(prop.get("name"), str):
            msg = f"property {prop!r} must be an object with a string 'name'"
            raise MapError(msg, where)
        name = prop["name"]
        result[name] = _typed(prop.get("type", "string"), prop.get("value"), name, where)
    return result


# --- objects -------------------------------------------------------------------------------------

_XML_GEOMETRIES = ("polyline", "polygon", "ellipse", "point", "text")


def _optional(raw: object, convert: Callable[[object, str, Location], T], name: str, where: Location) -> T | None:
    return None if raw is None else convert(raw, name, where)


def _xml_points(text: str, where: Location) -> tuple[Point, ...]:
    pairs = [pair.split(",") for pair in text.split()]
    # Fast path first: benchmark maps hold hundreds of thousands of points.
    if all(len(pair) == 2 for pair in pairs):
        try:
            flat = [float(coordinate) for pair in pairs for coordinate in pair]
        except ValueError:
            flat = []
        if len(flat) == 2 * len(pairs) and all(map(math.isfinite, flat)):
            return tuple(zip(flat[::2], flat[1::2], strict=True))
    for pair in pairs:  # slow path: find the culprit for the message
        if len(pair) != 2:
            msg = f"the points are {text!r}; they must be 'x,y' pairs separated by spaces"
            raise MapError(msg, where)
        as_number(pair[0], "point x", where)
        as_number(pair[1], "point y", where)
    raise AssertionError("unreachable: the fast path rejected valid points")  # pragma: no cover


def read_xml_object(element: ET.Element, path: Path, owner_id: int | None = None) -> ObjectFields:
    """One TMX ``<object>`` (``owner_id`` names the instance when reading a template's object)."""
    object_id = _optional(element.get("id"), as_int, "id", Location(path, object_id=owner_id))
    where = Location(path, object_id=owner_id if owner_id is not None else object_id)
    geometry: str | None = "tile" if element.get("gid") is not None else None
    polyline = None
    for kind in _XML_GEOMETRIES:
        child = element.find(kind)
        if child is not None:
            geometry = kind
            if kind == "polyline":
                polyline = _xml_points(child.get("points", ""), where)
            break
    # Tiled <= 1.8 and >= 1.10 write "type"; 1.9 wrote "class".
    shape_class = element.get("type", element.get("class"))
    return ObjectFields(
        id=object_id,
        shape_class=shape_class,
        x=_optional(element.get("x"), as_number, "x", where),
        y=_optional(element.get("y"), as_number, "y", where),
        rotation=_optional(element.get("rotation"), as_number, "rotation", where),
        visible=_optional(element.get("visible"), as_bool, "visible", where),
        geometry=geometry,
        polyline=polyline,
        properties=MappingProxyType(xml_properties(element, where)),
        template=element.get("template"),
        name=element.get("name") or None,
    )


def _json_points(raw: object, where: Location) -> tuple[Point, ...]:
    if not isinstance(raw, list):
        raise MapError(f"the polyline is {raw!r}; it must be a list of {{x, y}} points", where)
    # Fast path first (plain finite numbers throughout), as in _xml_points.
    try:
        flat = [point[axis] for point in raw for axis in ("x", "y")]
    except (TypeError, KeyError, IndexError):
        flat = []
    if len(flat) == 2 * len(raw) and set(map(type, flat)) <= {int, float} and all(map(math.isfinite, flat)):
        return tuple(zip(map(float, flat[::2]), map(float, flat[1::2]), strict=True))
    points = []
    for point in raw:
        if not isinstance(point, dict):
            raise MapError(f"polyline point {point!r} must be an object with x and y", where)
        points.append((as_number(point.get("x"), "point x", where), as_number(point.get("y"), "point y", where)))
    return tuple(points)


def _json_geometry(obj: dict[str, object]) -> str | None:
    if "gid" in obj:
        return "tile"
    for kind in ("polyline", "polygon", "text"):
        if kind in obj:
            return kind
    for kind in ("ellipse", "point"):
        if obj.get(kind) is True:
            return kind
    return None


def read_json_object(obj: object, path: Path, owner_id: int | None = None) -> ObjectFields:
    """One JSON map object (``owner_id`` names the instance when reading a template's object)."""
    if not isinstance(obj, dict):
        raise MapError(f"object {obj!r} must be a JSON object", Location(path, object_id=owner_id))
    object_id = _optional(obj.get("id"), as_int, "id", Location(path, object_id=owner_id))
    where = Location(path, object_id=owner_id if owner_id is not None else object_id)
    geometry = _json_geometry(obj)
    # Tiled <= 1.8 and >= 1.10 write "type"; 1.9 wrote "class".
    shape_class = obj["type"] if "type" in obj else obj.get("class")
    return ObjectFields(
        id=object_id,
        shape_class=_optional(shape_class, _as_str, "type", where),
        x=_optional(obj.get("x"), as_number, "x", where),
        y=_optional(obj.get("y"), as_number, "y", where),
        rotation=_optional(obj.get("rotation"), as_number, "rotation", where),
        visible=_optional(obj.get("visible"), as_bool, "visible", where),
        geometry=geometry,
        polyline=_json_points(obj["polyline"], where) if geometry == "polyline" else None,
        properties=MappingProxyType(json_properties(obj.get("properties"), where)),
        template=_optional(obj.get("template"), _as_str, "template", where),
        name=_optional(obj.get("name"), _as_str, "name", where) or None,
    )


# --- templates -----------------------------------------------------------------------------------


class TemplateCache:
    """Object templates read during one map load; a map may reference one template thousands of times.

    A template that cannot be read is reported once, at the first object that uses it: the one fix
    repairs every other instance, so repeating its error for each of them would only bury other errors.
    """

    __slots__ = ("_base", "_broken", "_map_path", "_parsed")

    def __init__(self, map_path: Path) -> None:
        self._map_path = map_path
        self._base = map_path.parent
        self._parsed: dict[str, ObjectFields] = {}
        self._broken: set[str] = set()

    def resolve(self, instance: ObjectFields) -> ObjectFields | None:
        """``instance`` with its template's keys filled in (unchanged when it names no template).

        A template that cannot be read raises its :class:`~fleetsim.errors.MapError` for the first
        instance; later instances of it resolve to ``None`` (already reported).
        """
        if instance.template is None:
            return instance
        # Tiled writes "/" but maps made on Windows by hand may hold "\"; both are relative to the map.
        template_path = self._base / instance.template.replace("\\", "/")
        key = os.path.normpath(template_path)
        template = self._parsed.get(key)
        if template is None:
            if key in self._broken:
                return None
            try:
                template = self._load(template_path, instance)
            except MapError:
                self._broken.add(key)
                raise
            self._parsed[key] = template
        return instance.over(template)

    def _load(self, template_path: Path, instance: ObjectFields) -> ObjectFields:
        if not template_path.is_file():
            msg = f"template {instance.template!r} not found (looked for {str(template_path)!r})"
            raise MapError(msg, Location(self._map_path, object_id=instance.id))
        text = read_text_file(template_path, MapError, Location(self._map_path, object_id=instance.id))
        # Sniffed by content, not suffix: either template format works from either map format.
        if text.lstrip().startswith("{"):
            return _json_template(text, template_path, instance.id)
        return _xml_template(text, template_path, instance.id)


def _xml_template(text: str, path: Path, owner_id: int | None) -> ObjectFields:
    root = parse_xml(text, path, owner_id)
    where = Location(path, object_id=owner_id)
    if root.tag != "template":
        raise MapError(f"root element <{root.tag}> must be <template>", where)
    element = root.find("object")  # a <tileset> sibling (tile templates) is irrelevant here
    if element is None:
        raise MapError("template has no <object>", where)
    return read_xml_object(element, path, owner_id)


def _json_template(text: str, path: Path, owner_id: int | None) -> ObjectFields:
    document = parse_json(text, path, owner_id)
    where = Location(path, object_id=owner_id)
    if not isinstance(document, dict) or document.get("type", "template") != "template":
        raise MapError('a JSON template must be an object with "type": "template"', where)
    if not isinstance(document.get("object"), dict):
        raise MapError(f"the template's object is {document.get('object')!r}; it must be a JSON object", where)
    return read_json_object(document["object"], path, owner_id)
