"""What a run with transport orders delivered (issue 45): throughput, service times, utilisation, backlog.

Every measure is taken over the *window*: from the end of the shift's warm-up (0 without one) to the
run's end. Definitions (docs/orders.md, "Measures", says the same):

* ``orders_per_hour``: orders completed in the window, per hour of the window; ``per_vehicle``: that
  over the number of vehicles.
* ``service_time``: completed − released, over the orders released in the window and completed;
  ``wait_for_vehicle``: first assigned − released, over those released in the window and assigned;
  ``wait_for_pickup``: first stop reached − released, likewise. Each as median, 95th percentile and
  maximum, in seconds; a percentile is the nearest rank (the ⌈p·n⌉-th smallest).
* ``deadline_misses``: orders whose deadline falls in the window and that were not completed by it.
* ``empty_travel_share``: of the distance the fleet drove in the window, the share driven while the
  vehicle held no started order (between an order's first stop reached and its last stop served it is
  loaded).
* ``utilisation``: the share of vehicle time in the window with work (a task or an order); of all
  vehicle time, ``idle`` (no work), ``dwelling`` (at a stop, from reaching it until its dwell ends) and
  ``blocked`` (standing still with work, not dwelling) shares. Each vehicle is counted as it is at the
  start of every step, for the step's length.
* ``stalls``: vehicles found with work and not moving for ``stall_after`` seconds (each stall once,
  over the whole run), and ``first_stall``: when the first was found.
* ``backlog``: open orders (released, not completed) at each full minute; ``backlog_slope``: its least
  squares slope over the window in orders per hour; the fleet is ``overloaded`` when the backlog grows:
  the slope exceeds 5 % of the window's arrival rate and the backlog at the end exceeds the one at the
  window's start by more than 5 orders (an overloaded fleet is said to be, not merely slow).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from fleetsim.dispatch.book import OrderRecord
from fleetsim.sim.lorr_counts import LorrCounts

__all__ = ["BACKLOG_EVERY", "OrderMeasures", "Stall", "Stats", "measure_orders", "measure_value"]

BACKLOG_EVERY = 60.0  # seconds between two backlog samples
_GROWTH_SHARE = 0.05  # of the arrival rate: a backlog slope above it grows
_GROWTH_ORDERS = 5  # and the backlog must have grown by more than this many orders


@dataclass(frozen=True, slots=True)
class Stall:
    """A vehicle of a shift that had work and did not move for ``stall_after`` seconds (not dwelling).

    Attributes:
        vehicle: The vehicle.
        since: Simulated seconds: when it last moved (0: it never did).
        time: Simulated seconds: when the stall was found (``since`` + ``stall_after``, on a whole second).
        orders: The orders it held then, in sequence: those held up with it.
        reason: Why it stands, as the stuck-fleet diagnosis words it (who it waits for, and why).
    """

    vehicle: int
    since: float
    time: float
    orders: tuple[str, ...]
    reason: str

    def message(self) -> str:
        held = f"; orders held up: {', '.join(self.orders)}" if self.orders else ""
        return (
            f"vehicle {self.vehicle} has work and has not moved for {self.time - self.since:.0f} s: {self.reason}{held}"
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "vehicle": self.vehicle,
            "since": round(self.since, 6),
            "time": round(self.time, 6),
            "orders": list(self.orders),
            "reason": self.reason,
        }


@dataclass(frozen=True, slots=True)
class Stats:
    """Median, 95th percentile (nearest rank) and maximum of some seconds, and how many there were."""

    count: int
    median: float
    p95: float
    max: float

    @classmethod
    def of(cls, values: Sequence[float]) -> Stats | None:
        if not values:
            return None
        ordered = sorted(values)
        n = len(ordered)
        median = ordered[n // 2] if n % 2 else 0.5 * (ordered[n // 2 - 1] + ordered[n // 2])
        return cls(n, median, ordered[max(0, math.ceil(0.95 * n) - 1)], ordered[-1])

    def to_dict(self) -> dict[str, Any]:
        return {
            "count": self.count,
            "median": round(self.median, 6),
            "p95": round(self.p95, 6),
            "max": round(self.max, 6),
        }


@dataclass(frozen=True, slots=True)
class OrderMeasures:
    """The measures of a run with transport orders (see the module's description for each definition)."""

    window: tuple[float, float]
    released: int
    completed: int
    orders_per_hour: float
    orders_per_vehicle_hour: float
    service_time: Stats | None
    wait_for_vehicle: Stats | None
    wait_for_pickup: Stats | None
    deadline_misses: int
    empty_travel_share: float | None
    utilisation: float
    idle_share: float
    dwelling_share: float
    blocked_share: float
    backlog: tuple[tuple[float, int], ...]
    backlog_slope: float
    overloaded: bool
    stalls: int = 0
    first_stall: float | None = None
    lorr: LorrCounts | None = None  # a League problem's run: the competition's counts (the result's ``lorr``)

    def value(self, measure: str) -> float | None:
        """One of ``fleetsim.orders.MEASURES`` (``service_time_p95``: that figure of the service times) as the
        result shows it (rounded as in ``to_dict``: what is judged is what is read), or ``None`` when the run
        has none (no order completed, say)."""
        return measure_value(self.to_dict(), measure)

    def to_dict(self) -> dict[str, Any]:
        def stats(value: Stats | None) -> dict[str, Any] | None:
            return None if value is None else value.to_dict()

        return {
            "window": [round(self.window[0], 6), round(self.window[1], 6)],
            "released": self.released,
            "completed": self.completed,
            "orders_per_hour": round(self.orders_per_hour, 4),
            "orders_per_vehicle_hour": round(self.orders_per_vehicle_hour, 4),
            "service_time": stats(self.service_time),
            "wait_for_vehicle": stats(self.wait_for_vehicle),
            "wait_for_pickup": stats(self.wait_for_pickup),
            "deadline_misses": self.deadline_misses,
            "empty_travel_share": None if self.empty_travel_share is None else round(self.empty_travel_share, 4),
            "utilisation": round(self.utilisation, 4),
            "idle_share": round(self.idle_share, 4),
            "dwelling_share": round(self.dwelling_share, 4),
            "blocked_share": round(self.blocked_share, 4),
            "backlog": [[round(t, 6), n] for t, n in self.backlog],
            "backlog_slope": round(self.backlog_slope, 4),
            "overloaded": self.overloaded,
            "stalls": self.stalls,
            "first_stall": None if self.first_stall is None else round(self.first_stall, 6),
        }


@dataclass(frozen=True, slots=True)
class FleetTimes:
    """Vehicle seconds and metres in the window, summed over the fleet."""

    vehicles: int
    idle: float  # seconds with no work
    dwelling: float  # seconds dwelling at a stop (braking to rest there included)
    blocked: float  # seconds standing still with work, not dwelling
    distance: float  # metres driven
    loaded_distance: float  # metres driven holding a started order


def measure_value(measures: Mapping[str, Any] | None, name: str) -> float | None:
    """``name`` (``service_time_p95``: that figure of the service times) from a result document's
    ``measures``; None for a run without orders (``measures`` None) or without the figure (no order
    completed, no distance driven)."""
    if measures is None:
        return None
    for prefix in ("service_time", "wait_for_vehicle", "wait_for_pickup"):
        if name.startswith(prefix + "_"):
            stats = measures.get(prefix)
            return None if stats is None else float(stats[name[len(prefix) + 1 :]])
    value = measures.get(name)
    return None if value is None else float(value)


def measure_orders(
    records: Mapping[str, OrderRecord],
    window: tuple[float, float],
    times: FleetTimes,
    backlog: Sequence[tuple[float, int]],
    stalls: Sequence[Stall] = (),
) -> OrderMeasures:
    """The measures of a run's orders over ``window`` (from the warm-up's end to the run's end)."""
    start, end = window
    hours = max(end - start, 1e-9) / 3600.0
    fresh = [r for r in records.values() if r.released >= start - 1e-9]
    done_in_window = [r for r in records.values() if r.completed is not None and r.completed >= start - 1e-9]
    per_hour = len(done_in_window) / hours
    vehicle_time = max(times.vehicles * (end - start), 1e-9)
    in_window = [(t, n) for t, n in backlog if t >= start - 1e-9]
    slope = _slope(in_window)
    arrivals = len(fresh) / hours
    grew = bool(in_window) and in_window[-1][1] - in_window[0][1] > _GROWTH_ORDERS
    return OrderMeasures(
        window=window,
        released=len(fresh),
        completed=len(done_in_window),
        orders_per_hour=per_hour,
        orders_per_vehicle_hour=per_hour / max(times.vehicles, 1),
        service_time=Stats.of([r.completed - r.released for r in fresh if r.completed is not None]),
        wait_for_vehicle=Stats.of([r.assigned - r.released for r in fresh if r.assigned is not None]),
        wait_for_pickup=Stats.of([r.started - r.released for r in fresh if r.started is not None]),
        deadline_misses=sum(1 for r in records.values() if _missed_in(r, start, end)),
        empty_travel_share=None
        if times.distance <= 0.0
        else max(times.distance - times.loaded_distance, 0.0) / times.distance,
        utilisation=1.0 - times.idle / vehicle_time,
        idle_share=times.idle / vehicle_time,
        dwelling_share=times.dwelling / vehicle_time,
        blocked_share=times.blocked / vehicle_time,
        backlog=tuple(backlog),
        backlog_slope=slope,
        overloaded=grew and slope > _GROWTH_SHARE * arrivals,
        stalls=len(stalls),
        first_stall=min((s.time for s in stalls), default=None),
    )


def _missed_in(record: OrderRecord, start: float, end: float) -> bool:
    deadline = record.order.deadline
    if deadline is None or not start - 1e-9 <= deadline <= end + 1e-9:
        return False
    return record.completed is None or record.completed > deadline + 1e-9


def _slope(points: Sequence[tuple[float, int]]) -> float:
    """Least squares slope of the backlog, in orders per hour (0 with fewer than two samples)."""
    if len(points) < 2:
        return 0.0
    n = len(points)
    mean_t = sum(t for t, _ in points) / n
    mean_b = sum(b for _, b in points) / n
    spread = sum((t - mean_t) ** 2 for t, _ in points)
    if spread <= 0.0:
        return 0.0
    return 3600.0 * sum((t - mean_t) * (b - mean_b) for t, b in points) / spread
