"""The dispatcher's rules: an answer is checked whole, and refused whole if any assignment breaks one.

Each rule is a stable code of :class:`~fleetsim.planning.checks.RejectionCode` (``assignment-*``,
``order-*``), recorded as a rejection of the assignment's vehicle, so suites expect them as any
rejection (``expect.rejections: [order-started]``). What is not an answer at all (not a sequence of
:class:`~fleetsim.dispatch.protocol.Assignment`, a vehicle id that is not an integer, an order id that is
not a string) is a fault of the dispatcher, as a planner's garbage is (:func:`validate_answer`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from fleetsim.dispatch.protocol import Assignment
from fleetsim.errors import PlannerError
from fleetsim.orders import Order
from fleetsim.planning.checks import Rejection, RejectionCode

__all__ = ["AnswerContext", "check_answer", "validate_answer"]

_WHERE = "dispatch()"


def validate_answer(answer: object) -> tuple[Assignment, ...]:
    """The answer's assignments, or a :class:`PlannerError` saying exactly what is wrong with it."""
    if isinstance(answer, (str, bytes, Mapping)) or not isinstance(answer, Sequence):
        msg = f"{_WHERE} returned {answer!r}; it must return a list of Assignment items"
        raise PlannerError(msg)
    for index, item in enumerate(answer):
        if not isinstance(item, Assignment):
            msg = f"{_WHERE} returned item {index} = {item!r}; each item must be an Assignment(vehicle_id, orders)"
            raise PlannerError(msg)
        if type(item.vehicle_id) is not int:
            msg = f"{_WHERE} returned item {index} with vehicle_id={item.vehicle_id!r}; it must be an int"
            raise PlannerError(msg)
        if not isinstance(item.orders, tuple) or not all(type(o) is str for o in item.orders):
            msg = f"{_WHERE} returned item {index} with orders={item.orders!r}; it must be a list of order ids (str)"
            raise PlannerError(msg)
    return tuple(answer)


@dataclass(frozen=True, slots=True)
class AnswerContext:
    """What an answer is checked against.

    Attributes:
        vehicle_types: Each vehicle's type name, by id.
        known: Every order the run knows of, by id: those of ``orders.csv`` (released or not) and the
            generated ones released so far (a generated order does not exist before its release).
        released: The ids of the released orders not yet completed.
        completed: The ids of the completed orders.
        holder: The vehicle each released, open order is assigned to (absent: none).
        started: The ids of the orders whose vehicle has reached their first stop.
    """

    vehicle_types: Mapping[int, str]
    known: Mapping[str, Order]
    released: frozenset[str]
    completed: frozenset[str]
    holder: Mapping[str, int]
    started: frozenset[str]


def check_answer(assignments: Sequence[Assignment], context: AnswerContext) -> list[Rejection]:
    """Every rule the assignments break, in answer order (empty: the answer may be applied)."""
    problems: list[Rejection] = []
    seen_vehicles: set[int] = set()
    given: dict[str, int] = {}  # order id -> the vehicle an earlier assignment of this answer gave it to
    for assignment in assignments:
        vehicle = assignment.vehicle_id

        def refuse(code: RejectionCode, message: str, vehicle: int = vehicle) -> None:
            problems.append(Rejection(code, vehicle, None, None, f"assignment for vehicle {vehicle}: {message}"))

        if vehicle not in context.vehicle_types:
            known = ", ".join(str(v) for v in sorted(context.vehicle_types)) or "none"
            refuse(RejectionCode.ASSIGNMENT_UNKNOWN_VEHICLE, f"no such vehicle (vehicles: {known})")
            continue
        if vehicle in seen_vehicles:
            refuse(RejectionCode.ASSIGNMENT_TWICE, "a second assignment for the vehicle in one answer")
            continue
        seen_vehicles.add(vehicle)
        type_name = context.vehicle_types[vehicle]
        for order_id in assignment.orders:
            problem = _order_problem(order_id, vehicle, type_name, given, context)
            if problem is not None:
                refuse(*problem)
            given.setdefault(order_id, vehicle)
        # An order this vehicle has started stays its own: an answer cannot give it to anyone else.
    for order_id, vehicle in sorted(given.items()):
        holder = context.holder.get(order_id)
        if order_id in context.started and holder is not None and holder != vehicle:
            msg = (
                f"assignment for vehicle {vehicle}: order {order_id!r} is vehicle {holder}'s, which has reached "
                "its first stop; an order may be given to another vehicle only until then"
            )
            problems.append(Rejection(RejectionCode.ORDER_STARTED, vehicle, None, None, msg))
    return problems


def _order_problem(
    order_id: str, vehicle: int, type_name: str, given: Mapping[str, int], context: AnswerContext
) -> tuple[RejectionCode, str] | None:
    """The rule naming ``order_id`` for ``vehicle`` breaks, if any (the first, in the rules' order)."""
    if order_id not in context.known:
        return RejectionCode.ORDER_UNKNOWN, f"order {order_id!r} does not exist"
    if order_id in context.completed:
        return RejectionCode.ORDER_COMPLETED, f"order {order_id!r} is already completed"
    if order_id not in context.released:
        release = context.known[order_id].release
        return RejectionCode.ORDER_UNRELEASED, f"order {order_id!r} is not released yet (release at {release:g} s)"
    if order_id in given:
        other = given[order_id]
        where = "twice in its sequence" if other == vehicle else f"also given to vehicle {other} in this answer"
        return RejectionCode.ORDER_TWICE, f"order {order_id!r} is {where}"
    allowed = context.known[order_id].vehicle_types
    if allowed is not None and type_name not in allowed:
        return (
            RejectionCode.ORDER_VEHICLE_TYPE,
            f"order {order_id!r} may be carried by vehicle types {', '.join(allowed)}, not {type_name!r}",
        )
    return None
