"""The dispatcher protocol (issue 45; the thesis's §2.3 scheduler): which vehicle serves which order.

A dispatcher is any object with ``dispatch(board, fleet, layout)``. It is asked when orders are released,
when a vehicle runs out of work, and every ``shift.dispatch_period`` seconds if the suite sets one; it
answers with [`Assignment`][fleetsim.dispatch.protocol.Assignment]s. Each assignment gives one vehicle its
sequence of orders from now on, after what it has started; vehicles not named keep theirs. The stops of
the assigned orders become the vehicle's task queue, so the route planner sees ordinary tasks (with their
``order_id``, ``stop`` and ``deadline``).

Rules (each a stable code, see ``fleetsim.dispatch.checks``): an order goes to one vehicle at a time; it
may be taken back and given to another until its vehicle reaches its first stop, never after; orders not
released, unknown or completed, and vehicles of a type the order excludes, are refused; an answer with any
refused assignment is refused whole, and the assignments in force stand.

A planner class may be the dispatcher too (one object with ``dispatch`` beside ``plan_routes`` and
``fix_legs``), or the suite (``dispatcher:``) and the command line (``--dispatcher``) name one apart.

Two optional hooks, for a dispatcher whose decisions arrive on their own time (the VDA 5050 fleet, whose
master control claims orders whenever it likes: ``fleetsim.vda5050.transport``): ``wants_call() -> bool``,
asked at the start of every step, asks for a call this step (``why`` then holds ``"request"``; it is made
even when no order is open), and ``refused(rejections)`` is told the rules its last answer broke when that
answer was refused. Both are plain calls in the loop's thread: keep them cheap, and let them not raise.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, Protocol, runtime_checkable

from fleetsim.orders import Order

if TYPE_CHECKING:
    from fleetsim.layout.layout import Layout
    from fleetsim.planning.snapshot import FleetSnapshot

__all__ = ["Assignment", "Dispatcher", "OpenOrder", "OrderBoard", "Why"]

# Why the dispatcher is asked: orders were released, a vehicle ran out of work, its period came round, or
# it asked to be (its optional ``wants_call()``).
Why = Literal["release", "idle", "period", "request"]


@dataclass(frozen=True, slots=True)
class Assignment:
    """``vehicle_id`` serves ``orders`` (ids), in this sequence, after the order it has started (if any).

    An empty sequence takes back every order of the vehicle that it has not started. An order named here
    that another vehicle holds and has not started is taken from that vehicle.
    """

    vehicle_id: int
    orders: tuple[str, ...]

    def __post_init__(self) -> None:
        # A list is accepted and frozen (as FleetPlan's legs are); what it holds is judged by the checks.
        if isinstance(self.orders, Sequence) and not isinstance(self.orders, (str, bytes, tuple)):
            object.__setattr__(self, "orders", tuple(self.orders))


@dataclass(frozen=True, slots=True)
class OpenOrder:
    """A released order not yet completed, as the dispatcher sees it.

    Attributes:
        order: The order (its stops, deadline, allowed vehicle types, priority).
        vehicle_id: The vehicle it is assigned to, or ``None``.
        started: Whether its vehicle has reached its first stop (then it can no longer be taken back).
        served: How many of its stops are served (reached and dwelt at).
        released: Seconds of simulated time it was released at.
    """

    order: Order
    vehicle_id: int | None
    started: bool
    served: int
    released: float

    @property
    def id(self) -> str:
        return self.order.id


@dataclass(frozen=True, slots=True)
class OrderBoard:
    """What a dispatcher is shown: the open orders and every vehicle's sequence, read-only.

    Attributes:
        time: Simulated seconds now.
        why: Why it is asked (several reasons at once: each is listed).
        orders: The released orders not yet completed, by id, in release order.
        sequences: Every vehicle's orders in force (the started one first), by vehicle id, ascending.
        idle: The vehicles with no order and no task left, ascending.
    """

    time: float
    why: tuple[Why, ...]
    orders: Mapping[str, OpenOrder]
    sequences: Mapping[int, tuple[str, ...]]
    idle: tuple[int, ...]

    def unassigned(self) -> tuple[OpenOrder, ...]:
        """The open orders no vehicle holds, in release order."""
        return tuple(order for order in self.orders.values() if order.vehicle_id is None)


@runtime_checkable
class Dispatcher(Protocol):
    """Assigns released orders to vehicles. A fresh instance serves one run."""

    def dispatch(self, board: OrderBoard, fleet: FleetSnapshot, layout: Layout) -> Sequence[Assignment]:
        """The assignments to change (an empty sequence: none).

        Args:
            board: The open orders and every vehicle's sequence of orders.
            fleet: The whole fleet now, read-only (states, plans, task queues), as a planner sees it.
            layout: The map.

        Returns:
            One [`Assignment`][fleetsim.dispatch.protocol.Assignment] per vehicle whose sequence changes.
        """
        ...
