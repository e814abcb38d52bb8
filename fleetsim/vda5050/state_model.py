"""fleetsim's models of the VDA 5050 messages a vehicle sends: ``state`` (6.10), ``connection`` (6.14),
``visualization`` (6.11) and ``factsheet`` (6.15), written from the specification's text (2.0 and 2.1).

Field names follow Python (``node_states`` for ``nodeStates``); :func:`fleetsim.vda5050.messages.encode`
writes them to the wire in camelCase for one protocol version, filling in the header's ``version``.
A field that is ``None`` is optional and left out; a tuple that defaults to ``()`` is a required array,
written even when empty. Fields the text adds in 2.1 (named in ``SINCE_2_1``) are left out of 2.0 messages.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

from fleetsim.vda5050.model import NodePosition, VdaError

__all__ = [
    "SINCE_2_1",
    "ActionState",
    "ActionStatus",
    "AgvAction",
    "AgvActionParameter",
    "AgvGeometry",
    "AgvPosition",
    "BatteryState",
    "BoundingBoxReference",
    "Connection",
    "ConnectionState",
    "EStop",
    "EdgeState",
    "Envelope2d",
    "Factsheet",
    "InfoLevel",
    "InfoReference",
    "Information",
    "Load",
    "LoadDimensions",
    "LoadSpecification",
    "MapState",
    "MapStatus",
    "NodeState",
    "OperatingMode",
    "OptionalParameter",
    "PhysicalParameters",
    "PolygonPoint",
    "ProtocolFeatures",
    "ProtocolLimits",
    "SafetyState",
    "State",
    "Timing",
    "TypeSpecification",
    "VehicleConfig",
    "Velocity",
    "VersionInfo",
    "Visualization",
]


class ActionStatus(str, Enum):
    """Where an action is in its life (6.10.5); PAUSED is in the text of 2.0 and 2.1 alike."""

    WAITING = "WAITING"
    INITIALIZING = "INITIALIZING"
    RUNNING = "RUNNING"
    PAUSED = "PAUSED"
    FINISHED = "FINISHED"
    FAILED = "FAILED"


class OperatingMode(str, Enum):
    AUTOMATIC = "AUTOMATIC"
    SEMIAUTOMATIC = "SEMIAUTOMATIC"
    MANUAL = "MANUAL"
    SERVICE = "SERVICE"
    TEACHIN = "TEACHIN"


class EStop(str, Enum):
    """The acknowledge type of an active emergency stop; NONE when none is active."""

    AUTOACK = "AUTOACK"
    MANUAL = "MANUAL"
    REMOTE = "REMOTE"
    NONE = "NONE"


class InfoLevel(str, Enum):
    INFO = "INFO"
    DEBUG = "DEBUG"


class MapStatus(str, Enum):
    ENABLED = "ENABLED"
    DISABLED = "DISABLED"


class ConnectionState(str, Enum):
    """ONLINE and OFFLINE the vehicle publishes itself; CONNECTIONBROKEN is its MQTT last will."""

    ONLINE = "ONLINE"
    OFFLINE = "OFFLINE"
    CONNECTIONBROKEN = "CONNECTIONBROKEN"


@dataclass(frozen=True, slots=True)
class NodeState:
    node_id: str
    sequence_id: int
    released: bool
    node_description: str | None = None
    node_position: NodePosition | None = None


@dataclass(frozen=True, slots=True)
class EdgeState:
    edge_id: str
    sequence_id: int
    released: bool
    edge_description: str | None = None
    trajectory: Mapping[str, Any] | None = None


@dataclass(frozen=True, slots=True)
class AgvPosition:
    x: float
    y: float
    theta: float
    map_id: str
    position_initialized: bool
    map_description: str | None = None
    localization_score: float | None = None
    deviation_range: float | None = None


@dataclass(frozen=True, slots=True)
class Velocity:
    """In the vehicle's frame: ``vx`` along its nose, ``omega`` about its vertical axis."""

    vx: float | None = None
    vy: float | None = None
    omega: float | None = None


@dataclass(frozen=True, slots=True)
class BoundingBoxReference:
    x: float
    y: float
    z: float
    theta: float | None = None


@dataclass(frozen=True, slots=True)
class LoadDimensions:
    length: float
    width: float
    height: float | None = None


@dataclass(frozen=True, slots=True)
class Load:
    load_id: str | None = None
    load_type: str | None = None
    load_position: str | None = None
    bounding_box_reference: BoundingBoxReference | None = None
    load_dimensions: LoadDimensions | None = None
    weight: float | None = None


@dataclass(frozen=True, slots=True)
class ActionState:
    action_id: str
    action_status: ActionStatus
    action_type: str | None = None
    action_description: str | None = None
    result_description: str | None = None


@dataclass(frozen=True, slots=True)
class BatteryState:
    battery_charge: float
    charging: bool
    battery_voltage: float | None = None
    battery_health: int | None = None  # percent; an int8 in the text's table
    reach: float | None = None


@dataclass(frozen=True, slots=True)
class InfoReference:
    reference_key: str
    reference_value: str


@dataclass(frozen=True, slots=True)
class Information:
    info_type: str
    info_level: InfoLevel
    info_description: str | None = None
    info_references: tuple[InfoReference, ...] | None = None


@dataclass(frozen=True, slots=True)
class SafetyState:
    e_stop: EStop
    field_violation: bool


@dataclass(frozen=True, slots=True)
class MapState:
    """A map stored on the vehicle (2.1's ``maps``)."""

    map_id: str
    map_version: str
    map_status: MapStatus
    map_description: str | None = None


@dataclass(frozen=True, slots=True)
class State:
    """The ``state`` message. ``order_id`` is ``""`` and ``last_node_id`` ``""`` before the first order."""

    header_id: int
    timestamp: str
    manufacturer: str
    serial_number: str
    order_id: str
    order_update_id: int
    last_node_id: str
    last_node_sequence_id: int
    driving: bool
    operating_mode: OperatingMode
    battery_state: BatteryState
    safety_state: SafetyState
    node_states: tuple[NodeState, ...] = ()
    edge_states: tuple[EdgeState, ...] = ()
    action_states: tuple[ActionState, ...] = ()
    errors: tuple[VdaError, ...] = ()
    information: tuple[Information, ...] = ()
    maps: tuple[MapState, ...] = ()
    zone_set_id: str | None = None
    paused: bool | None = None
    new_base_request: bool | None = None
    distance_since_last_node: float | None = None
    agv_position: AgvPosition | None = None
    velocity: Velocity | None = None
    loads: tuple[Load, ...] | None = None  # None: the vehicle cannot tell its loads (left out)


@dataclass(frozen=True, slots=True)
class Connection:
    header_id: int
    timestamp: str
    manufacturer: str
    serial_number: str
    connection_state: ConnectionState


@dataclass(frozen=True, slots=True)
class Visualization:
    header_id: int
    timestamp: str
    manufacturer: str
    serial_number: str
    agv_position: AgvPosition | None = None
    velocity: Velocity | None = None


@dataclass(frozen=True, slots=True)
class TypeSpecification:
    series_name: str
    agv_kinematic: str  # DIFF, OMNI, THREEWHEEL
    agv_class: str  # FORKLIFT, CONVEYOR, TUGGER, CARRIER
    max_load_mass: float
    localization_types: tuple[str, ...]  # NATURAL, REFLECTOR, RFID, DMC, SPOT, GRID
    navigation_types: tuple[str, ...]  # PHYSICAL_LINE_GUIDED, VIRTUAL_LINE_GUIDED, AUTONOMOUS
    series_description: str | None = None


@dataclass(frozen=True, slots=True)
class PhysicalParameters:
    speed_min: float
    speed_max: float
    acceleration_max: float
    deceleration_max: float
    height_max: float
    width: float
    length: float
    height_min: float | None = None


@dataclass(frozen=True, slots=True)
class Timing:
    min_order_interval: float
    min_state_interval: float
    default_state_interval: float | None = None
    visualization_interval: float | None = None


@dataclass(frozen=True, slots=True)
class ProtocolLimits:
    """``max_string_lens`` and ``max_array_lens`` map the text's keys (``idLen``, ``order.nodes``...) to
    limits; an empty mapping says there is no explicit limit."""

    timing: Timing
    max_string_lens: Mapping[str, int | bool] = field(default_factory=dict)
    max_array_lens: Mapping[str, int] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class OptionalParameter:
    parameter: str  # e.g. "order.nodes.nodePosition.allowedDeviationTheta"
    support: str  # SUPPORTED or REQUIRED
    description: str | None = None


@dataclass(frozen=True, slots=True)
class AgvActionParameter:
    key: str
    value_data_type: str  # BOOL, NUMBER, INTEGER, FLOAT, STRING, OBJECT, ARRAY
    description: str | None = None
    is_optional: bool | None = None


@dataclass(frozen=True, slots=True)
class AgvAction:
    action_type: str
    action_scopes: tuple[str, ...]  # INSTANT, NODE, EDGE
    action_description: str | None = None
    action_parameters: tuple[AgvActionParameter, ...] | None = None
    result_description: str | None = None
    blocking_types: tuple[str, ...] | None = None  # 2.1 only


@dataclass(frozen=True, slots=True)
class ProtocolFeatures:
    optional_parameters: tuple[OptionalParameter, ...] = ()
    agv_actions: tuple[AgvAction, ...] = ()


@dataclass(frozen=True, slots=True)
class PolygonPoint:
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class Envelope2d:
    """The vehicle's outline seen from above, in its own frame (``set`` names the outline)."""

    set: str
    polygon_points: tuple[PolygonPoint, ...]
    description: str | None = None


@dataclass(frozen=True, slots=True)
class AgvGeometry:
    envelopes2d: tuple[Envelope2d, ...] | None = None


@dataclass(frozen=True, slots=True)
class LoadSpecification:
    load_positions: tuple[str, ...] | None = None


@dataclass(frozen=True, slots=True)
class VersionInfo:
    key: str
    value: str


@dataclass(frozen=True, slots=True)
class VehicleConfig:
    """2.1 only: the vehicle's software and hardware versions."""

    versions: tuple[VersionInfo, ...] | None = None


@dataclass(frozen=True, slots=True)
class Factsheet:
    header_id: int
    timestamp: str
    manufacturer: str
    serial_number: str
    type_specification: TypeSpecification
    physical_parameters: PhysicalParameters
    protocol_limits: ProtocolLimits
    protocol_features: ProtocolFeatures
    agv_geometry: AgvGeometry = AgvGeometry()
    load_specification: LoadSpecification = LoadSpecification()
    vehicle_config: VehicleConfig | None = None  # 2.1 only


# The fields the text adds in 2.1, by class and field name: left out of a 2.0 message.
SINCE_2_1 = frozenset(
    {
        ("State", "maps"),
        ("VdaError", "error_hint"),
        ("AgvAction", "blocking_types"),
        ("Factsheet", "vehicle_config"),
    }
)
