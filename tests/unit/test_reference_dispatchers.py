"""The reference dispatchers (issue 45): nearest vehicle by travel time over the map, and oldest order first.

Boards are made by hand (the open orders, who holds them, who is idle); fleets are the scenario's at its
start, as ``FleetController(scenario).snapshot(0.0)`` shows them to a planner.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import replace
from pathlib import Path

import pytest
from scenario_factory import AGV, TUGGER, make_scenario

from fleetsim.dispatch.protocol import Assignment, OpenOrder, OrderBoard
from fleetsim.dispatchers import NearestVehicleDispatcher, OldestFirstDispatcher
from fleetsim.dispatchers.travel import TravelTimes
from fleetsim.enums import Direction, Progress, Shape
from fleetsim.layout import Segment
from fleetsim.orders import Order, Stop
from fleetsim.planning import FleetController
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Scenario

Dispatcher = NearestVehicleDispatcher | OldestFirstDispatcher


def straight(
    sid: int, a: tuple[float, float], b: tuple[float, float], direction: Direction = Direction.BOTH
) -> Segment:
    return Segment(sid, Shape.STRAIGHT, direction, (a, b))


def line(n: int, length: float = 10.0) -> tuple[Segment, ...]:
    """``n`` straights in a row along x, ``length`` metres each, segment ``i`` from x = (i-1)·length."""
    return tuple(straight(i, (length * (i - 1), 0.0), (length * i, 0.0)) for i in range(1, n + 1))


def fleet_of(scenario: Scenario) -> FleetSnapshot:
    return FleetController(scenario).snapshot(0.0)


def board(orders: Iterable[Order], idle: Iterable[int], held: dict[str, int] | None = None) -> OrderBoard:
    held = held or {}
    opens = {o.id: OpenOrder(o, held.get(o.id), False, 0, o.release) for o in orders}
    sequences: dict[int, tuple[str, ...]] = {}
    for order_id, vehicle in held.items():
        sequences[vehicle] = (*sequences.get(vehicle, ()), order_id)
    return OrderBoard(0.0, ("release",), opens, dict(sorted(sequences.items())), tuple(sorted(idle)))


def order(order_id: str, segment: int, release: float = 0.0, **fields: object) -> Order:
    return Order(order_id, (Stop(segment), Stop(1)), release, **fields)  # type: ignore[arg-type]


def answer(dispatcher: Dispatcher, scenario: Scenario, open_board: OrderBoard) -> list[tuple[int, tuple[str, ...]]]:
    found = dispatcher.dispatch(open_board, fleet_of(scenario), scenario.layout)
    assert all(isinstance(a, Assignment) for a in found)
    return [(a.vehicle_id, a.orders) for a in found]


@pytest.fixture
def row(tmp_path: Path) -> Scenario:
    """Six 10 m straights: vehicle 1 (agv) on 1 driving +x, vehicle 2 (agv) on 5 driving -x, vehicle 3
    (tugger) on 6 driving -x."""
    vehicles = "1,1,forward,,agv\n2,5,backward,,agv\n3,6,backward,,tugger\n"
    return make_scenario(tmp_path, line(6), vehicles, allow_start_conflicts=True)


# -- nearest vehicle -----------------------------------------------------------------------------------


def test_nearest_gives_the_order_to_the_vehicle_that_reaches_its_first_stop_soonest(row: Scenario) -> None:
    # Vehicle 1 reaches segment 2 after 10 m, vehicle 2 after 30 m (5, 4, 3 backwards).
    assert answer(NearestVehicleDispatcher(), row, board([order("o1", 2)], idle=[1, 2])) == [(1, ("o1",))]
    assert answer(NearestVehicleDispatcher(), row, board([order("o1", 4)], idle=[1, 2])) == [(2, ("o1",))]


def test_nearest_breaks_a_tie_by_the_lowest_vehicle_id(row: Scenario) -> None:
    # Segment 3: vehicle 1 drives 1 and 2 (20 m), vehicle 2 drives 5 and 4 (20 m).
    travel = TravelTimes()
    fleet = fleet_of(row)
    stop = Stop(3)
    times = [travel.time(row.layout, fleet.vehicles[v], fleet.plans[v], stop) for v in (1, 2)]
    assert times == [20.0, 20.0]
    assert answer(NearestVehicleDispatcher(), row, board([order("o1", 3)], idle=[2, 1])) == [(1, ("o1",))]


def test_nearest_takes_priority_then_age_then_id_and_gives_each_idle_vehicle_one_order(row: Scenario) -> None:
    orders = [order("o2", 2, 5.0), order("o10", 4, 1.0), order("o9", 4, 1.0), order("urgent", 4, 9.0, priority=1)]
    # urgent first (to 2, nearer to 4), then o9 before o10 (same release, natural id order) to vehicle 1.
    assert answer(NearestVehicleDispatcher(), row, board(orders, idle=[1, 2])) == [(1, ("o9",)), (2, ("urgent",))]


def test_nearest_never_assigns_to_a_vehicle_that_is_not_idle(row: Scenario) -> None:
    assert answer(NearestVehicleDispatcher(), row, board([order("o1", 2)], idle=[2])) == [(2, ("o1",))]
    assert answer(NearestVehicleDispatcher(), row, board([order("o1", 2)], idle=[])) == []


def test_nearest_leaves_held_orders_alone_and_answers_nothing_when_nothing_waits(row: Scenario) -> None:
    held = board([order("o1", 2), order("o2", 3)], idle=[2], held={"o1": 1, "o2": 3})
    assert answer(NearestVehicleDispatcher(), row, held) == []


def test_nearest_respects_the_vehicle_types_an_order_allows(row: Scenario) -> None:
    tuggers_only = order("o1", 2, vehicle_types=("tugger",))
    assert answer(NearestVehicleDispatcher(), row, board([tuggers_only], idle=[1, 2, 3])) == [(3, ("o1",))]
    nobody = order("o2", 2, vehicle_types=("forklift",))
    assert answer(NearestVehicleDispatcher(), row, board([nobody], idle=[1, 2, 3])) == []


def _square(
    tmp_path: Path, stop_direction: Direction, vehicles: str = "1,3,backward,,agv\n2,5,forward,,agv\n"
) -> Scenario:
    """A rectangle: bottom A (0,0)-(10,0), G (10,0)-(20,0), B (20,0)-(30,0); C up the right side, D back
    along the top, E down the left. Vehicle 1 on B driving -x (towards G), vehicle 2 at the right end of D
    driving -x along the top."""
    segments = (
        straight(1, (0.0, 0.0), (10.0, 0.0)),  # A
        straight(2, (10.0, 0.0), (20.0, 0.0), stop_direction),  # G: the stop
        straight(3, (20.0, 0.0), (30.0, 0.0)),  # B
        straight(4, (30.0, 0.0), (30.0, 10.0)),  # C
        straight(5, (30.0, 10.0), (0.0, 10.0)),  # D
        straight(6, (0.0, 10.0), (0.0, 0.0)),  # E
    )
    return make_scenario(tmp_path, segments, vehicles)


def test_nearest_counts_the_way_round_a_one_way_segment(tmp_path: Path) -> None:
    both = _square(tmp_path / "both", Direction.BOTH)
    assert answer(NearestVehicleDispatcher(), both, board([order("o1", 2)], idle=[1, 2])) == [(1, ("o1",))]
    # G only +x: vehicle 1 must turn back and drive round (B, C, D, E, A: 80 m), vehicle 2 has 50 m.
    one_way = _square(tmp_path / "one-way", Direction.FORWARD)
    travel = TravelTimes()
    fleet = fleet_of(one_way)
    times = {v: travel.time(one_way.layout, fleet.vehicles[v], fleet.plans[v], Stop(2)) for v in (1, 2)}
    # Metres at 1 m/s, and in-place turns at 90 deg/s: 180 deg at B's end, then four corners (vehicle 1)
    # or two (vehicle 2) of 90 deg.
    assert times == {1: pytest.approx(80.0 + 2.0 + 4.0), 2: pytest.approx(50.0 + 2.0)}
    assert answer(NearestVehicleDispatcher(), one_way, board([order("o1", 2)], idle=[1, 2])) == [(2, ("o1",))]


def test_a_curve_vehicle_takes_no_corner_on_its_way(tmp_path: Path) -> None:
    # The tugger on B can only reach the one-way G round the rectangle's corners: it cannot.
    vehicles = "1,3,backward,,tugger\n2,5,forward,,agv\n"
    one_way = _square(tmp_path / "one-way", Direction.FORWARD, vehicles)
    fleet = fleet_of(one_way)
    assert TravelTimes().time(one_way.layout, fleet.vehicles[1], fleet.plans[1], Stop(2)) == math.inf
    assert answer(NearestVehicleDispatcher(), one_way, board([order("o1", 2)], idle=[1])) == []
    # Straight on, through a two-way G, it reaches A.
    both = _square(tmp_path / "both", Direction.BOTH, vehicles)
    fleet = fleet_of(both)
    assert TravelTimes().time(both.layout, fleet.vehicles[1], fleet.plans[1], Stop(1)) == 20.0


def test_a_curve_vehicle_that_must_arrive_backing_drives_through_and_backs_in(row: Scenario) -> None:
    travel = TravelTimes()
    fleet = fleet_of(row)
    tugger, agv = fleet.vehicles[3], fleet.vehicles[2]
    # The tugger on 6 driving -x nose first enters segment 4 after 20 m, nose first. Backing, it enters 4
    # only after driving all of 4 and reversing at its end (a cusp): 30 m.
    assert travel.time(row.layout, tugger, fleet.plans[3], Stop(4)) == 20.0
    assert travel.time(row.layout, tugger, fleet.plans[3], Stop(4, Progress.REVERSE)) == 30.0
    assert travel.time(row.layout, tugger, fleet.plans[3], Stop(4, Progress.FORWARD)) == 20.0
    # A vehicle that turns in place arrives backing just as soon.
    assert travel.time(row.layout, agv, fleet.plans[2], Stop(3, Progress.REVERSE)) == 20.0


def test_a_vehicle_on_the_stop_is_there_unless_it_must_arrive_the_other_way(row: Scenario) -> None:
    travel = TravelTimes()
    fleet = fleet_of(row)
    assert travel.time(row.layout, fleet.vehicles[1], fleet.plans[1], Stop(1)) == 0.0
    assert travel.time(row.layout, fleet.vehicles[1], fleet.plans[1], Stop(1, Progress.REVERSE)) > 0.0


def test_travel_counts_the_rest_of_the_leg_and_the_fixed_legs_ahead(row: Scenario) -> None:
    travel = TravelTimes()
    fleet = fleet_of(row)
    moved = fleet.vehicles[1]._replace(distance=4.0)
    plan = fleet.plans[1]
    assert travel.time(row.layout, moved, plan, Stop(3)) == 16.0
    ahead = replace(plan, legs=(*plan.legs, replace(plan.legs[0], segment=2)))
    assert travel.time(row.layout, moved, ahead, Stop(2)) == 6.0  # it enters 2 at the end of its leg
    assert travel.time(row.layout, moved, ahead, Stop(4)) == 26.0


@pytest.fixture
def dead_end(tmp_path: Path) -> Scenario:
    """Two one-way straights, +x: vehicle 1 at the start of the first, vehicle 2 on the second (which ends
    nowhere): nothing behind vehicle 2 is reachable for it."""
    segments = (
        straight(1, (0.0, 0.0), (10.0, 0.0), Direction.FORWARD),
        straight(2, (10.0, 0.0), (20.0, 0.0), Direction.FORWARD),
        straight(3, (-10.0, 0.0), (0.0, 0.0), Direction.FORWARD),
    )
    return make_scenario(tmp_path, segments, "1,3,forward,,agv\n2,2,forward,,agv\n", allow_start_conflicts=True)


@pytest.mark.parametrize("dispatcher", [NearestVehicleDispatcher, OldestFirstDispatcher])
def test_an_order_no_idle_vehicle_can_reach_stays_unassigned(dead_end: Scenario, dispatcher: type[Dispatcher]) -> None:
    assert answer(dispatcher(), dead_end, board([order("o1", 1)], idle=[2])) == []
    assert answer(dispatcher(), dead_end, board([order("o1", 1)], idle=[1, 2])) == [(1, ("o1",))]


# -- oldest first --------------------------------------------------------------------------------------


def test_oldest_first_gives_the_oldest_order_to_the_lowest_idle_id_whatever_the_distance(row: Scenario) -> None:
    # o1 (older) lies next to vehicle 2, o2 next to vehicle 1: age wins over distance.
    orders = [order("o2", 2, 3.0), order("o1", 4, 1.0)]
    assert answer(OldestFirstDispatcher(), row, board(orders, idle=[1, 2])) == [(1, ("o1",)), (2, ("o2",))]
    assert answer(NearestVehicleDispatcher(), row, board(orders, idle=[1, 2])) == [(1, ("o2",)), (2, ("o1",))]


def test_oldest_first_takes_priority_first_and_skips_what_a_vehicle_may_not_carry(row: Scenario) -> None:
    orders = [
        order("old", 2, 0.0, vehicle_types=("tugger",)),
        order("young", 3, 9.0),
        order("urgent", 4, 20.0, priority=3),
    ]
    assert answer(OldestFirstDispatcher(), row, board(orders, idle=[1, 2, 3])) == [
        (1, ("urgent",)),
        (2, ("young",)),
        (3, ("old",)),
    ]


def test_oldest_first_passes_over_an_order_the_vehicle_cannot_reach(dead_end: Scenario) -> None:
    orders = [order("o1", 1, 0.0), order("o2", 2, 1.0)]
    assert answer(OldestFirstDispatcher(), dead_end, board(orders, idle=[2])) == [(2, ("o2",))]


def test_oldest_first_never_assigns_to_a_vehicle_that_is_not_idle(row: Scenario) -> None:
    assert answer(OldestFirstDispatcher(), row, board([order("o1", 2)], idle=[3])) == [(3, ("o1",))]
    assert answer(OldestFirstDispatcher(), row, board([order("o1", 2)], idle=[])) == []


# -- cost ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("dispatcher", [NearestVehicleDispatcher, OldestFirstDispatcher])
def test_fifty_vehicles_and_a_hundred_orders_search_the_map_once_per_stop_segment(
    tmp_path: Path, dispatcher: type[Dispatcher]
) -> None:
    """The map searches are kept: one per stop segment (and kind of vehicle), none on the next call."""
    vehicles = "".join(f"{v},{2 * v - 1},forward,,agv\n" for v in range(1, 51))
    scenario = make_scenario(tmp_path, line(120, 5.0), vehicles, types=(AGV, TUGGER))
    orders = [order(f"o{n}", 2 + 2 * (n % 20), float(n)) for n in range(100)]
    open_board = board(orders, idle=range(1, 51))
    chosen = dispatcher()
    first = answer(chosen, scenario, open_board)
    assert len(first) == 50 and len({orders for _, orders in first}) == 50
    assert chosen.travel.searches == 20
    assert answer(chosen, scenario, open_board) == first  # no state between calls: the same answer
    assert chosen.travel.searches == 20
