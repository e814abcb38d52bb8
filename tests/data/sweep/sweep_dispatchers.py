"""Dispatchers for the sweep tests; workers import this module through PYTHONPATH."""

from __future__ import annotations

from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.dispatchers import NearestVehicleDispatcher
from fleetsim.layout.layout import Layout
from fleetsim.planning.snapshot import FleetSnapshot


class EveryOtherCall(NearestVehicleDispatcher):
    """The nearest-vehicle dispatcher that answers only every other call (``[]`` in between): an idle
    vehicle may stand until the next release or the next vehicle running out of work. Worse on purpose."""

    def __init__(self) -> None:
        super().__init__()
        self.calls = 0

    def dispatch(self, board: OrderBoard, fleet: FleetSnapshot, layout: Layout) -> list[Assignment]:
        self.calls += 1
        return super().dispatch(board, fleet, layout) if self.calls % 2 else []


class HighestIdleOnly:
    """Gives one order per call, the oldest waiting one, to the idle vehicle with the highest id, however
    far it is; the other idle vehicles wait for the next call. Worse on purpose."""

    def dispatch(self, board: OrderBoard, fleet: FleetSnapshot, layout: Layout) -> list[Assignment]:
        waiting = board.unassigned()
        if not waiting or not board.idle:
            return []
        return [Assignment(board.idle[-1], (waiting[0].id,))]
