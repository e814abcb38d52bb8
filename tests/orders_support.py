"""Short runs with transport orders for the tests of what pictures, recordings and the viewer show of them:
ten minutes of the shipped warehouse's shift, and a loop whose vehicle 2 stalls with an order."""

from __future__ import annotations

import dataclasses
from functools import cache

from unit.dispatch_support import FirstIdle, scenario

from fleetsim import load_scenario, load_suite
from fleetsim.dispatchers import NearestVehicleDispatcher
from fleetsim.orders import Order, Shift, Stop
from fleetsim.planners import ReservingPlanner
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult

WAREHOUSE = "scenario_suites/warehouse.fleetsim.yaml"


@cache
def warehouse_run(duration: float = 600.0) -> tuple[Scenario, RunResult]:
    """The shipped ``shift`` (a Poisson stream, nearest-vehicle dispatch), its shift cut to ``duration``."""
    suite = load_suite(WAREHOUSE)
    loaded = load_scenario(next(s for s in suite.scenarios if s.name == "shift"), suite)
    assert loaded.shift is not None
    shift = dataclasses.replace(loaded, shift=dataclasses.replace(loaded.shift, duration=duration, warmup=0.0))
    return shift, run_scenario(shift, ReservingPlanner(), dispatcher=NearestVehicleDispatcher())


class _LeavesVehicle2(ReservingPlanner):
    """Routes every vehicle but 2, which is left standing with its order."""

    def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
        return [] if task.vehicle_id == 2 else super().plan_routes(task, fleet, layout)


STALL_ORDERS = (
    Order("a", (Stop(7, dwell=3.0), Stop(2, dwell=2.0))),
    Order("b", (Stop(2), Stop(7))),
    Order("c", (Stop(4),), release=5.0),
)


@cache
def stall_run(on_stall: str = "end") -> tuple[Scenario, RunResult]:
    """The shipped one-way loop with three orders; vehicle 2 holds order b and is never routed: it stalls
    at 16.1 s (``stall_after`` 10 s), which ends the shift (``on_stall: end``) or is counted."""
    loop = dataclasses.replace(
        scenario(STALL_ORDERS),
        shift=Shift(duration=40.0, stall_after=10.0, on_stall=on_stall),  # type: ignore[arg-type]
    )
    return loop, run_scenario(loop, _LeavesVehicle2(), dispatcher=FirstIdle())


__all__ = ["STALL_ORDERS", "stall_run", "warehouse_run"]
