"""The reference planner's remembered routes (fleetsim.planners.routing.RoutesMemo): a route is searched
again exactly when what its search read changed (plans driving a segment it looked at the other way, the
segments near vehicles without tasks). A shipped shift runs the same with every route searched again
(tests/unit/test_ways_out_memo.py)."""

from __future__ import annotations

from pathlib import Path

from fleetsim.enums import Direction, Progress, Shape, Traverse
from fleetsim.layout import Segment, build_layout
from fleetsim.planners import ReservingPlanner
from fleetsim.planners.fleet_index import FleetIndex
from fleetsim.planners.routing import RouteFound, RoutesMemo
from fleetsim.planning import FleetController
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, Task, Vehicle

WAREHOUSE = Path(__file__).resolve().parents[2] / "scenario_suites" / "warehouse.fleetsim.yaml"
LAYOUT = build_layout(
    [Segment(sid, Shape.STRAIGHT, Direction.BOTH, ((4.0 * sid, 0.0), (4.0 * sid + 4.0, 0.0))) for sid in range(1, 9)],
    vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius,
)
KEY = ("a question",)
F, B = Traverse.FORWARD, Traverse.BACKWARD


def _driving(vehicle: int, segment: int, traverse: Traverse) -> FleetPlan:
    legs = (FleetLeg(1, F, Progress.FORWARD, True), FleetLeg(segment, traverse, Progress.FORWARD, False))
    return FleetPlan(vehicle, legs)


def _remembered(index: FleetIndex) -> RoutesMemo:
    """A route that looked at segment 5 driven forward (no one driving it backward, no parked vehicle
    near) and at segment 6 (near a parked vehicle)."""
    memo = RoutesMemo()
    read = ((5, F, B, False, False), (6, F, B, False, True))
    memo.keep(KEY, RouteFound(None, index.tick, read, frozenset({6}), frozenset({5})))
    return memo


def test_a_route_is_given_again_while_what_it_read_is_the_same() -> None:
    index = FleetIndex(LAYOUT, 6)
    memo = _remembered(index)
    assert memo.get(KEY, 1, index, {6, 7}) is not None
    index.assume(2, _driving(2, 7, B))  # another plan drives 7 the other way: the search never looked there
    index.assume(3, _driving(3, 5, F))  # and one drives 5 the same way: not head-on
    assert memo.get(KEY, 1, index, {6}) is not None
    index.assume(1, _driving(1, 5, B))  # the vehicle's own plan does not count
    assert memo.get(KEY, 1, index, {6}) is not None
    assert (memo.asked, memo.searched) == (3, 0)


def test_a_plan_driving_a_segment_looked_at_the_other_way_makes_the_search_again() -> None:
    index = FleetIndex(LAYOUT, 6)
    memo = _remembered(index)
    index.assume(2, _driving(2, 5, B))
    assert memo.get(KEY, 1, index, {6}) is None and memo.searched == 1


def test_a_parked_vehicle_near_another_segment_looked_at_makes_the_search_again() -> None:
    index = FleetIndex(LAYOUT, 6)
    memo = _remembered(index)
    assert memo.get(KEY, 1, index, {5, 6}) is None  # now near 5 as well
    assert memo.get(KEY, 1, index, set()) is None  # no longer near 6
    assert memo.searched == 2


def test_a_memo_that_keeps_nothing_remembers_nothing() -> None:
    class Forgetful(RoutesMemo):
        capacity = 0

    index = FleetIndex(LAYOUT, 6)
    memo = Forgetful()
    memo.keep(KEY, RouteFound(None, index.tick, (), frozenset(), frozenset()))
    assert memo.get(KEY, 1, index, set()) is None


def _fleet(*tasks: Task) -> FleetSnapshot:
    """Vehicle 1 on segment 1, vehicle 2 on segment 8, of the lane."""
    vehicles = tuple(
        Vehicle(vid, segment, F, Progress.FORWARD, DEFAULT_VEHICLE_TYPE) for vid, segment in ((1, 1), (2, 8))
    )
    types = {DEFAULT_VEHICLE_TYPE.name: DEFAULT_VEHICLE_TYPE}
    return FleetController(Scenario("lane", LAYOUT, types, vehicles, tasks)).snapshot(0.0)


def test_the_planner_asks_the_same_route_once_until_a_plan_drives_its_way_head_on() -> None:
    task = Task(1, 1, 6)
    fleet = _fleet(task, Task(2, 2, 7))
    planner = ReservingPlanner()
    last = fleet.plans[1].legs[-1]
    first = planner._route(task, last, fleet, LAYOUT, remember=True)
    assert first is not None and [leg.segment for leg in first] == [2, 3, 4, 5, 6]
    assert planner._route(task, last, fleet, LAYOUT, remember=True) == first
    assert (planner._routes.asked, planner._routes.searched) == (2, 1)
    assert planner._index is not None
    planner._index.assume(2, _driving(2, 4, B))  # (as a plan of the same answer would be counted)
    assert planner._route(task, last, fleet, LAYOUT, remember=True) == first  # the only way, dearer now
    assert planner._routes.searched == 2
    assert planner._route(task, last, fleet, LAYOUT, remember=True) == first and planner._routes.searched == 2


def test_only_routes_likely_asked_again_are_remembered() -> None:
    # (A route to a new task is seldom asked twice; the route on from a waiting place is, round after round.)
    task = Task(1, 1, 6)
    fleet = _fleet(task)
    planner = ReservingPlanner()
    last = fleet.plans[1].legs[-1]
    assert planner._route(task, last, fleet, LAYOUT) == planner._route(task, last, fleet, LAYOUT) is not None
    assert planner._route(task, last, fleet, LAYOUT, within=100.0, remember=True) is not None  # a way round
    assert planner._routes.asked == 0
