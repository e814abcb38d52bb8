"""Reading and writing VDA 5050 messages (2.0 and 2.1): the wire's JSON to and from fleetsim's models.

:func:`decode_order` and :func:`decode_instant_actions` check an incoming payload against the text's
message tables (required keys, types, ranges, enumerations) in one pass and raise :class:`MessageInvalid`
with every problem found, each a ``validationError`` a vehicle can put in its state as it is. Unknown keys
are ignored, as the text allows, except misspellings seen in the wild, which would otherwise be lost
silently: ``instantActions`` in place of ``actions`` and ``allowedDeviationXy`` in place of
``allowedDeviationXY`` (both vda-5050-lib 1.4.0's), ``actionName`` in place of ``actionType`` (the 2.0.0
instantActions schema file). Each is named so that the sender learns what to fix.

:func:`encode` writes an outgoing message (:mod:`fleetsim.vda5050.state_model`) for one version: camelCase
keys, the header's ``version``, optional fields left out when ``None``, 2.1's additions left out of 2.0.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import fields, is_dataclass
from enum import Enum
from typing import Any

from fleetsim.errors import FleetsimError
from fleetsim.vda5050.model import (
    VERSIONS,
    Action,
    ActionParameter,
    BlockingType,
    Edge,
    ErrorLevel,
    ErrorReference,
    Header,
    InstantActions,
    Node,
    NodePosition,
    Order,
    VdaError,
)
from fleetsim.vda5050.state_model import SINCE_2_1, Connection, ConnectionState, Factsheet, State, Visualization

__all__ = [
    "KEY_REFERENCE",
    "TOPICS",
    "MessageInvalid",
    "decode_connection",
    "decode_instant_actions",
    "decode_order",
    "encode",
    "to_document",
    "topic",
]

# The referenceKey under which a validationError names the offending JSON key path (``nodes[2].sequenceId``).
KEY_REFERENCE = "key"
TOPICS = frozenset({"order", "instantActions", "state", "visualization", "connection", "factsheet"})
_PI = 3.14159265359  # the bound the text's tables give for angles
_TIMESTAMP = re.compile(r"\d{4}-\d\d-\d\d[Tt ]\d\d:\d\d:\d\d(\.\d+)?([Zz]|[+-]\d\d:\d\d)")
_KINDS = {
    "string": (str,),
    "integer": (int,),
    "number": (int, float),
    "boolean": (bool,),
    "array": (list,),
    "object": (dict,),
}


class MessageInvalid(FleetsimError, ValueError):
    """An incoming message fleetsim cannot accept; ``errors`` are its ``validationError``\\ s, all of them."""

    def __init__(self, topic: str, errors: Sequence[VdaError]) -> None:
        self.topic = topic
        self.errors = tuple(errors)
        listing = "; ".join(error.error_description for error in self.errors)
        count = f"{len(self.errors)} problem" + ("s" if len(self.errors) != 1 else "")
        super().__init__(f"invalid {topic} message ({count}): {listing}")


def _version(version: str) -> str:
    if version not in VERSIONS:
        msg = f"version={version!r} must be one of {sorted(VERSIONS)}"
        raise ValueError(msg)
    return version


def _json_type(value: Any) -> str:
    names = {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "an array"}
    return "null" if value is None else names.get(type(value), "an object")


class _Reader:
    """Reads one message, collecting every problem with its key path and the ids it concerns."""

    def __init__(self, version: str) -> None:
        self.version = version
        self.problems: list[tuple[str, str, tuple[ErrorReference, ...]]] = []
        self.references: list[ErrorReference] = []
        self.context: list[ErrorReference] = []

    def problem(self, path: str, text: str) -> None:
        self.problems.append((path, text, tuple(self.context)))

    @contextmanager
    def about(self, key: str, value: Any) -> Iterator[None]:
        """Problems found inside refer to ``key`` (``nodeId``, ``actionId``...) when its value is known."""
        known = isinstance(value, str)
        if known:
            self.context.append(ErrorReference(key, value))
        try:
            yield
        finally:
            if known:
                self.context.pop()

    def get(
        self,
        obj: Mapping[str, Any],
        key: str,
        path: str,
        kind: str,
        required: bool = True,
        low: float | None = None,
        high: float | None = None,
        words: Sequence[str] = (),
    ) -> Any:
        """``obj[key]`` when it is of ``kind`` (within ``low``..``high``, one of ``words``), else None."""
        where = f"{path}.{key}" if path else key
        if key not in obj:
            if required:
                self.problem(where, "required key is missing")
            return None
        value = obj[key]
        if kind == "integer" and isinstance(value, float) and value.is_integer():
            value = int(value)  # JSON does not tell 3 from 3.0; the schemas accept both
        if (isinstance(value, bool) and kind != "boolean") or not isinstance(value, _KINDS[kind]):
            self.problem(
                where, f"expected {'an' if kind[0] in 'aeiou' else 'a'} {kind}, got {value!r} ({_json_type(value)})"
            )
            return None
        if isinstance(value, float) and not math.isfinite(value):
            self.problem(where, f"expected a finite number, got {value!r}")
            return None
        if isinstance(value, (int, float)) and (
            (low is not None and value < low) or (high is not None and value > high)
        ):
            bounds = (
                f"at least {low}" if high is None else f"in {low}..{high}" if low is not None else f"at most {high}"
            )
            self.problem(where, f"{value!r} must be {bounds}")
            return None
        if words and value not in words:
            self.problem(where, f"{value!r} is not one of {', '.join(words)}")
            return None
        return value

    def items(
        self, obj: Mapping[str, Any], key: str, path: str, required: bool = True
    ) -> Iterator[tuple[str, dict[str, Any]]]:
        """The objects of the array ``obj[key]`` with their paths; items that are not objects are problems."""
        array = self.get(obj, key, path, "array", required)
        for index, item in enumerate(array or ()):
            where = f"{path}.{key}[{index}]" if path else f"{key}[{index}]"
            if isinstance(item, dict):
                yield where, item
            else:
                self.problem(where, f"expected an object, got {item!r} ({_json_type(item)})")

    def errors(self) -> tuple[VdaError, ...]:
        return tuple(
            VdaError(
                error_type="validationError",
                error_description=f"{path}: {text}" if path else text,
                error_level=ErrorLevel.WARNING,
                error_references=(
                    *self.references,
                    *context,
                    *((ErrorReference(KEY_REFERENCE, path),) if path else ()),
                ),
            )
            for path, text, context in self.problems
        )


def _load(payload: bytes, version: str) -> tuple[_Reader, dict[str, Any] | None]:
    """The payload's top-level object, or None with the reason recorded."""
    reader = _Reader(_version(version))
    if not isinstance(payload, (bytes, bytearray)):
        msg = f"payload={payload!r:.80} must be bytes (an MQTT message's payload)"
        raise TypeError(msg)
    payload = bytes(payload)
    try:
        text = payload.decode("utf-8")
    except UnicodeDecodeError as error:
        reader.problem("", f"payload is not UTF-8: byte {error.start} ({payload[error.start : error.start + 1]!r})")
        return reader, None
    try:
        document = json.loads(text, parse_constant=float)  # NaN and Infinity parse, then fail the number check
    except json.JSONDecodeError as error:
        offset = len(text[: error.pos].encode("utf-8"))
        reader.problem(
            "", f"payload is not JSON: {error.msg} at byte {offset} (line {error.lineno}, column {error.colno})"
        )
        return reader, None
    if not isinstance(document, dict):
        reader.problem("", f"payload must be a JSON object, got {_json_type(document)}")
        return reader, None
    return reader, document


def _header(reader: _Reader, document: Mapping[str, Any]) -> Header:
    header_id = reader.get(document, "headerId", "", "integer")
    if header_id is not None:
        reader.references.append(ErrorReference("headerId", str(header_id)))
    timestamp = reader.get(document, "timestamp", "", "string")
    if timestamp is not None and not _TIMESTAMP.fullmatch(timestamp):
        reader.problem("timestamp", f"{timestamp!r} is not an ISO 8601 date-time (YYYY-MM-DDTHH:mm:ss.ffZ)")
    version = reader.get(document, "version", "", "string")
    if version is not None and not re.fullmatch(r"2\.\d+\.\d+", version):
        reader.problem("version", f"{version!r} is not a VDA 5050 2.x version ([Major].[Minor].[Patch])")
    manufacturer = reader.get(document, "manufacturer", "", "string")
    serial_number = reader.get(document, "serialNumber", "", "string")
    return Header(header_id, timestamp, version, manufacturer, serial_number)


def _actions(reader: _Reader, obj: Mapping[str, Any], key: str, path: str) -> tuple[Action, ...]:
    actions = []
    value_kinds = (list, bool, int, float, str, dict) if reader.version == "2.1" else (list, bool, int, float, str)
    for where, item in reader.items(obj, key, path):
        action_id = reader.get(item, "actionId", where, "string")
        with reader.about("actionId", action_id):
            if "actionName" in item:
                reader.problem(f"{where}.actionName", "not a VDA 5050 2.x key; an action's type is 'actionType'")
            action_type = reader.get(item, "actionType", where, "string")
            blocking = reader.get(item, "blockingType", where, "string", words=[b.value for b in BlockingType])
            description = reader.get(item, "actionDescription", where, "string", required=False)
            parameters = []
            for at, parameter in reader.items(item, "actionParameters", where, required=False):
                key_ = reader.get(parameter, "key", at, "string")
                if "value" not in parameter:
                    reader.problem(f"{at}.value", "required key is missing")
                elif not isinstance(parameter["value"], value_kinds):
                    reader.problem(f"{at}.value", f"{parameter['value']!r} is not a {reader.version} parameter value")
                else:
                    parameters.append(ActionParameter(key_, parameter["value"]))
            # An invalid blockingType is a problem already: the message is refused, and NONE fills an Action never used.
            actions.append(
                Action(
                    action_type,
                    action_id,
                    BlockingType(blocking) if blocking else BlockingType.NONE,
                    description,
                    tuple(parameters),
                )
            )
    return tuple(actions)


def _node_position(reader: _Reader, obj: Mapping[str, Any], path: str) -> NodePosition | None:
    position = reader.get(obj, "nodePosition", path, "object", required=False)
    if position is None:
        return None
    at = f"{path}.nodePosition"
    if "allowedDeviationXy" in position:
        reader.problem(f"{at}.allowedDeviationXy", "not a VDA 5050 2.x key; the text's key is 'allowedDeviationXY'")
    return NodePosition(
        x=reader.get(position, "x", at, "number"),
        y=reader.get(position, "y", at, "number"),
        map_id=reader.get(position, "mapId", at, "string"),
        theta=reader.get(position, "theta", at, "number", False, -_PI, _PI),
        allowed_deviation_xy=reader.get(position, "allowedDeviationXY", at, "number", False, 0.0),
        allowed_deviation_theta=reader.get(position, "allowedDeviationTheta", at, "number", False, -_PI, _PI),
        map_description=reader.get(position, "mapDescription", at, "string", False),
    )


def _trajectory(reader: _Reader, obj: Mapping[str, Any], path: str) -> dict[str, Any] | None:
    trajectory = reader.get(obj, "trajectory", path, "object", required=False)
    if trajectory is None:
        return None
    at = f"{path}.trajectory"
    reader.get(trajectory, "degree", at, "integer", low=1)
    for index, knot in enumerate(reader.get(trajectory, "knotVector", at, "array") or ()):
        if isinstance(knot, bool) or not isinstance(knot, (int, float)) or not 0.0 <= knot <= 1.0:
            reader.problem(f"{at}.knotVector[{index}]", f"expected a number in 0..1, got {knot!r}")
    for where, point in reader.items(trajectory, "controlPoints", at):
        reader.get(point, "x", where, "number")
        reader.get(point, "y", where, "number")
        reader.get(point, "weight", where, "number", False, 0.0)
    return dict(trajectory)


def _edge(reader: _Reader, item: Mapping[str, Any], at: str) -> Edge:
    get = reader.get
    edge = Edge(
        edge_id=get(item, "edgeId", at, "string"),
        sequence_id=get(item, "sequenceId", at, "integer", low=0),
        released=get(item, "released", at, "boolean"),
        start_node_id=get(item, "startNodeId", at, "string"),
        end_node_id=get(item, "endNodeId", at, "string"),
        actions=_actions(reader, item, "actions", at),
        max_speed=get(item, "maxSpeed", at, "number", False),
        orientation=get(item, "orientation", at, "number", False, -_PI, _PI),
        orientation_type=get(item, "orientationType", at, "string", False, words=("GLOBAL", "TANGENTIAL")),
        direction=get(item, "direction", at, "string", False),
        rotation_allowed=get(item, "rotationAllowed", at, "boolean", False),
        max_rotation_speed=get(item, "maxRotationSpeed", at, "number", False),
        length=get(item, "length", at, "number", False),
        trajectory=_trajectory(reader, item, at),
        edge_description=get(item, "edgeDescription", at, "string", False),
    )
    get(item, "maxHeight", at, "number", False)
    get(item, "minHeight", at, "number", False)
    corridor = get(item, "corridor", at, "object", False) if reader.version == "2.1" else None
    if corridor is not None:
        get(corridor, "leftWidth", f"{at}.corridor", "number", low=0.0)
        get(corridor, "rightWidth", f"{at}.corridor", "number", low=0.0)
        get(corridor, "corridorRefPoint", f"{at}.corridor", "string", False, words=("KINEMATICCENTER", "CONTOUR"))
    return edge


def decode_order(payload: bytes, version: str) -> Order:
    """The ``order`` in ``payload`` for a vehicle speaking ``version`` ("2.0" or "2.1"); raises
    :class:`MessageInvalid` with every problem. Any 2.x header ``version`` is accepted (a minor version only
    adds optional keys); the order's semantics, such as sequence ids alternating between nodes and edges,
    are the vehicle's to check: those are ``orderError``\\ s."""
    reader, document = _load(payload, version)
    if document is None:
        raise MessageInvalid("order", reader.errors())
    header = _header(reader, document)
    order_id = reader.get(document, "orderId", "", "string")
    if order_id is not None:
        reader.references.append(ErrorReference("orderId", order_id))
    order_update_id = reader.get(document, "orderUpdateId", "", "integer", low=0)
    zone_set_id = reader.get(document, "zoneSetId", "", "string", required=False)
    nodes = []
    for at, item in reader.items(document, "nodes", ""):
        node_id = reader.get(item, "nodeId", at, "string")
        with reader.about("nodeId", node_id):
            sequence_id = reader.get(item, "sequenceId", at, "integer", low=0)
            released = reader.get(item, "released", at, "boolean")
            actions = _actions(reader, item, "actions", at)
            position = _node_position(reader, item, at)
            description = reader.get(item, "nodeDescription", at, "string", False)
            nodes.append(Node(node_id, sequence_id, released, actions, position, description))
    edges = []
    for at, item in reader.items(document, "edges", ""):
        with reader.about("edgeId", item.get("edgeId")):
            edges.append(_edge(reader, item, at))
    if reader.problems:
        raise MessageInvalid("order", reader.errors())
    return Order(header, order_id, order_update_id, tuple(nodes), tuple(edges), zone_set_id)


def decode_instant_actions(payload: bytes, version: str) -> InstantActions:
    """The ``instantActions`` in ``payload`` for a vehicle speaking ``version``; raises :class:`MessageInvalid`."""
    reader, document = _load(payload, version)
    if document is None:
        raise MessageInvalid("instantActions", reader.errors())
    header = _header(reader, document)
    if "instantActions" in document:
        reader.problem("instantActions", "expected key 'actions' (VDA 5050 2.x); 'instantActions' is not a 2.x key")
    actions = (
        _actions(reader, document, "actions", "") if "actions" in document or "instantActions" not in document else ()
    )
    if reader.problems:
        raise MessageInvalid("instantActions", reader.errors())
    return InstantActions(header, actions)


def decode_connection(payload: bytes, version: str) -> Connection:
    """A ``connection`` message in ``payload`` (a master control tells its own on fleetsim's
    ``master/connection`` topic); raises :class:`MessageInvalid` with every problem."""
    reader, document = _load(payload, version)
    if document is None:
        raise MessageInvalid("connection", reader.errors())
    header = _header(reader, document)
    words = [state.value for state in ConnectionState]
    connection_state = reader.get(document, "connectionState", "", "string", words=words)
    if reader.problems:
        raise MessageInvalid("connection", reader.errors())
    return Connection(
        header.header_id, header.timestamp, header.manufacturer, header.serial_number, ConnectionState(connection_state)
    )


# Enumerated words the outgoing models hold as plain strings, by class and field.
_WORDS = {
    ("TypeSpecification", "agv_kinematic"): {"DIFF", "OMNI", "THREEWHEEL"},
    ("TypeSpecification", "agv_class"): {"FORKLIFT", "CONVEYOR", "TUGGER", "CARRIER"},
    ("TypeSpecification", "localization_types"): {"NATURAL", "REFLECTOR", "RFID", "DMC", "SPOT", "GRID"},
    ("TypeSpecification", "navigation_types"): {"PHYSICAL_LINE_GUIDED", "VIRTUAL_LINE_GUIDED", "AUTONOMOUS"},
    ("OptionalParameter", "support"): {"SUPPORTED", "REQUIRED"},
    ("AgvActionParameter", "value_data_type"): {"BOOL", "NUMBER", "INTEGER", "FLOAT", "STRING", "OBJECT", "ARRAY"},
    ("AgvAction", "action_scopes"): {"INSTANT", "NODE", "EDGE"},
    ("AgvAction", "blocking_types"): {b.value for b in BlockingType},
}


# Wire keys that are not the camelCase of the field's name.
_KEYS = {("NodePosition", "allowed_deviation_xy"): "allowedDeviationXY"}


def _camel(name: str) -> str:
    head, *rest = name.split("_")
    return head + "".join(part[:1].upper() + part[1:] for part in rest)


# Numbers the text's tables type as integers although a float would be a natural reading (2.0's schema insists).
_INTEGERS = frozenset({("BatteryState", "battery_health")})
# Bounds the text sets on outgoing numbers, by class and field.
_RANGES: dict[tuple[str, str], tuple[float | None, float | None]] = {
    ("AgvPosition", "localization_score"): (0.0, 1.0),
    ("BatteryState", "battery_health"): (0.0, 100.0),
    ("BatteryState", "reach"): (0.0, None),
    ("Load", "weight"): (0.0, None),
}


def _check(name: str, field_name: str, value: Any, where: str) -> None:
    """The text's constraints on one field of an outgoing model: enumerated words, bounds, timestamps."""
    words = _WORDS.get((name, field_name))
    for word in value if isinstance(value, tuple) else (value,):
        if words is not None and word not in words:
            msg = f"{where}={word!r} must be one of {sorted(words)}"
            raise ValueError(msg)
    if (name, field_name) in _INTEGERS and (isinstance(value, bool) or not isinstance(value, int)):
        msg = f"{where}={value!r} must be an integer"
        raise ValueError(msg)
    low, high = _RANGES.get((name, field_name), (None, None))
    if (low is not None and value < low) or (high is not None and value > high):
        msg = f"{where}={value!r} must be in {low}..{'' if high is None else high}"
        raise ValueError(msg)
    if field_name == "timestamp" and not _TIMESTAMP.fullmatch(value):
        msg = f"{where}={value!r} must be an ISO 8601 date-time such as '2026-12-03T13:00:00.25Z'"
        raise ValueError(msg)


def _wire(value: Any, version: str, where: str) -> Any:
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            msg = f"{where}={value!r} must be a finite number"
            raise ValueError(msg)
        return value
    if isinstance(value, (tuple, list)):
        return [_wire(item, version, f"{where}[{index}]") for index, item in enumerate(value)]
    if isinstance(value, Mapping):
        return {str(key): _wire(item, version, f"{where}.{key}") for key, item in value.items()}
    if is_dataclass(value) and not isinstance(value, type):
        name = type(value).__name__
        document: dict[str, Any] = {}
        for item in fields(value):
            content = getattr(value, item.name)
            if content is None or (version == "2.0" and (name, item.name) in SINCE_2_1):
                continue
            key = _KEYS.get((name, item.name)) or _camel(item.name)
            _check(name, item.name, content, f"{where}.{key}")
            document[key] = _wire(content, version, f"{where}.{key}")
            if key == "timestamp" and where.count(".") == 0:
                document["version"] = VERSIONS[version]  # the header's order: headerId, timestamp, version, ...
        return document
    msg = f"{where}={value!r} cannot be written to JSON"
    raise TypeError(msg)


def to_document(message: State | Connection | Visualization | Factsheet, version: str) -> dict[str, Any]:
    """The JSON object of an outgoing ``message`` for ``version`` ("2.0" or "2.1")."""
    if not isinstance(message, (State, Connection, Visualization, Factsheet)):
        msg = f"message={message!r} must be a State, Connection, Visualization or Factsheet"
        raise TypeError(msg)
    return _wire(message, _version(version), _camel(type(message).__name__.lower()))  # type: ignore[no-any-return]


def encode(message: State | Connection | Visualization | Factsheet, version: str) -> bytes:
    """``message`` as its topic's payload: compact JSON in UTF-8."""
    document = to_document(message, version)
    return json.dumps(document, separators=(",", ":"), ensure_ascii=False, allow_nan=False).encode("utf-8")


def topic(interface_name: str, version: str, manufacturer: str, serial_number: str, name: str) -> str:
    """The MQTT topic ``interfaceName/majorVersion/manufacturer/serialNumber/topic`` (majorVersion ``v2``)."""
    _version(version)
    if name not in TOPICS:
        msg = f"name={name!r} must be one of {sorted(TOPICS)}"
        raise ValueError(msg)
    for label, level in (
        ("interface_name", interface_name),
        ("manufacturer", manufacturer),
        ("serial_number", serial_number),
    ):
        if not level or any(character in level for character in "/+#"):
            msg = f"{label}={level!r} must be a non-empty topic level without '/', '+' or '#'"
            raise ValueError(msg)
    return f"{interface_name}/v2/{manufacturer}/{serial_number}/{name}"
