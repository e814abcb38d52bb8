"""The measures of runs with transport orders that baselines and sweeps gate on, and how to read them.

A team that gates a fleet's software on its shifts compares these (``fleetsim.sim.measures`` defines
each): orders completed per hour, the median and 95th percentile of the service time, the 95th percentile
of the wait for pick-up, deadline misses, vehicle utilisation, the empty-travel share and stalls. Each is
read from a run's ``measures`` as its result document shows it (``schemas/result.schema.json``), so a run,
a ``result.json`` and a sweep's row give the same figure; a run without orders has none of them (None).

Which way is better: more orders per hour and a higher utilisation (the share of vehicle time with work:
a fleet standing idle while orders wait is wasted, as fleet operators count it); less of every time,
miss, stall and empty travel. Utilisation alone can mislead — vehicles that drive detours for the same
work are busier, not better — so gate it beside throughput and empty travel, never alone.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from fleetsim.sim.measures import measure_value

__all__ = ["GATED_MEASURES", "GatedMeasure", "measure_value"]


@dataclass(frozen=True, slots=True)
class GatedMeasure:
    """A measure to gate on: its name (one of ``fleetsim.orders.MEASURES``), words, unit and direction.

    Attributes:
        name: The measure, as ``expect`` bounds and result documents name it.
        label: Its name in words, for tables.
        unit: Its unit as documents hold it (``share``: a fraction from 0 to 1).
        better: ``"higher"`` or ``"lower"``.
        whole: Whether it counts things (deadline misses, stalls): an integer.
    """

    name: str
    label: str
    unit: str
    better: Literal["lower", "higher"]
    whole: bool = False


GATED_MEASURES: tuple[GatedMeasure, ...] = (
    GatedMeasure("orders_per_hour", "orders per hour", "orders/h", "higher"),
    GatedMeasure("service_time_median", "service time median", "s", "lower"),
    GatedMeasure("service_time_p95", "service time p95", "s", "lower"),
    GatedMeasure("wait_for_pickup_p95", "wait for pick-up p95", "s", "lower"),
    GatedMeasure("deadline_misses", "deadline misses", "", "lower", whole=True),
    GatedMeasure("utilisation", "utilisation", "share", "higher"),
    GatedMeasure("empty_travel_share", "empty travel", "share", "lower"),
    GatedMeasure("stalls", "stalls", "", "lower", whole=True),
)
