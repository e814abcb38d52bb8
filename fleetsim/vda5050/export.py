"""A recorded run's accepted plans as the VDA 5050 orders that would drive real vehicles along them.

Export is the inverse of :mod:`fleetsim.vda5050.orders`: each order written here, read back by
:func:`~fleetsim.vda5050.orders.read_order` and joined by :func:`~fleetsim.vda5050.orders.join_order`,
gives back the plan fleetsim accepted (its segments, traverses, progress and fixed flags; goal markers
are fleetsim's own and travel only as a ``nodeDescription``). So a plan tested in CI can be replayed on a
vendor's simulator or on a vehicle.

Per vehicle, from the trace (SPEC §10) replayed against its scenario:

- The **first** plan it is given is a new order, ``orderId`` ``<scenario>-v<vehicle>-1`` with
  ``orderUpdateId`` 0. Its node 0 is the entry node of the plan's first leg, the leg the vehicle is on
  (its last node, also when it has begun driving its start leg before its first plan); then, per leg,
  the edge that drives it and the node it ends at. Base (``released``) = fixed.
- Every **later** plan keeps the fixed legs the vehicle had (the checks insist), so it is an order update:
  the same ``orderId``, ``orderUpdateId`` + 1, starting at the stitching node (the last released node so
  far, with its ``sequenceId``) and carrying only the legs after the fixed ones. The old horizon is gone.
- Sequence ids count from the order's start: node k is 2k, edge k is 2k + 1; an update goes on from its
  stitching node.
- Edges: the map's edge ids (:mod:`fleetsim.vda5050.places`: LIF edge ids on a LIF site, ``e7`` on a Tiled
  map), ``orientationType`` TANGENTIAL with ``orientation`` 0 for nose first and pi for backing.
- Nodes: the place's position in ``mapId`` (the scenario's name unless given), ``theta`` the heading the
  vehicle arrives with (at node 0: the heading it leaves with), within :data:`ALLOWED_DEVIATION_XY`
  metres and :data:`ALLOWED_DEVIATION_THETA` radians: fleetsim's vehicles stay on their segments, so a
  real one may stray only a little.
- Header: ``headerId`` counts the vehicle's order topic from 0; ``timestamp`` is :data:`EPOCH` plus the
  simulated time at the start of the step that accepted the plan (planning happens before motion), so the
  same run exports the same bytes; ``version`` per the protocol version asked for.

Nothing else goes into an order: no actions (fleetsim's tasks are places to reach, not actions) and no
trajectories (the vehicle drives its own path between the nodes).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from typing import Any

from fleetsim.enums import Progress, Traverse
from fleetsim.errors import FleetsimError
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.snapshot import initial_plan
from fleetsim.recording.replay import replay
from fleetsim.scenario import Scenario
from fleetsim.vda5050.messages import topic
from fleetsim.vda5050.model import VERSIONS, Edge, Header, Node, NodePosition, Order
from fleetsim.vda5050.places import SiteGraph, site_graph

__all__ = [
    "ALLOWED_DEVIATION_THETA",
    "ALLOWED_DEVIATION_XY",
    "EPOCH",
    "ExportError",
    "ExportedOrder",
    "export_orders",
    "order_document",
    "order_line",
]

EPOCH = datetime(2000, 1, 1, tzinfo=timezone.utc)  # simulated time 0 in the exported timestamps
ALLOWED_DEVIATION_XY = 0.1  # metres a vehicle may be off a node's position and still be on it
ALLOWED_DEVIATION_THETA = 0.1  # radians (about 6 degrees) it may be off the node's theta
_TRAVERSE = {"f": Traverse.FORWARD, "b": Traverse.BACKWARD}
_PROGRESS = {"f": Progress.FORWARD, "r": Progress.REVERSE}


class ExportError(FleetsimError, ValueError):
    """A trace whose plans no VDA 5050 order can express: a plan that drops the vehicle's fixed legs, or a
    leg driven against a site's one-way edge."""


@dataclass(frozen=True, slots=True)
class ExportedOrder:
    """One order (or order update) and what it stands for: the plan accepted at ``step`` (``at`` seconds
    of simulated time), which the order turns the vehicle's plan ``before`` into."""

    vehicle_id: int
    step: int
    at: float
    order: Order
    plan: FleetPlan
    before: FleetPlan


def export_orders(
    scenario: Scenario,
    lines: Sequence[str],
    *,
    version: str = "2.0",
    manufacturer: str = "fleetsim",
    map_id: str | None = None,
) -> list[ExportedOrder]:
    """The orders of the run of ``scenario`` whose trace is ``lines`` (header first), in time order
    (by step, then vehicle id). ``version``: "2.0" or "2.1"; the serial number is the vehicle's id."""
    if version not in VERSIONS:
        msg = f"version={version!r} must be one of {sorted(VERSIONS)}"
        raise ValueError(msg)
    graph = site_graph(scenario.layout, map_id=map_id or scenario.name)
    step_us = _time_step_us(lines[0] if lines else "")
    writers = {
        v.id: _Writer(scenario, graph, v.id, Header(0, "", VERSIONS[version], manufacturer, str(v.id)))
        for v in scenario.vehicles
    }
    plans: Mapping[int, FleetPlan] = {v.id: initial_plan(v) for v in scenario.vehicles}
    exported: list[ExportedOrder] = []
    for line, frame in zip(lines[1:], replay(scenario, lines), strict=True):  # replay judges the lines
        step, _vehicles, accepted, _events = json.loads(line)
        at_us = step * step_us
        for record in accepted:
            plan = _plan(record)
            before = plans[plan.vehicle_id]
            order = writers[plan.vehicle_id].order(plan, before, step, _timestamp(at_us))
            exported.append(ExportedOrder(plan.vehicle_id, step, at_us / 1e6, order, plan, before))
        plans = frame.plans
    return exported


def order_document(order: Order) -> dict[str, Any]:
    """The ``order`` message's JSON object, keys as the text names them (camelCase, the header first)."""
    header = order.header
    return {
        "headerId": header.header_id,
        "timestamp": header.timestamp,
        "version": header.version,
        "manufacturer": header.manufacturer,
        "serialNumber": header.serial_number,
        "orderId": order.order_id,
        "orderUpdateId": order.order_update_id,
        "nodes": [_node_document(node) for node in order.nodes],
        "edges": [_edge_document(edge) for edge in order.edges],
    }


def order_line(exported: ExportedOrder, *, interface_name: str = "uagv") -> str:
    """One line of a ``<serialNumber>.orders.jsonl`` file: ``{"topic": ..., "at": seconds, "message": {...}}``,
    compact JSON: publish ``message`` on ``topic`` ``at`` seconds after the replay starts."""
    header = exported.order.header
    name = next(n for n, full in VERSIONS.items() if full == header.version)
    where = topic(interface_name, name, header.manufacturer, header.serial_number, "order")
    document = {"topic": where, "at": exported.at, "message": order_document(exported.order)}
    return json.dumps(document, separators=(",", ":"), ensure_ascii=False, allow_nan=False)


class _Writer:
    """One vehicle's order topic: its current order, the next header id, the stitching node's sequence id."""

    def __init__(self, scenario: Scenario, graph: SiteGraph, vehicle_id: int, header: Header) -> None:
        self.scenario = scenario
        self.graph = graph
        self.vehicle_id = vehicle_id
        self.header = header
        self.order_id = ""
        self.update_id = -1
        self.header_id = 0
        self.stitch_sequence = 0  # the last released node's sequenceId

    def order(self, plan: FleetPlan, before: FleetPlan, step: int, timestamp: str) -> Order:
        if not self.order_id:  # a new order, from the vehicle's last node: the entry of the leg it is on
            legs = plan.legs
            start, start_sequence = self._node(plan.legs[0], entry=True), 0
            self.order_id = f"{self.scenario.name}-v{self.vehicle_id}-1"
        else:  # an update, from the stitching node: the end of the fixed legs
            fixed = _kept_fixed_legs(plan, before, self.vehicle_id, step)
            legs = plan.legs[len(fixed) :]
            start, start_sequence = self._node(fixed[-1], entry=False), self.stitch_sequence
        self.update_id += 1
        nodes = [Node(start.node_id, start_sequence, True, node_position=start.node_position)]
        edges = []
        for k, leg in enumerate(legs):
            sequence = start_sequence + 2 * k
            end = self._node(leg, entry=False)
            edges.append(
                Edge(
                    self._edge_id(leg, step),
                    sequence + 1,
                    leg.fixed,
                    nodes[-1].node_id,
                    end.node_id,
                    orientation=math.pi if leg.progress is Progress.REVERSE else 0.0,
                    orientation_type="TANGENTIAL",
                )
            )
            goal = f"goal of task {leg.goal_for_task}" if leg.goal_for_task is not None else None
            nodes.append(
                Node(end.node_id, sequence + 2, leg.fixed, node_position=end.node_position, node_description=goal)
            )
        self.stitch_sequence = max(node.sequence_id for node in nodes if node.released)
        header = Header(
            self.header_id, timestamp, self.header.version, self.header.manufacturer, self.header.serial_number
        )
        self.header_id += 1
        return Order(header, self.order_id, self.update_id, tuple(nodes), tuple(edges))

    def _node(self, leg: FleetLeg, *, entry: bool) -> Node:
        """The node a leg enters (``entry``) or ends at, placed, with the vehicle's heading there."""
        graph = self.graph
        node_id = (graph.entry_node if entry else graph.exit_node)(leg.segment, leg.traverse)
        place = graph.places[node_id]
        segment = self.scenario.layout.segments[leg.segment]
        _, _, travel = segment.pose_at(0.0 if entry else segment.length, leg.traverse)
        heading = travel + (math.pi if leg.progress is Progress.REVERSE else 0.0)
        position = NodePosition(
            x=round(place.x, 6),
            y=round(place.y, 6),
            map_id=graph.map_id,
            theta=math.remainder(heading, math.tau),  # in -pi..pi, as the text bounds it
            allowed_deviation_xy=ALLOWED_DEVIATION_XY,
            allowed_deviation_theta=ALLOWED_DEVIATION_THETA,
        )
        return Node(node_id, 0, True, node_position=position)

    def _edge_id(self, leg: FleetLeg, step: int) -> str:
        try:
            return self.graph.edge_id(leg.segment, leg.traverse)
        except KeyError:
            msg = (
                f"step {step}: vehicle {self.vehicle_id}'s plan drives segment {leg.segment} {leg.traverse.value}, "
                f"against map {self.graph.map_id!r}'s one-way edge; no VDA 5050 edge drives it that way"
            )
            raise ExportError(msg) from None


def _kept_fixed_legs(plan: FleetPlan, before: FleetPlan, vehicle_id: int, step: int) -> tuple[FleetLeg, ...]:
    """The fixed legs the vehicle had before ``plan``, which ``plan`` must begin with."""
    fixed = tuple(leg for leg in before.legs if leg.fixed)
    kept = tuple(_drive(leg) for leg in plan.legs[: len(fixed)]) == tuple(_drive(leg) for leg in fixed)
    if not fixed or not kept:
        msg = (
            f"step {step}: vehicle {vehicle_id}'s accepted plan {_path(plan.legs)} does not begin with its fixed legs "
            f"{_path(fixed)}; a VDA 5050 order update continues the base, it cannot change it"
        )
        raise ExportError(msg)
    return fixed


def _drive(leg: FleetLeg) -> tuple[int, Traverse, Progress]:
    return leg.segment, leg.traverse, leg.progress


def _path(legs: Sequence[FleetLeg]) -> str:
    return "[" + ", ".join(f"{leg.segment}{leg.traverse.value[0]}" for leg in legs) + "]"


def _plan(record: Sequence[Any]) -> FleetPlan:
    """A plan as the trace writes it: [vehicle id, [[segment, traverse, progress, fixed, goal], ...]]."""
    vehicle_id, legs = record
    return FleetPlan(
        vehicle_id,
        tuple(FleetLeg(segment, _TRAVERSE[t], _PROGRESS[p], bool(fixed), goal) for segment, t, p, fixed, goal in legs),
    )


def _time_step_us(header_line: str) -> int:
    try:
        header = json.loads(header_line)
        step_us = header["time_step_us"]
    except (json.JSONDecodeError, KeyError, TypeError):
        step_us = None
    if not isinstance(step_us, int) or isinstance(step_us, bool) or step_us <= 0:
        msg = f"trace header={header_line[:80]!r} must be a fleetsim trace's header, with time_step_us > 0"
        raise ExportError(msg)
    return step_us


def _timestamp(microseconds: int) -> str:
    """ISO 8601 UTC: milliseconds, or microseconds when the time needs them."""
    moment = EPOCH + timedelta(microseconds=microseconds)
    fraction = f"{moment.microsecond // 1000:03d}" if moment.microsecond % 1000 == 0 else f"{moment.microsecond:06d}"
    return f"{moment:%Y-%m-%dT%H:%M:%S}.{fraction}Z"


def _node_document(node: Node) -> dict[str, Any]:
    document: dict[str, Any] = {"nodeId": node.node_id, "sequenceId": node.sequence_id, "released": node.released}
    position = node.node_position
    if position is not None:
        document["nodePosition"] = {
            "x": position.x,
            "y": position.y,
            **({"theta": position.theta} if position.theta is not None else {}),
            **(
                {"allowedDeviationXY": position.allowed_deviation_xy}
                if position.allowed_deviation_xy is not None
                else {}
            ),
            **(
                {"allowedDeviationTheta": position.allowed_deviation_theta}
                if position.allowed_deviation_theta is not None
                else {}
            ),
            "mapId": position.map_id,
        }
    if node.node_description is not None:
        document["nodeDescription"] = node.node_description
    document["actions"] = []
    return document


def _edge_document(edge: Edge) -> dict[str, Any]:
    document: dict[str, Any] = {
        "edgeId": edge.edge_id,
        "sequenceId": edge.sequence_id,
        "released": edge.released,
        "startNodeId": edge.start_node_id,
        "endNodeId": edge.end_node_id,
    }
    if edge.orientation is not None:
        document["orientation"] = edge.orientation
    if edge.orientation_type is not None:
        document["orientationType"] = edge.orientation_type
    document["actions"] = []
    return document
