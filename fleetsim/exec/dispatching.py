"""The dispatcher's messages of the JSON-lines protocol (1.5): the ``dispatch`` request and its answer.

A client that answers a 1.5 init (or later) with ``{"type": "ready", "dispatches": true}`` says it is a
dispatcher too. When a run has transport orders and no other dispatcher is named (``--dispatcher``, the
suite's ``dispatcher:``), fleetsim then asks it whenever a dispatcher is asked (orders released, a vehicle
out of work, the shift's dispatch period), between requests, with::

    {"type": "dispatch", "id": N, "board": BOARD, "fleet": FLEET}

``id`` counts on with the planner requests' ids; ``fleet`` is the fleet update a request would carry
(left out when the fleet is the one last sent). ``BOARD`` is what an in-process dispatcher's ``OrderBoard``
holds: ``time``; ``why`` (``release``, ``idle``, ``period``: each reason there is); ``orders``, the released
orders not yet completed in release order, each its order (``id``, ``stops``: each ``segment, progress,
dwell``; ``release``, ``deadline``, ``vehicle_types``: names or null for any, ``priority``) and where it
stands (``vehicle_id``: the vehicle holding it or null, ``started``: its vehicle reached its first stop,
``served``: stops served, ``released``: when it was released); ``sequences``, every vehicle's orders in
force (the started one first) as ``[vehicle_id, [order ids]]`` pairs in ascending vehicle id; ``idle``, the
vehicles without an order or task, ascending.

The answer is ``{"id": N, "assignments": [{"vehicle_id": V, "orders": [order ids]}...]}``
(``schemas/planner-dispatch-answer.schema.json``): each assignment gives a vehicle its sequence from now
on, as :class:`~fleetsim.dispatch.protocol.Assignment` does; an empty list changes nothing. The answer
is then judged by the dispatcher's rules exactly as an in-process dispatcher's.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Any

from fleetsim.dispatch.protocol import Assignment, OpenOrder, OrderBoard, Why
from fleetsim.exec.protocol import decode_progress, dumps
from fleetsim.orders import Order, Stop

__all__ = [
    "DISPATCH",
    "BoardEncoder",
    "BoardReader",
    "decode_assignments",
    "encode_assignments",
    "encode_board",
    "encode_order",
]

# A dispatch request: its id, the board, then (when the fleet changed) ',"fleet":' and the update.
DISPATCH = b'{"type":"dispatch","id":%d,"board":%b%b}\n'


def encode_order(order: Order) -> dict[str, Any]:
    """An order as the board shows it (its ``line`` in ``orders.csv`` stays behind: it is for messages)."""
    return {
        "id": order.id,
        "stops": [
            {
                "segment": stop.segment,
                "progress": None if stop.progress is None else stop.progress.value,
                "dwell": stop.dwell,
            }
            for stop in order.stops
        ],
        "release": order.release,
        "deadline": order.deadline,
        "vehicle_types": None if order.vehicle_types is None else list(order.vehicle_types),
        "priority": order.priority,
    }


def _standing(open_order: OpenOrder) -> dict[str, Any]:
    return {
        "vehicle_id": open_order.vehicle_id,
        "started": open_order.started,
        "served": open_order.served,
        "released": open_order.released,
    }


def encode_board(board: OrderBoard) -> dict[str, Any]:
    """The board as the dispatch request's ``board``."""
    return {
        "time": board.time,
        "why": list(board.why),
        "orders": [{**encode_order(entry.order), **_standing(entry)} for entry in board.orders.values()],
        "sequences": [[vehicle, list(sequence)] for vehicle, sequence in board.sequences.items()],
        "idle": list(board.idle),
    }


class BoardEncoder:
    """:func:`encode_board` as JSON, each order's own part encoded once for the run (an order stays open
    over many calls; what changes is where it stands)."""

    def __init__(self) -> None:
        self._orders: dict[str, tuple[Order, bytes]] = {}  # order id -> the order, its JSON without the "}"

    def encode(self, board: OrderBoard) -> bytes:
        orders = []
        kept: dict[str, tuple[Order, bytes]] = {}  # the open orders only: a long shift's encoder stays small
        for entry in board.orders.values():
            known = self._orders.get(entry.order.id)
            if known is None or known[0] is not entry.order:
                known = (entry.order, dumps(encode_order(entry.order))[:-1])
            kept[entry.order.id] = known
            orders.append(known[1] + b"," + dumps(_standing(entry))[1:])
        self._orders = kept
        return b'{"time":%b,"why":%b,"orders":[%b],"sequences":%b,"idle":%b}' % (
            dumps(board.time),
            dumps(list(board.why)),
            b",".join(orders),
            dumps([[vehicle, list(sequence)] for vehicle, sequence in board.sequences.items()]),
            dumps(list(board.idle)),
        )


def _order(data: Mapping[str, Any]) -> Order:
    stops = tuple(
        Stop(stop["segment"], None if stop["progress"] is None else decode_progress[stop["progress"]], stop["dwell"])
        for stop in data["stops"]
    )
    types = data["vehicle_types"]
    return Order(
        data["id"], stops, data["release"], data["deadline"], None if types is None else tuple(types), data["priority"]
    )


_ORDER_KEYS = ("id", "stops", "release", "deadline", "vehicle_types", "priority")


class BoardReader:
    """Boards from dispatch requests, for a dispatcher served in another process: the same
    :class:`~fleetsim.dispatch.protocol.OrderBoard` an in-process dispatcher is shown. An order is decoded
    once and is the same object on every board while it is open, as in process."""

    def __init__(self) -> None:
        self._orders: dict[str, tuple[list[Any], Order]] = {}  # order id -> its fields as sent, the order

    def board(self, data: Mapping[str, Any]) -> OrderBoard:
        orders: dict[str, OpenOrder] = {}
        kept: dict[str, tuple[list[Any], Order]] = {}  # the open orders only: a long shift's reader stays small
        for entry in data["orders"]:
            fields = [entry[key] for key in _ORDER_KEYS]
            known = self._orders.get(entry["id"])
            if known is None or known[0] != fields:
                known = (fields, _order(entry))
            kept[entry["id"]] = known
            orders[entry["id"]] = OpenOrder(
                known[1], entry["vehicle_id"], entry["started"], entry["served"], entry["released"]
            )
        self._orders = kept
        why: tuple[Why, ...] = tuple(data["why"])
        return OrderBoard(
            time=data["time"],
            why=why,
            orders=MappingProxyType(orders),
            sequences=MappingProxyType({vehicle: tuple(sequence) for vehicle, sequence in data["sequences"]}),
            idle=tuple(data["idle"]),
        )


def encode_assignments(number: int, assignments: Sequence[Assignment]) -> dict[str, Any]:
    """The answer to dispatch request ``number``."""
    return {
        "id": number,
        "assignments": [{"vehicle_id": item.vehicle_id, "orders": list(item.orders)} for item in assignments],
    }


def decode_assignments(answer: Mapping[str, Any]) -> list[Assignment]:
    """The assignments of a schema-valid answer, in its order."""
    return [Assignment(item["vehicle_id"], tuple(item["orders"])) for item in answer["assignments"]]
