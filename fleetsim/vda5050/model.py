"""fleetsim's own models of the VDA 5050 messages a vehicle receives (``order``, ``instantActions``) and of
the errors it reports, written from the specification (VDA 5050 2.0 and 2.1, sections 6.6-6.10).

Field names follow Python (``node_id`` for ``nodeId``); :mod:`fleetsim.vda5050.messages` reads them from and
writes them to the wire. Everything here is immutable plain data.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any

__all__ = [
    "VERSIONS",
    "Action",
    "ActionParameter",
    "BlockingType",
    "Edge",
    "ErrorLevel",
    "ErrorReference",
    "Header",
    "InstantActions",
    "Node",
    "NodePosition",
    "Order",
    "VdaError",
]

# The protocol versions fleetsim's vehicles speak (the ``version`` of every header they send) by the
# setting's name; the topic's ``majorVersion`` is ``v2`` for both.
VERSIONS = {"2.0": "2.0.0", "2.1": "2.1.0"}


class BlockingType(str, Enum):
    """How an action blocks driving and other actions (6.6.3)."""

    NONE = "NONE"
    SOFT = "SOFT"
    HARD = "HARD"


class ErrorLevel(str, Enum):
    """WARNING: the vehicle can go on; FATAL: it cannot without help (6.10.6)."""

    WARNING = "WARNING"
    FATAL = "FATAL"


@dataclass(frozen=True, slots=True)
class Header:
    """The header every message carries (6.5)."""

    header_id: int
    timestamp: str
    version: str
    manufacturer: str
    serial_number: str


@dataclass(frozen=True, slots=True)
class ActionParameter:
    key: str
    value: Any


@dataclass(frozen=True, slots=True)
class Action:
    """An action on a node, an edge or in ``instantActions`` (6.6.3)."""

    action_type: str
    action_id: str
    blocking_type: BlockingType
    action_description: str | None = None
    action_parameters: tuple[ActionParameter, ...] = ()

    def parameter(self, key: str) -> Any:
        """The value of the parameter ``key`` (None when it is not given)."""
        return next((p.value for p in self.action_parameters if p.key == key), None)


@dataclass(frozen=True, slots=True)
class NodePosition:
    """Where a node is, in the map's frame (6.6.2)."""

    x: float
    y: float
    map_id: str
    theta: float | None = None
    allowed_deviation_xy: float | None = None
    allowed_deviation_theta: float | None = None
    map_description: str | None = None


@dataclass(frozen=True, slots=True)
class Node:
    """A node of an order: released (base) or not (horizon)."""

    node_id: str
    sequence_id: int
    released: bool
    actions: tuple[Action, ...] = ()
    node_position: NodePosition | None = None
    node_description: str | None = None


@dataclass(frozen=True, slots=True)
class Edge:
    """An edge of an order, from ``start_node_id`` to ``end_node_id`` (6.6.4). ``orientation`` with
    ``orientation_type`` TANGENTIAL (the default) is the vehicle's heading relative to the edge's tangent:
    about pi means it drives the edge backwards (reversing)."""

    edge_id: str
    sequence_id: int
    released: bool
    start_node_id: str
    end_node_id: str
    actions: tuple[Action, ...] = ()
    max_speed: float | None = None
    orientation: float | None = None
    orientation_type: str | None = None
    direction: str | None = None
    rotation_allowed: bool | None = None
    max_rotation_speed: float | None = None
    length: float | None = None
    trajectory: dict[str, Any] | None = None
    edge_description: str | None = None


@dataclass(frozen=True, slots=True)
class Order:
    """An ``order`` message: nodes and edges alternate by sequence id, node first and last (6.6)."""

    header: Header
    order_id: str
    order_update_id: int
    nodes: tuple[Node, ...]
    edges: tuple[Edge, ...]
    zone_set_id: str | None = None

    @property
    def base(self) -> tuple[tuple[Node, ...], tuple[Edge, ...]]:
        """The released nodes and edges."""
        return tuple(n for n in self.nodes if n.released), tuple(e for e in self.edges if e.released)


@dataclass(frozen=True, slots=True)
class InstantActions:
    """An ``instantActions`` message (6.7)."""

    header: Header
    actions: tuple[Action, ...]


@dataclass(frozen=True, slots=True)
class ErrorReference:
    """What an error refers to: ``headerId``, ``orderId``, ``nodeId``, ``edgeId``, ``actionId``, a key, ..."""

    reference_key: str
    reference_value: str


@dataclass(frozen=True, slots=True)
class VdaError:
    """An entry of the state's ``errors`` (6.10.6); ``error_type`` is the standard's name where it has one
    (``validationError``, ``orderError``, ``orderUpdateError``, ``noRouteError``, ...)."""

    error_type: str
    error_description: str
    error_level: ErrorLevel = ErrorLevel.WARNING
    error_references: tuple[ErrorReference, ...] = field(default=())
    error_hint: str | None = None  # 2.1 only; left out of a 2.0 state
