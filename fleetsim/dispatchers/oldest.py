"""Oldest order first (openTCS-style, by age): each idle vehicle takes the oldest order it may carry."""

from __future__ import annotations

import math

from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.dispatchers.travel import TravelTimes
from fleetsim.dispatchers.waiting import may_carry, next_stop, waiting_orders
from fleetsim.layout.layout import Layout
from fleetsim.planning.snapshot import FleetSnapshot

__all__ = ["OldestFirstDispatcher"]


class OldestFirstDispatcher:
    """Oldest order first, whatever the distance, as openTCS's dispatcher orders by age.

    On every call, each idle vehicle (``board.idle``), by ascending id, takes the most urgent order no
    vehicle holds (higher priority first, then the oldest, then by id) that its type may carry and that it
    can reach at all (``fleetsim.dispatchers.travel.TravelTimes``, finite). It never takes an
    order back, and answers ``[]`` when no idle vehicle gets an order.
    """

    def __init__(self) -> None:
        self.travel = TravelTimes()  # the map searches, kept for the run

    def dispatch(self, board: OrderBoard, fleet: FleetSnapshot, layout: Layout) -> list[Assignment]:
        waiting = waiting_orders(board)
        answer: list[Assignment] = []
        for vehicle in board.idle:
            if not waiting:
                break
            state = fleet.vehicles[vehicle]
            start = self.travel.start(layout, state, fleet.plans[vehicle])
            for index, order in enumerate(waiting):
                if may_carry(order.order, state.type) and math.isfinite(
                    self.travel.time_from(layout, start, next_stop(order))
                ):
                    answer.append(Assignment(vehicle, (order.id,)))
                    del waiting[index]
                    break
        return answer
