"""Orders and station sets checked against the scenario's map and fleet, when a scenario is loaded.

- The suite's own station sets name segments of the map; a stream draws its stops from sets the map or
  the suite defines (a :class:`~fleetsim.errors.SuiteError` at the set's item or at the ``from``).
- Every ``orders.csv`` order can be served: some vehicle of a type it allows can drive from its start
  through each of its stops in turn (an error at the order's row, with the reason the map gives).
- Lint: a station of a set a stream draws from that some vehicle the stream allows cannot reach from its
  start is a warning (``unreachable-station``) in the scenario's warnings: a stop drawn there waits for
  another vehicle, or for none.

"Reachable" is the static task check's (:mod:`.task_reach`): some route exists, whatever the planner.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path

from fleetsim.enums import Progress, TurnCapability
from fleetsim.errors import LoadError, Location, ScenarioFileError
from fleetsim.layout.layout import Layout
from fleetsim.layout.reachability import ReachIndex, State, arrivals, goal_states, reach
from fleetsim.layout.segment_ids import not_in_map
from fleetsim.layout.unreachable import why_unreachable
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.stations import merge_station_sets
from fleetsim.load.suites.orders_entry import OrderSetup
from fleetsim.load.suites.schema import raise_suite_errors
from fleetsim.orders import Order, OrderStream, Station
from fleetsim.scenario import Scenario, Vehicle

__all__ = ["REACH_WARNING", "apply_order_setup", "order_reach_errors", "station_reach_warnings"]

REACH_WARNING = "unreachable-station"


def apply_order_setup(scenario: Scenario, setup: OrderSetup) -> Scenario:
    """``scenario`` (its map's station sets loaded) with the suite entry's stations, stream, shift and
    dispatcher; every set and ``from`` the map contradicts is raised (several as one SuiteErrors)."""
    if setup.order_stream is None and not setup.stations and setup.shift is None and setup.dispatcher is None:
        return scenario
    segments = scenario.layout.segments
    errors = ErrorCollector()
    for name, places in setup.station_items.items():
        for segment, place in places.items():
            if segment not in segments:
                errors.add(place.error(f"station set {name!r}: {not_in_map(segment, segments)}"))
    stations = merge_station_sets(scenario.stations, setup.stations)
    stream = setup.order_stream
    for draw, place in zip(stream.stops if stream is not None else (), setup.stream_from, strict=True):
        for name in draw.stations:
            if name not in stations:
                errors.add(place.error(_unknown_set(name, stations)))
    raise_suite_errors(errors)
    warnings = scenario.warnings
    if stream is not None:
        where = [place.location for place in setup.stream_from]
        warnings += station_reach_warnings(scenario.layout, scenario.vehicles, stream, stations, where)
    return replace(
        scenario,
        stations=stations,
        order_stream=stream,
        shift=setup.shift,
        dispatcher=setup.dispatcher,
        warnings=warnings,
    )


def _unknown_set(name: str, stations: Mapping[str, object]) -> str:
    if not stations:
        return f"station set {name!r} is not defined: neither the map nor the suite's 'stations' define any set"
    listed = ", ".join(stations)
    return f"station set {name!r} is defined neither by the map nor by the suite's 'stations' (sets: {listed}){did_you_mean(name, stations)}"


class _Reach:
    """Where vehicles of one turn capability may be after each stop (memoised: orders repeat places)."""

    def __init__(self, layout: Layout) -> None:
        self.layout = layout
        self._indexes: dict[TurnCapability, ReachIndex] = {}
        self._memo: dict[tuple[TurnCapability, frozenset[State], int, Progress | None], frozenset[State]] = {}

    def arrived(
        self, capability: TurnCapability, starts: frozenset[State], goal: int, progress: Progress | None
    ) -> frozenset[State]:
        key = (capability, starts, goal, progress)
        found = self._memo.get(key)
        if found is None:
            index = self._indexes.get(capability)
            if index is None:
                index = self._indexes[capability] = ReachIndex(self.layout, capability)
            entered = index.entered(starts, goal_states(self.layout, goal))
            found = self._memo[key] = arrivals(starts, entered, goal, progress)
        return found


def _starts(vehicles: Iterable[Vehicle]) -> dict[TurnCapability, frozenset[State]]:
    """The start states of ``vehicles``, by turn capability (capabilities in a fixed order)."""
    found: dict[TurnCapability, set[State]] = {}
    for vehicle in vehicles:
        found.setdefault(vehicle.type.turn_capability, set()).add(
            (vehicle.start_segment, vehicle.traverse, vehicle.progress)
        )
    return {capability: frozenset(found[capability]) for capability in TurnCapability if capability in found}


def order_reach_errors(
    layout: Layout, vehicles: Sequence[Vehicle], orders: Iterable[Order], orders_path: Path
) -> list[LoadError]:
    """An error at its row for each order no vehicle it allows can serve (stop after stop, from its start)."""
    reacher = _Reach(layout)
    errors: list[LoadError] = []
    # The start states of each set of vehicles orders allow, made once: the same frozensets each time are
    # hashed once and found in the memo by identity (a League problem has thousands of orders for one fleet).
    starts_of: dict[tuple[str, ...] | None, dict[TurnCapability, frozenset[State]]] = {}
    for order in orders:
        allowed = [v for v in vehicles if order.vehicle_types is None or v.type.name in order.vehicle_types]
        where = Location(orders_path, line=order.line, field="stops")
        if not allowed:
            types = ", ".join(sorted({v.type.name for v in vehicles})) or "none: the scenario has no vehicles"
            msg = f"order {order.id!r}: no vehicle is of a type it allows ({', '.join(order.vehicle_types or ())}; the vehicles' types: {types})"
            errors.append(ScenarioFileError(msg, where))
            continue
        starts = starts_of.get(order.vehicle_types)
        if starts is None:
            starts = starts_of[order.vehicle_types] = _starts(allowed)
        problem = _unserved(layout, reacher, order, allowed, starts)
        if problem is not None:
            errors.append(ScenarioFileError(problem, where))
    return errors


def _unserved(
    layout: Layout,
    reacher: _Reach,
    order: Order,
    allowed: list[Vehicle],
    start_states: Mapping[TurnCapability, frozenset[State]],
) -> str | None:
    """Why no vehicle of ``allowed`` (whose start states by capability are ``start_states``) can serve
    ``order``, or ``None`` when one can."""
    furthest: tuple[int, TurnCapability, frozenset[State]] | None = None  # the stop a group fails at
    for capability, starts in start_states.items():
        here = starts
        for number, stop in enumerate(order.stops):
            arrived = reacher.arrived(capability, here, stop.segment, stop.progress)
            if not arrived:
                if furthest is None or number > furthest[0]:
                    furthest = (number, capability, here)
                break
            here = arrived
        else:
            return None
    assert furthest is not None
    number, capability, here = furthest
    stop = order.stops[number]
    type_name = next(v.type.name for v in allowed if v.type.turn_capability is capability)
    reason = why_unreachable(layout, reach(layout, capability, here), stop.segment, stop.progress, type_name)
    ids = ", ".join(str(v.id) for v in allowed)
    arriving = f" arriving {stop.progress.value}" if stop.progress is not None else ""
    origin = (
        "from their starts" if number == 0 else f"from its stop {number} (segment {order.stops[number - 1].segment})"
    )
    return (
        f"order {order.id!r}: no vehicle it may go to ({ids}) can reach segment {stop.segment}{arriving}, "
        f"its stop {number + 1}, {origin}: {reason}"
    )


def station_reach_warnings(
    layout: Layout,
    vehicles: Sequence[Vehicle],
    stream: OrderStream,
    stations: Mapping[str, tuple[Station, ...]],
    where: Sequence[Location],
) -> tuple[str, ...]:
    """A warning per station of a set ``stream`` draws from that some vehicle it allows cannot reach from
    its start; ``where`` locates each stop draw's ``from``."""
    allowed = [v for v in vehicles if stream.vehicle_types is None or v.type.name in stream.vehicle_types]
    reacher = _Reach(layout)
    warnings: list[str] = []
    checked: set[tuple[str, Progress | None]] = set()
    for draw, location in zip(stream.stops, where, strict=True):
        for name in draw.stations:
            if (name, draw.progress) in checked:
                continue
            checked.add((name, draw.progress))
            for station in stations.get(name, ()):
                missed = [
                    vehicle.id
                    for vehicle in allowed
                    if not reacher.arrived(
                        vehicle.type.turn_capability,
                        frozenset({(vehicle.start_segment, vehicle.traverse, vehicle.progress)}),
                        station.segment,
                        draw.progress,
                    )
                ]
                if missed:
                    warnings.append(_station_warning(location, name, station, draw.progress, missed, len(allowed)))
    return tuple(warnings)


def _station_warning(
    location: Location, name: str, station: Station, progress: Progress | None, missed: list[int], allowed: int
) -> str:
    arriving = f" arriving {progress.value}" if progress is not None else ""
    who = ", ".join(map(str, missed))
    if len(missed) == allowed:
        tail = "no vehicle the stream allows can serve a stop there"
    else:
        tail = "a stop drawn there waits for another vehicle"
    return (
        f"{location}: warning {REACH_WARNING}: station set {name!r}: segment {station.segment}{arriving} "
        f"cannot be reached by vehicle{'s' if len(missed) > 1 else ''} {who} from "
        f"{'their starts' if len(missed) > 1 else 'its start'}; {tail}"
    )
