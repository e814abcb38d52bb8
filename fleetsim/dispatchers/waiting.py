"""Which open orders wait for a vehicle, most urgent first, and which vehicles may carry them."""

from __future__ import annotations

import re

from fleetsim.dispatch.protocol import OpenOrder, OrderBoard
from fleetsim.orders import Order, Stop
from fleetsim.scenario import VehicleType

__all__ = ["may_carry", "next_stop", "waiting_orders"]

_NUMBERS = re.compile(r"(\D*)(\d*)")


def _id_key(order_id: str) -> tuple[tuple[tuple[str, int], ...], str]:
    """Ids in natural order (``s2`` before ``s10``), then as written (``s01`` beside ``s1``)."""
    parts = tuple((text, int(digits) if digits else -1) for text, digits in _NUMBERS.findall(order_id))
    return parts, order_id


def waiting_orders(board: OrderBoard) -> list[OpenOrder]:
    """The open orders no vehicle holds, most urgent first: higher priority, then released earlier
    (``order.release``), then by id (natural order)."""
    return sorted(board.unassigned(), key=lambda o: (-o.order.priority, o.order.release, _id_key(o.id)))


def may_carry(order: Order, vehicle_type: VehicleType) -> bool:
    """Whether a vehicle of ``vehicle_type`` is allowed to carry ``order``."""
    return order.vehicle_types is None or vehicle_type.name in order.vehicle_types


def next_stop(order: OpenOrder) -> Stop:
    """The order's first stop not yet served (its first, for an order nobody holds)."""
    stops = order.order.stops
    return stops[min(order.served, len(stops) - 1)]
