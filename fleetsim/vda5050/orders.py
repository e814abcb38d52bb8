"""Orders onto the plan model: a VDA 5050 order (or order update) read as a vehicle's new route plan.

The thesis's fixed legs are VDA 5050's base, its planned legs the horizon. An order's edges, in sequence,
become legs: a released edge a fixed leg, an unreleased one a planned leg; the segment and traverse come
from the edge's id and its nodes (:mod:`fleetsim.vda5050.places`), the progress from the edge's
``orientation`` (TANGENTIAL, the default: about 0 nose first, about pi backing; GLOBAL: against the
edge's direction of travel) or, without one, the legal continuation of the leg before (nose first where
both are legal).

Where the order joins what the vehicle already has:

- An **update** (same ``orderId``, higher ``orderUpdateId``) starts at the stitching node, the last
  released node of the order so far, with its ``sequenceId``. The plan is the vehicle's fixed legs (the
  base it still drives) followed by the update's legs: the old horizon is replaced.
- A **new order** (another ``orderId``) is taken when the vehicle has no base left beyond the leg it is on:
  it starts at that leg's exit node (where the vehicle stands once it has driven it), or at its entry
  node (the vehicle's last node), the order's first edge being that leg.
- The same ``orderUpdateId`` again is a resend and changes nothing; a lower one is refused.

The plan is then judged by fleetsim's own checks, exactly as any planner's; a VDA 5050 error of the
standard's kind is derived from the check's code (:func:`vda_error`), so the vehicle's state and the
run's result say the same thing. A wrong join makes a plan that does not start with the vehicle's fixed
legs (the order as it reads, on its own), which the checks reject as ``fixed-legs-changed``. Faults of the
message itself that no plan can show (sequence ids, a base after the horizon, an edge between other nodes
than its neighbours) are :attr:`Reading.problems`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

from fleetsim.enums import Progress, Traverse
from fleetsim.layout.layout import Layout
from fleetsim.planning.checks import Rejection, RejectionCode
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.scenario import VehicleType
from fleetsim.vda5050.model import Edge, ErrorReference, Node, Order, VdaError
from fleetsim.vda5050.places import EdgeProblem, SiteGraph

__all__ = [
    "NO_SEGMENT",
    "Join",
    "OrderStatus",
    "Reading",
    "join_order",
    "read_order",
    "vda_error",
]

# The segment a leg names when its edge is no edge of the map: no map has a segment 0 (Tiled ids start
# at 1, LIF and RMF segments are numbered from 1), so the checks reject the leg as ``unknown-segment``.
NO_SEGMENT = 0


class Join(str, Enum):
    """How an order relates to the vehicle's current one."""

    NEW = "new"  # another orderId
    UPDATE = "update"  # the same orderId, a higher orderUpdateId
    RESENT = "resent"  # the same orderId and orderUpdateId: nothing changes
    OUTDATED = "outdated"  # the same orderId, a lower orderUpdateId: refused


@dataclass(frozen=True, slots=True)
class OrderStatus:
    """What a vehicle holds of its current order: ids, and the stitching node (its last released node)."""

    order_id: str = ""
    order_update_id: int = 0
    stitch_node_id: str = ""
    stitch_sequence_id: int = 0


@dataclass(frozen=True, slots=True)
class Reading:
    """An order read onto legs: ``legs[i]`` drives ``edges[i]``; ``problems`` are faults of the message
    that no plan shows (each a ``validationError``)."""

    legs: tuple[FleetLeg, ...]
    edges: tuple[Edge, ...]
    nodes: tuple[Node, ...]
    problems: tuple[VdaError, ...]


def read_order(order: Order, graph: SiteGraph, layout: Layout, vehicle_type: VehicleType, start: Progress) -> Reading:
    """The order's edges as legs, in sequence order (``start``: the progress the vehicle has before the
    first edge, for an edge without an orientation)."""
    problems: list[VdaError] = []
    nodes = tuple(sorted(order.nodes, key=lambda n: n.sequence_id))
    edges = tuple(sorted(order.edges, key=lambda e: e.sequence_id))
    problems += _sequence_problems(order, nodes, edges)
    problems += _base_problems(nodes, edges)
    legs: list[FleetLeg] = []
    progress = start
    for index, edge in enumerate(edges):
        if index + 1 < len(nodes) and (edge.start_node_id, edge.end_node_id) != (
            nodes[index].node_id,
            nodes[index + 1].node_id,
        ):
            problems.append(
                _problem(
                    f"edge {edge.edge_id!r} (sequenceId {edge.sequence_id}) runs from {edge.start_node_id!r} to "
                    f"{edge.end_node_id!r}, but its neighbours in the order are nodes {nodes[index].node_id!r} and "
                    f"{nodes[index + 1].node_id!r}",
                    ("edgeId", edge.edge_id),
                    ("sequenceId", str(edge.sequence_id)),
                )
            )
        try:
            segment, traverse = graph.leg_of(edge.edge_id, edge.start_node_id, edge.end_node_id)
        except EdgeProblem as problem:
            problems.append(
                _problem(str(problem), ("edgeId", edge.edge_id), (problem.reference, _value(edge, problem)))
            )
            legs.append(FleetLeg(NO_SEGMENT, Traverse.FORWARD, progress, edge.released))
            continue
        previous = legs[-1] if legs and legs[-1].segment != NO_SEGMENT else None
        progress = _progress(edge, layout, vehicle_type, previous, segment, traverse, progress)
        legs.append(FleetLeg(segment, traverse, progress, edge.released))
    return Reading(tuple(legs), edges, nodes, tuple(problems))


def join_order(
    order: Order,
    reading: Reading,
    status: OrderStatus,
    current: FleetPlan,
    graph: SiteGraph,
) -> tuple[Join, FleetPlan | None, tuple[VdaError, ...]]:
    """How ``order`` joins the vehicle's current plan, the plan it makes (None: nothing to do) and the
    VDA 5050 errors of the join."""
    fixed = tuple(leg for leg in current.legs if leg.fixed)
    first = reading.nodes[0] if reading.nodes else None
    alone = FleetPlan(current.vehicle_id, reading.legs)  # the order read on its own
    if status.order_id and order.order_id == status.order_id:
        if order.order_update_id == status.order_update_id:
            return Join.RESENT, None, ()
        if order.order_update_id < status.order_update_id:
            error = VdaError(
                "orderUpdateError",
                f"orderUpdateId {order.order_update_id} of order {order.order_id!r} is lower than the current "
                f"{status.order_update_id}; the update is refused",
                error_references=_refs(("orderId", order.order_id), ("orderUpdateId", str(order.order_update_id))),
            )
            return Join.OUTDATED, None, (error,)
        if first is not None and (first.node_id, first.sequence_id) == (
            status.stitch_node_id,
            status.stitch_sequence_id,
        ):
            return Join.UPDATE, FleetPlan(current.vehicle_id, fixed + reading.legs), ()
        at = f"node {first.node_id!r} (sequenceId {first.sequence_id})" if first is not None else "no node"
        error = VdaError(
            "orderUpdateError",
            f"the update {order.order_update_id} of order {order.order_id!r} starts at {at}, not at the stitching node "
            f"{status.stitch_node_id!r} (sequenceId {status.stitch_sequence_id}), the last released node so far: "
            "an update continues the base, it does not change it",
            error_references=_refs(("orderId", order.order_id), ("orderUpdateId", str(order.order_update_id))),
        )
        return Join.UPDATE, alone, (error,)
    end = fixed[-1] if fixed else current.legs[0]
    end_node = graph.exit_node(end.segment, end.traverse)
    entry_node = graph.entry_node(current.legs[0].segment, current.legs[0].traverse)
    place = graph.node(first.node_id) if first is not None else None
    first_id = place.node_id if place is not None else None
    if first_id is not None and first_id == end_node and len(fixed) <= 1:
        return Join.NEW, FleetPlan(current.vehicle_id, fixed + reading.legs), ()
    if first_id is not None and first_id == entry_node and len(fixed) <= 1:
        return Join.NEW, alone, ()  # its first edge must be the leg the vehicle is on: the checks see to that
    if len(fixed) > 1:
        description = (
            f"order {order.order_id!r} arrived while order {status.order_id!r} still has base to drive "
            f"(up to node {end_node!r}); update that order (same orderId, higher orderUpdateId) or cancel it first"
        )
        kind = "orderUpdateError"
    else:
        where = f"node {first.node_id!r}" if first is not None else "no node"
        description = (
            f"order {order.order_id!r} starts at {where}, but the vehicle is on the edge from node {entry_node!r} "
            f"to node {end_node!r}: an order starts at one of them"
        )
        kind = "noRouteError"
    error = VdaError(kind, description, error_references=_refs(("orderId", order.order_id)))
    return Join.NEW, alone, (error,)


# What each check's rejection is in VDA 5050 terms: the error type, and what it refers to.
_KINDS = {
    RejectionCode.UNKNOWN_SEGMENT: "validationError",
    RejectionCode.EMPTY_PLAN: "validationError",
    RejectionCode.FIXED_NOT_CONTIGUOUS: "validationError",
    RejectionCode.FIXED_LEGS_CHANGED: "orderUpdateError",
    RejectionCode.NOT_CONNECTED: "noRouteError",
    RejectionCode.WRONG_WAY: "noRouteError",
    RejectionCode.ILLEGAL_PROGRESS_CHANGE: "noRouteError",
}


def vda_error(rejection: Rejection, order: Order, edges: Sequence[Edge | None]) -> VdaError:
    """The VDA 5050 error of a plan the checks rejected. ``edges[i]`` is the order's edge behind leg ``i``
    of the rejected plan (None for the fixed legs the vehicle had before the order)."""
    references = [("headerId", str(order.header.header_id)), ("orderId", order.order_id)]
    edge = edges[rejection.leg_index] if rejection.leg_index is not None and rejection.leg_index < len(edges) else None
    if edge is not None:
        references += [("edgeId", edge.edge_id), ("sequenceId", str(edge.sequence_id))]
    return VdaError(
        _KINDS.get(rejection.code, "orderError"),
        f"{rejection.code.value}: {rejection.message}",
        error_references=_refs(*references),
    )


def _sequence_problems(order: Order, nodes: tuple[Node, ...], edges: tuple[Edge, ...]) -> list[VdaError]:
    """Nodes and edges must alternate by sequenceId, a node first and last: node k has start + 2k, edge k
    start + 2k + 1 (an update continues the numbering from its stitching node)."""
    problems = []
    if not nodes:
        return [_problem(f"order {order.order_id!r} has no nodes; it needs at least one", ("orderId", order.order_id))]
    if len(edges) != len(nodes) - 1:
        problems.append(
            _problem(
                f"order {order.order_id!r} has {len(nodes)} nodes and {len(edges)} edges; an order has one edge fewer "
                "than nodes",
                ("orderId", order.order_id),
            )
        )
    start = nodes[0].sequence_id
    numbered = [("node", "nodeId", n.node_id, n.sequence_id, start + 2 * k) for k, n in enumerate(nodes)]
    numbered += [("edge", "edgeId", e.edge_id, e.sequence_id, start + 2 * k + 1) for k, e in enumerate(edges)]
    for kind, key, ident, sequence_id, expected in numbered:
        if sequence_id != expected:
            problems.append(
                _problem(
                    f"{kind} {ident!r} has sequenceId {sequence_id}, expected {expected}: nodes and edges alternate by "
                    "sequenceId (node, edge, node, ...)",
                    (key, ident),
                    ("sequenceId", str(sequence_id)),
                )
            )
    return problems


def _base_problems(nodes: tuple[Node, ...], edges: tuple[Edge, ...]) -> list[VdaError]:
    """The released nodes and edges form the base: a prefix of the order, ending with a node."""
    items: list[Node | Edge] = [item for pair in zip(nodes, edges, strict=False) for item in pair]
    if len(nodes) > len(edges):
        items.append(nodes[len(edges)])
    problems = []
    horizon = next((i for i, item in enumerate(items) if not item.released), len(items))
    for item in items[horizon:]:
        if item.released:
            kind, key, ident = (
                ("node", "nodeId", item.node_id) if isinstance(item, Node) else ("edge", "edgeId", item.edge_id)
            )
            problems.append(
                _problem(
                    f"{kind} {ident!r} (sequenceId {item.sequence_id}) is released after the horizon begins: the base "
                    "(released nodes and edges) comes first",
                    (key, ident),
                    ("sequenceId", str(item.sequence_id)),
                )
            )
    if horizon and horizon < len(items) and isinstance(items[horizon - 1], Edge):
        edge = items[horizon - 1]
        assert isinstance(edge, Edge)
        problems.append(
            _problem(
                f"edge {edge.edge_id!r} is released but its end node {edge.end_node_id!r} is not: the base ends with a node",
                ("edgeId", edge.edge_id),
                ("sequenceId", str(edge.sequence_id)),
            )
        )
    return problems


def _progress(
    edge: Edge,
    layout: Layout,
    vehicle_type: VehicleType,
    previous: FleetLeg | None,
    segment: int,
    traverse: Traverse,
    before: Progress,
) -> Progress:
    if edge.orientation is not None and math.isfinite(edge.orientation):
        if (edge.orientation_type or "TANGENTIAL") == "GLOBAL":
            _, _, travel = layout.segments[segment].pose_at(0.0, traverse)
            offset = edge.orientation - travel
        else:
            offset = edge.orientation
        return Progress.FORWARD if math.cos(offset) >= 0.0 else Progress.REVERSE
    if previous is None:
        return before
    legal = [
        c.progress
        for c in layout.continuations(vehicle_type, previous.segment, previous.traverse, previous.progress)
        if (c.segment, c.traverse) == (segment, traverse)
    ]
    if not legal:
        return previous.progress  # no legal way on: the checks say so (not-connected, illegal-progress-change)
    return Progress.FORWARD if Progress.FORWARD in legal else legal[0]


def _problem(description: str, *references: tuple[str, str]) -> VdaError:
    return VdaError("validationError", description, error_references=_refs(*references))


def _refs(*pairs: tuple[str, str]) -> tuple[ErrorReference, ...]:
    return tuple(ErrorReference(key, value) for key, value in pairs)


def _value(edge: Edge, problem: EdgeProblem) -> str:
    return {"edgeId": edge.edge_id, "startNodeId": edge.start_node_id, "endNodeId": edge.end_node_id}[problem.reference]
