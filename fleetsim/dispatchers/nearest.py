"""The thesis's scheduler (§2.3): each waiting order to the idle vehicle that reaches its first stop soonest."""

from __future__ import annotations

import math

from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.dispatchers.travel import TravelTimes
from fleetsim.dispatchers.waiting import may_carry, next_stop, waiting_orders
from fleetsim.layout.layout import Layout
from fleetsim.planning.snapshot import FleetSnapshot

__all__ = ["NearestVehicleDispatcher"]

# Seconds within which two travel times count as equal (then the lower vehicle id wins): sums of the same
# lengths in another order may differ in their last bits.
TIE = 1e-6


class NearestVehicleDispatcher:
    """Nearest vehicle by travel time, as the thesis's scheduler picks it (§2.3).

    On every call, the orders no vehicle holds are taken most urgent first (higher priority, then older,
    then by id); each goes to the idle vehicle (``board.idle``, not given an order earlier in the same
    answer) of a type the order allows that reaches the order's first stop soonest
    (``fleetsim.dispatchers.travel.TravelTimes``: least time over the map from where the
    vehicle is committed to be); ties go to the lowest vehicle id. An order no idle vehicle can reach
    stays waiting. It never takes an order back, and answers ``[]`` when no idle vehicle gets an order.
    """

    def __init__(self) -> None:
        self.travel = TravelTimes()  # the map searches, kept for the run

    def dispatch(self, board: OrderBoard, fleet: FleetSnapshot, layout: Layout) -> list[Assignment]:
        free = list(board.idle)
        travel = self.travel
        starts = {v: travel.start(layout, fleet.vehicles[v], fleet.plans[v]) for v in free}
        answer: list[Assignment] = []
        for waiting in waiting_orders(board):
            if not free:
                break
            stop = next_stop(waiting)
            best: int | None = None
            best_time = math.inf
            for vehicle in free:
                if not may_carry(waiting.order, fleet.vehicles[vehicle].type):
                    continue
                time = travel.time_from(layout, starts[vehicle], stop)
                if time < best_time - TIE:
                    best, best_time = vehicle, time
            if best is not None:
                free.remove(best)
                answer.append(Assignment(best, (waiting.id,)))
        return sorted(answer, key=lambda assignment: assignment.vehicle_id)
