"""Transport orders and shifts: the work a fleet is given over hours, not as fixed trips (issue 45).

An *order* is an ordered list of *stops* (places to reach, each with a dwell time: loading, unloading),
released at a moment (nobody sees it before), perhaps with a deadline for its last stop, vehicle types
allowed to carry it and a priority. Orders come from ``orders.csv`` or from an *order stream* a suite
entry describes (an arrival process and where stops are drawn from, seeded). A *dispatcher* assigns
released orders to vehicles (``fleetsim.dispatch``); each assigned stop becomes a task in the vehicle's
queue, so route planners keep the protocol they have.

These are plain, immutable data: loading makes them, the simulation reads them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from fleetsim.enums import Progress

__all__ = [
    "MEASURES",
    "Arrivals",
    "LorrSetup",
    "MeasureBound",
    "Order",
    "OrderStream",
    "Shift",
    "Station",
    "Stop",
    "StopDraw",
]


@dataclass(frozen=True, slots=True)
class Stop:
    """A place an order's vehicle must reach, and stand at.

    Attributes:
        segment: The segment to reach (its task is done when the vehicle enters a leg on it that its plan
            marks as the task's goal, as for any task).
        progress: ``FORWARD`` or ``REVERSE`` if the vehicle must arrive that way, ``None`` if either will do.
        dwell: Seconds the vehicle stands there once at rest (loading, unloading); 0: none.
    """

    segment: int
    progress: Progress | None = None
    dwell: float = 0.0


@dataclass(frozen=True, slots=True)
class Station:
    """A segment of a named station set (``pick``, ``drop``, ``park``, ...), where stops are drawn from.

    Maps name them: a Tiled segment's custom property ``station`` (set names, comma-separated) with an
    optional ``station_weight``; a LIF station's interaction nodes; an Open-RMF vertex's
    ``pickup_dispenser`` (set ``pick``) or ``dropoff_ingestor`` (set ``drop``); suites may add sets of
    their own (``stations:``).

    Attributes:
        segment: The segment a vehicle stops on.
        weight: Its relative weight when stops are drawn by weight (1 by default).
        name: The station's own name where the map gives one (a LIF station's id), for messages.
    """

    segment: int
    weight: float = 1.0
    name: str = ""


@dataclass(frozen=True, slots=True)
class Order:
    """A transport order: stops in order, visible from ``release`` on.

    Attributes:
        id: The order's id (``orders.csv``'s ``order_id``; generated orders are ``s1``, ``s2``, ...),
            unique in the scenario.
        stops: Its stops, in the order they must be served (at least one).
        release: Seconds of simulated time from which the order exists for the dispatcher (and anyone).
        deadline: Seconds of simulated time by which its last stop must be served, or ``None``.
        vehicle_types: The names of the vehicle types allowed to carry it, or ``None`` for any.
        priority: Higher is more urgent; what it means is the dispatcher's business (reference dispatchers
            take higher priorities first).
        line: The ``orders.csv`` line it was read from, for messages (``None`` when generated or made in code).
    """

    id: str
    stops: tuple[Stop, ...]
    release: float = 0.0
    deadline: float | None = None
    vehicle_types: tuple[str, ...] | None = None
    priority: int = 0
    line: int | None = field(default=None, compare=False)


@dataclass(frozen=True, slots=True)
class Arrivals:
    """When a stream's orders are released.

    Attributes:
        process: ``"poisson"`` (exponential gaps at ``rate`` orders per hour), ``"interval"`` (one every
            ``interval`` seconds) or ``"pool"`` (a closed pool: ``open`` orders are kept open, a new one
            released as one is completed, as the League of Robot Runners does).
        rate: Orders per hour (``poisson``).
        interval: Seconds between releases (``interval``).
        open: How many orders are open at once (``pool``).
        start: Seconds: the first release (``poisson``: the first gap counts from here).
        until: Seconds: no release after this (``None``: until the run ends).
    """

    process: Literal["poisson", "interval", "pool"]
    rate: float | None = None
    interval: float | None = None
    open: int | None = None
    start: float = 0.0
    until: float | None = None


@dataclass(frozen=True, slots=True)
class StopDraw:
    """How one stop of each generated order is drawn.

    Attributes:
        stations: The names of the station sets its segment is drawn from (their union, each segment once).
        weighted: Whether stations are drawn by their weights (else uniformly).
        dwell: Seconds standing there: fixed (``lo == hi``) or drawn uniformly from ``[lo, hi]``.
        count: How many such stops follow one another: fixed or drawn uniformly from ``[lo, hi]``.
        progress: The arrival direction required, or ``None``.
    """

    stations: tuple[str, ...]
    weighted: bool = False
    dwell: tuple[float, float] = (0.0, 0.0)
    count: tuple[int, int] = (1, 1)
    progress: Progress | None = None


@dataclass(frozen=True, slots=True)
class OrderStream:
    """Orders generated, seeded and deterministic, from a suite entry's ``orders:`` block.

    Attributes:
        seed: The random seed: the same seed gives the same orders, on any machine.
        arrivals: When orders are released.
        stops: How each order's stops are drawn, in order.
        deadline: Seconds after its release by which each order's last stop must be served, or ``None``.
        vehicle_types: The vehicle types allowed to carry them, or ``None`` for any.
        priority: Their priority.
        limit: At most this many orders (``None``: as many as the arrivals give until the run ends).
    """

    seed: int
    arrivals: Arrivals
    stops: tuple[StopDraw, ...]
    deadline: float | None = None
    vehicle_types: tuple[str, ...] | None = None
    priority: int = 0
    limit: int | None = None


@dataclass(frozen=True, slots=True)
class Shift:
    """A run as a shift: how long it lasts and how it is measured (a suite entry's ``shift:``).

    Attributes:
        duration: Seconds: reaching it is the normal end of the run (not a timeout).
        warmup: Seconds at the start left out of the measures.
        dispatch_period: Seconds between calls of the dispatcher besides those on a release and on a
            vehicle running out of work (``None``: no periodic call).
        stall_after: Seconds a vehicle with work may stand without moving before it is a stall.
        on_stall: ``"count"`` (the run goes on; stalls are measured) or ``"end"`` (the first ends the run).
    """

    duration: float
    warmup: float = 0.0
    dispatch_period: float | None = None
    stall_after: float = 300.0
    on_stall: Literal["count", "end"] = "count"


@dataclass(frozen=True, slots=True)
class LorrSetup:
    """The League of Robot Runners problem a scenario was loaded from (``fleetsim.load.lorr``): a run of
    it also gives the competition's own counts (the result's ``lorr``).

    Attributes:
        problem: The problem file's name.
        edition: ``"2023"``, ``"2024"`` or ``"2026"``.
        team_size: How many robots run (``teamSize``, or the suite entry's ``agents``).
        task_pool: How many tasks are kept revealed (``numTasksReveal × teamSize``, at least 1).
        horizon: Timesteps the run lasts (its shift's duration, at ``timestep`` seconds each).
        timestep: Seconds per League timestep (1: one cell per second).
        not_mapped: What of the problem fleetsim has no counterpart for, or maps with a difference, in words.
    """

    problem: str
    edition: str
    team_size: int
    task_pool: int
    horizon: int
    timestep: float = 1.0
    not_mapped: tuple[str, ...] = ()


# The measures of a run with orders that a suite's ``expect`` may bound (``min_<name>``, ``max_<name>``):
# fleetsim.sim.measures defines each; a ``_median``/``_p95``/``_max`` name is that figure of its times.
MEASURES = (
    "orders_per_hour",
    "orders_per_vehicle_hour",
    "completed",
    "service_time_median",
    "service_time_p95",
    "service_time_max",
    "wait_for_vehicle_median",
    "wait_for_vehicle_p95",
    "wait_for_vehicle_max",
    "wait_for_pickup_median",
    "wait_for_pickup_p95",
    "wait_for_pickup_max",
    "deadline_misses",
    "empty_travel_share",
    "utilisation",
    "idle_share",
    "dwelling_share",
    "blocked_share",
    "backlog_slope",
    "stalls",
)


@dataclass(frozen=True, slots=True)
class MeasureBound:
    """An expectation on a measure of a run with orders (``expect: {min_orders_per_hour: 40}``).

    Attributes:
        measure: One of ``MEASURES``.
        bound: ``"min"`` (the measure must be at least ``value``) or ``"max"`` (at most).
        value: The bound, in the measure's unit (orders per hour, seconds, a share from 0 to 1, a count).
    """

    measure: str
    bound: Literal["min", "max"]
    value: float

    @property
    def key(self) -> str:
        """Its key in a suite's ``expect``: ``min_orders_per_hour``."""
        return f"{self.bound}_{self.measure}"
