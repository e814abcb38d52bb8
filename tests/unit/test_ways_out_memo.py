"""The reference planner's remembered searches for ways out (fleetsim.planners.making_way.WaysOutMemo):
a search is made again exactly when what it read changed, and what the memo gives is what a fresh search
finds, in the shipped shifts where vehicles make way thousands of times."""

from __future__ import annotations

from collections.abc import Callable
from collections.abc import Set as AbstractSet
from pathlib import Path

from loop_switches import run_switched

from fleetsim.enums import Direction, Progress, Shape, Traverse, TurnCapability
from fleetsim.layout import Segment, build_layout
from fleetsim.layout.reachability import State
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import ReservingPlanner
from fleetsim.planners.fleet_index import FleetIndex
from fleetsim.planners.making_way import Reads, WayOut, WaysOutMemo, ways_out
from fleetsim.planners.routing import RoutesMemo, StepTable
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario
from fleetsim.sim.loop import run_scenario

WAREHOUSE = Path(__file__).resolve().parents[2] / "scenario_suites" / "warehouse.fleetsim.yaml"

# A lane of segments 1 → 2 → … → 8, 4 m each, driven both ways.
LAYOUT = build_layout(
    [Segment(sid, Shape.STRAIGHT, Direction.BOTH, ((4.0 * sid, 0.0), (4.0 * sid + 4.0, 0.0))) for sid in range(1, 9)],
    vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius,
)
LENGTHS = {sid: segment.length for sid, segment in LAYOUT.segments.items()}
TABLE = StepTable(LAYOUT, TurnCapability.IN_PLACE)
START: State = (1, Traverse.FORWARD, Progress.FORWARD)


def _standing_on(vehicle: int, segment: int) -> FleetPlan:
    return FleetPlan(vehicle, (FleetLeg(segment, Traverse.FORWARD, Progress.FORWARD, True),))


def _ask(memo: WaysOutMemo, index: FleetIndex, movable: Callable[[int], bool], avoid: AbstractSet[int]) -> list[WayOut]:
    found = memo.ways_out(1, START, avoid, index, LENGTHS, movable, turnaround=10.0, limit=4_000, table=TABLE)
    fresh = ways_out(
        1, START, TurnCapability.IN_PLACE, avoid, LAYOUT, index, LENGTHS, movable,
        turnaround=10.0, limit=4_000, table=TABLE,
    )  # fmt: skip
    assert found == fresh
    return found


def _nobody(_: int) -> bool:
    return False


def _places(ways: list[WayOut]) -> list[tuple[int, tuple[int, ...]]]:
    return [(way.path[-1][0], way.crossing) for way in ways]


def test_an_unchanged_fleet_is_not_searched_again() -> None:
    index, memo = FleetIndex(LAYOUT, 6), WaysOutMemo()
    index.assume(2, _standing_on(2, 6))
    first = _ask(memo, index, _nobody, {1, 2})
    assert _places(first) == [(3, ())]
    assert _ask(memo, index, _nobody, {1, 2}) is first
    assert _ask(memo, index, _nobody, frozenset({1, 2})) is first  # the same area, however given
    assert (memo.asked, memo.searched) == (3, 1)


def test_a_change_where_the_search_looked_makes_it_again_and_one_taken_back_does_not() -> None:
    index, memo = FleetIndex(LAYOUT, 6), WaysOutMemo()
    index.assume(2, _standing_on(2, 6))
    assert _places(_ask(memo, index, _nobody, {1, 2})) == [(3, ())]
    index.assume(2, _standing_on(2, 4))  # now next to segment 3, where the way ended
    assert _ask(memo, index, _nobody, {1, 2}) == [] and memo.searched == 2  # 3 is held, and 4 and 5 past it
    # Moved and moved back between two questions: the segments are stamped later, their holders the same.
    index.assume(2, _standing_on(2, 6))
    index.assume(2, _standing_on(2, 3))
    index.assume(2, _standing_on(2, 4))
    assert _ask(memo, index, _nobody, {1, 2}) == [] and memo.searched == 2


def test_the_last_two_fleets_a_search_was_made_in_are_kept() -> None:
    # (A vehicle's way out is searched with and without the plans of the vehicles moved before it, in turn.)
    index, memo = FleetIndex(LAYOUT, 6), WaysOutMemo()
    index.assume(2, _standing_on(2, 6))
    first = _ask(memo, index, _nobody, {1, 2})
    index.assume(2, _standing_on(2, 4))
    assert _ask(memo, index, _nobody, {1, 2}) == []
    index.assume(2, _standing_on(2, 6))
    assert _ask(memo, index, _nobody, {1, 2}) is first and memo.searched == 2
    index.assume(2, _standing_on(2, 3))  # a third: the first is forgotten
    assert _ask(memo, index, _nobody, {1, 2}) == [] and memo.searched == 3
    index.assume(2, _standing_on(2, 6))
    assert _ask(memo, index, _nobody, {1, 2}) == first and memo.searched == 4


def test_a_change_far_from_where_the_search_looked_keeps_its_ways() -> None:
    index, memo = FleetIndex(LAYOUT, 6), WaysOutMemo()
    index.assume(2, _standing_on(2, 5))
    first = _ask(memo, index, _nobody, {1, 2})
    index.assume(3, _standing_on(3, 8))  # beyond vehicle 2, where the search never looked
    assert _ask(memo, index, _nobody, {1, 2}) is first
    assert memo.searched == 1


def test_another_answer_to_whether_a_blocker_may_move_makes_the_search_again() -> None:
    index, memo = FleetIndex(LAYOUT, 6), WaysOutMemo()
    index.assume(2, _standing_on(2, 4))
    asked: list[int] = []

    def may(answer: bool) -> Callable[[int], bool]:
        def movable(other: int) -> bool:
            asked.append(other)
            return answer

        return movable

    assert _ask(memo, index, may(False), {1, 2}) == [] and memo.searched == 1
    crossing = _ask(memo, index, may(True), {1, 2})
    assert _places(crossing) == [(6, (2,))] and memo.searched == 2  # through where vehicle 2 stands
    del asked[:]
    assert _ask(memo, index, may(True), {1, 2}) == crossing and memo.searched == 2
    assert asked[0] == 2  # the memo asked again (and the fresh search after it): the answer may have changed


def test_a_memo_that_keeps_nothing_searches_every_time() -> None:
    class Forgetful(WaysOutMemo):
        capacity = 0

    index, memo = FleetIndex(LAYOUT, 6), Forgetful()
    _ask(memo, index, _nobody, {1, 2})
    _ask(memo, index, _nobody, {1, 2})
    assert (memo.asked, memo.searched) == (2, 2)


class _Checking(WaysOutMemo):
    """Checks every answer against a fresh search (which asks ``movable`` again: the planner's answers do
    not depend on how often it is asked)."""

    def ways_out(
        self,
        vehicle: int,
        start: State,
        avoid: AbstractSet[int],
        index: FleetIndex,
        lengths: dict[int, float],
        movable: Callable[[int], bool],
        *,
        turnaround: float,
        limit: int,
        table: StepTable,
        wanted: int = 6,
        reads: Reads | None = None,
    ) -> list[WayOut]:
        found = super().ways_out(
            vehicle, start, avoid, index, lengths, movable,
            turnaround=turnaround, limit=limit, table=table, wanted=wanted, reads=reads,
        )  # fmt: skip
        fresh = ways_out(
            vehicle, start, table.capability, avoid, table.layout, index, lengths, movable,
            turnaround=turnaround, limit=limit, wanted=wanted, table=table,
        )  # fmt: skip
        assert found == fresh, (vehicle, start)
        return found


def _planner(memo: WaysOutMemo) -> ReservingPlanner:
    planner = ReservingPlanner()
    planner._ways_out = memo
    return planner


def _warehouse(name: str) -> Scenario:
    suite = load_suite(WAREHOUSE)
    return load_scenario(next(entry for entry in suite.scenarios if entry.name == name), suite)


def test_in_a_shipped_shift_every_remembered_answer_is_what_a_fresh_search_finds() -> None:
    memo = _Checking()
    # Every vehicle asked on every round (the quiet hint ignored), so that blocked vehicles ask again and again.
    result = run_switched(_warehouse("deadlines-oldest-first"), _planner(memo), quiet=False)
    assert result.ended == "shift-end"
    # Vehicles made way there thousands of times, and most searches were not made again.
    assert memo.asked > 3_000 and memo.searched < memo.asked / 10


def test_a_shift_runs_the_same_with_every_search_made_again() -> None:
    class Forgetful(WaysOutMemo):
        capacity = 0

    class NoRoutes(RoutesMemo):
        capacity = 0

    scenario = _warehouse("shift")
    remembered, forgetful = WaysOutMemo(), Forgetful()
    kept = run_scenario(scenario, _planner(remembered), keep_trace=False)
    again_planner = _planner(forgetful)
    again_planner._routes = NoRoutes()
    again = run_scenario(scenario, again_planner, keep_trace=False)
    assert kept.trace_hash == again.trace_hash
    assert kept.metrics.planner_calls == again.metrics.planner_calls
    assert forgetful.searched == forgetful.asked == remembered.asked > remembered.searched
    assert again_planner._routes.searched == again_planner._routes.asked > 0
