"""Transport orders on fleetsim's own topics, where a master control dispatches them (issue 45).

When the VDA 5050 fleet is the run's dispatcher (a scenario with transport orders and no other dispatcher
named), each released order is published, retained, on ``<interfaceName>/fleetsim/transportOrders/<orderId>``
with its stops (the goal edges and nodes of each, as a task's message names them), dwell, release,
deadline, vehicle types and priority, and again whenever its state changes: ``RELEASED`` (no vehicle),
``ASSIGNED`` (to ``serialNumber``), ``STARTED`` (its vehicle has reached its first stop), ``servedStops``
counting up, ``COMPLETED``.

A master control *claims* an order for a vehicle on ``.../transportOrders/<orderId>/claim`` with
``{"serialNumber": "2"}``: the vehicle is to serve the order after those it holds. A claim is the
dispatcher's answer ``Assignment(vehicle, its sequence in force + the order)``, checked by the dispatcher's
rules (``fleetsim.dispatch.checks``) as any dispatcher's answer; claims are judged one a step, in arrival
order, each alone (a wrong claim never takes a right one down with it). A refused claim is a rejection of
the run with its code, and is told back on the order's topic as ``lastRefusal`` (the claim's
``serialNumber``, the ``code``, the ``reason``, the ``time``): retained in the order's message for an order
the master control has seen, and in a message of its own, not retained, with ``state: UNKNOWN`` for an
order it cannot have seen (unknown, or not released yet). A claim that is not one (not a JSON object, no
``serialNumber`` naming a vehicle id) is told back the same way with the code ``claim-invalid``.

An order id is one topic level: percent-encoded (RFC 3986) except letters, digits and ``_.-~``.
"""

from __future__ import annotations

import json
import sys
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any
from urllib.parse import quote, unquote

from fleetsim.dispatch.protocol import Assignment, OpenOrder, OrderBoard
from fleetsim.orders import Order
from fleetsim.planning.checks import Rejection
from fleetsim.scenario import Task
from fleetsim.vda5050.link import MqttLink
from fleetsim.vda5050.places import SiteGraph

__all__ = ["CLAIM_INVALID", "Claim", "ClaimInvalid", "TransportOrders", "goal_places", "order_level", "read_claim"]

CLAIM_INVALID = "claim-invalid"  # the code told back for a message on a claim topic that is not a claim


class ClaimInvalid(ValueError):
    """A message on the claim topic of ``order_id`` that is not a claim; its message says why."""

    def __init__(self, message: str, order_id: str) -> None:
        super().__init__(message)
        self.order_id = order_id


@dataclass(frozen=True, slots=True)
class Claim:
    """A master control's claim: vehicle ``vehicle_id`` (serial number ``serial``) is to serve ``order_id``."""

    order_id: str
    serial: str
    vehicle_id: int


def order_level(order_id: str) -> str:
    """The topic level that names ``order_id``."""
    return quote(order_id, safe="")


def goal_places(graph: SiteGraph, segment: int) -> tuple[list[str], list[str]]:
    """The edges a vehicle may reach ``segment`` by (one per way it may be driven) and its two nodes."""
    edges = sorted({graph.edge_id(segment, t) for t in graph.traverses(segment)})
    nodes = sorted({graph.node_at(segment, False), graph.node_at(segment, True)})
    return edges, nodes


def read_claim(order_id: str, payload: bytes) -> Claim:
    """The claim ``payload`` makes for ``order_id``, or :class:`ClaimInvalid` saying what is wrong."""
    try:
        document = json.loads(payload)
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        msg = f"the claim for order {order_id!r} is not JSON: {error}"
        raise ClaimInvalid(msg, order_id) from None
    if not isinstance(document, dict):
        msg = f'the claim for order {order_id!r} is {document!r}; it must be an object {{"serialNumber": "..."}}'
        raise ClaimInvalid(msg, order_id)
    serial = document.get("serialNumber")
    if not isinstance(serial, str) or not _is_vehicle_id(serial):
        msg = (
            f"the claim for order {order_id!r} has serialNumber={serial!r}; it must be a vehicle's serial "
            "number (its vehicle id, a string of digits)"
        )
        raise ClaimInvalid(msg, order_id)
    return Claim(order_id, serial, int(serial))


def _is_vehicle_id(serial: str) -> bool:
    digits = serial[1:] if serial.startswith("-") else serial
    return digits.isascii() and digits.isdigit() and str(int(serial)) == serial


class TransportOrders:
    """The transport orders of one run on ``<prefix>/<orderId>``, and the claims on ``.../claim``.

    The fleet shows it every board the loop shows the dispatcher (:meth:`answer`) and every step's task
    queues (:meth:`observe`); :meth:`waiting` says when a call is wanted: a claim waits, a claim was judged
    (the board after it shows its outcome), or a vehicle has reached a stop the last board did not show
    served (the next shows it served, or the order completed).
    """

    def __init__(self, link: MqttLink, prefix: str, graph: SiteGraph) -> None:
        self.link = link
        self.prefix = prefix
        self.graph = graph
        self.claims: deque[Claim | ClaimInvalid] = deque()  # in arrival order, each told back in its turn
        self.claimed = 0  # claims judged in all
        self._open: dict[str, OpenOrder] = {}  # the last board's open orders
        self._said: dict[str, tuple[Any, ...]] = {}  # what each known order's message last said
        self._orders: dict[str, Order] = {}  # every order the master control has been shown
        self._time: dict[str, float] = {}  # when each known order's state last changed
        self._refusal: dict[str, dict[str, Any]] = {}  # each known order's last refused claim
        self._judging: tuple[Claim, float] | None = None
        self._stale = False

    def subscribe(self) -> None:
        self.link.subscribe(f"{self.prefix}/+/claim", qos=1)

    # -- asked by the loop ------------------------------------------------------------------------------

    def waiting(self) -> bool:
        """Whether the dispatcher wants to be called this step (see the class docstring)."""
        self._take()
        return bool(self.claims) or self._stale

    def answer(self, board: OrderBoard) -> list[Assignment]:
        """Publish what ``board`` shows changed; the next claim as an answer (none: an empty one)."""
        self.show(board)
        self._stale = False
        self._judging = None
        self._take()
        while self.claims and isinstance(self.claims[0], ClaimInvalid):
            invalid = self.claims.popleft()
            assert isinstance(invalid, ClaimInvalid)
            self._tell_refusal(invalid.order_id, None, CLAIM_INVALID, str(invalid), board.time)
        if not self.claims:
            return []
        claim = self.claims.popleft()
        assert isinstance(claim, Claim)
        self.claimed += 1
        self._judging = (claim, board.time)
        self._stale = True  # the next board shows whether it was taken
        held = list(board.sequences.get(claim.vehicle_id, ()))
        return [Assignment(claim.vehicle_id, (*held, claim.order_id) if claim.order_id not in held else tuple(held))]

    def refuse(self, rejections: Sequence[Rejection]) -> None:
        """The claim just answered was refused for ``rejections``: tell the master control."""
        if self._judging is None or not rejections:
            return
        (claim, now), self._judging = self._judging, None
        reason = "; ".join(r.message for r in rejections)
        self._tell_refusal(claim.order_id, claim.serial, rejections[0].code.value, reason, now)

    def observe(self, tasks: Mapping[int, tuple[Task, ...]]) -> None:
        """The step's task queues: a vehicle that has reached a stop not shown served wants the next board."""
        for order_id, shown in self._open.items():
            if shown.vehicle_id is None:
                continue
            left = sum(1 for task in tasks.get(shown.vehicle_id, ()) if task.order_id == order_id)
            if len(shown.order.stops) - left > shown.served:
                self._stale = True
                return

    # -- publishing -------------------------------------------------------------------------------------

    def show(self, board: OrderBoard) -> None:
        """Publish the state of every order ``board`` shows changed, and those it no longer shows completed."""
        for order_id in [o for o in self._open if o not in board.orders]:  # in release order
            shown = self._open[order_id]
            self._say(order_id, ("COMPLETED", _serial(shown.vehicle_id), len(shown.order.stops)), board.time)
        for order_id, shown in board.orders.items():
            self._orders[order_id] = shown.order
            state = "RELEASED" if shown.vehicle_id is None else "STARTED" if shown.started else "ASSIGNED"
            self._say(order_id, (state, _serial(shown.vehicle_id), shown.served), board.time)
        self._open = dict(board.orders)

    def _say(self, order_id: str, said: tuple[Any, ...], now: float) -> None:
        if self._said.get(order_id) == said:
            return
        self._said[order_id] = said
        self._time[order_id] = now
        self._publish_order(order_id)

    def _publish_order(self, order_id: str) -> None:
        order = self._orders[order_id]
        state, serial, served = self._said[order_id]
        stops = []
        for stop in order.stops:
            edges, nodes = goal_places(self.graph, stop.segment)
            progress = stop.progress.value if stop.progress is not None else None
            stops.append({"goalEdgeIds": edges, "goalNodeIds": nodes, "goalProgress": progress, "dwell": stop.dwell})
        document = {
            "orderId": order_id,
            "state": state,
            "serialNumber": serial,
            "stops": stops,
            "servedStops": served,
            "release": order.release,
            "deadline": order.deadline,
            "vehicleTypes": list(order.vehicle_types) if order.vehicle_types is not None else None,
            "priority": order.priority,
            "time": round(self._time[order_id], 6),
            "lastRefusal": self._refusal.get(order_id),
        }
        self.link.publish(self._topic(order_id), _json(document), qos=1, retain=True)

    def _tell_refusal(self, order_id: str, serial: str | None, code: str, reason: str, now: float) -> None:
        refusal = {"serialNumber": serial, "code": code, "reason": reason, "time": round(now, 6)}
        if order_id in self._said:  # an order the master control has been shown: its message says it
            self._refusal[order_id] = refusal
            self._publish_order(order_id)
            return
        document = {"orderId": order_id, "state": "UNKNOWN", "time": round(now, 6), "lastRefusal": refusal}
        self.link.publish(self._topic(order_id), _json(document), qos=1, retain=False)

    # -- claims -----------------------------------------------------------------------------------------

    def _take(self) -> None:
        for inbound in self.link.drain():
            if inbound.retained:
                continue  # a claim of an earlier run, kept by the broker: history, not a claim
            level = inbound.topic[len(self.prefix) + 1 : -len("/claim")]
            order_id = unquote(level)
            try:
                self.claims.append(read_claim(order_id, inbound.payload))
            except ClaimInvalid as invalid:
                print(f"fleetsim: refused a message on {inbound.topic}: {invalid}", file=sys.stderr, flush=True)
                self.claims.append(invalid)

    def _topic(self, order_id: str) -> str:
        return f"{self.prefix}/{order_level(order_id)}"


def _serial(vehicle_id: int | None) -> str | None:
    return None if vehicle_id is None else str(vehicle_id)


def _json(document: Any) -> bytes:
    return json.dumps(document, separators=(",", ":")).encode()
