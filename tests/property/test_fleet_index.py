"""The planner's fleet index counts only what changed between plans; its tables must always equal the
tables counted from scratch, whatever sequence of plans, assumptions and restores it sees."""

from __future__ import annotations

from dataclasses import replace

from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.enums import Progress, Traverse
from fleetsim.layout import build_layout
from fleetsim.planners.fleet_index import FleetIndex, _delta, _parts
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.snapshot import FleetSnapshot, PlanLog
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE
from fleetsim.strategies.geometry import grid

LAYOUT = build_layout(grid(4), vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius)
SEGMENTS = sorted(LAYOUT.segments)
AHEAD = 3

legs = st.builds(
    lambda segment, traverse, fixed: FleetLeg(segment, traverse, Progress.FORWARD, fixed=fixed),
    st.sampled_from(SEGMENTS),
    st.sampled_from(list(Traverse)),
    st.booleans(),
)


def plan_of(vehicle: int, drawn: list[FleetLeg], fixed: int) -> FleetPlan:
    """Fixed legs first (at least the one it stands on), then planned ones, as the protocol has them."""
    count = max(1, min(fixed, len(drawn)))
    return FleetPlan(
        vehicle,
        tuple(FleetLeg(leg.segment, leg.traverse, leg.progress, fixed=k < count) for k, leg in enumerate(drawn)),
    )


plans = st.builds(plan_of, st.integers(1, 3), st.lists(legs, min_size=1, max_size=8), st.integers(0, 8))
actions = st.lists(st.tuples(st.sampled_from(["assume", "restore"]), plans), min_size=1, max_size=25)


def tables(index: FleetIndex) -> tuple[object, ...]:
    return (index.fixed_near, index.ahead_near, index.drives)


@settings(max_examples=200, deadline=None)
@given(actions)
def test_counts_equal_counting_from_scratch(steps: list[tuple[str, FleetPlan]]) -> None:
    index = FleetIndex(LAYOUT, AHEAD)
    current: dict[int, FleetPlan] = {}
    undo: list[tuple[int, FleetPlan | None]] = []
    for action, plan in steps:
        if action == "assume" or not undo:
            undo.append((plan.vehicle_id, index.assume(plan.vehicle_id, plan)))
            current[plan.vehicle_id] = plan
        else:
            vehicle, old = undo.pop()
            index.restore(vehicle, old)
            if old is None:
                current.pop(vehicle, None)
            else:
                current[vehicle] = old
        fresh = FleetIndex(LAYOUT, AHEAD)
        for vehicle, held in sorted(current.items()):
            fresh.assume(vehicle, held)
        assert tables(index) == tables(fresh)
        for segment in SEGMENTS:  # whose routes come near each segment, gathered when asked
            for vehicle in range(1, 5):
                near = {
                    other
                    for other, held in current.items()
                    if other != vehicle and any(segment in LAYOUT.conflicts(leg.segment) for leg in held.legs)
                }
                assert index.routes_near(vehicle, segment) == len(near), (vehicle, segment)


def test_holders_are_the_others_by_id() -> None:
    index = FleetIndex(LAYOUT, AHEAD)
    segment = SEGMENTS[0]
    for vehicle in (3, 1, 2):
        index.assume(vehicle, FleetPlan(vehicle, (FleetLeg(segment, Traverse.FORWARD, Progress.FORWARD, fixed=True),)))
    assert index.holders(2, segment) == [1, 3]
    assert index.holders(4, segment) == [1, 2, 3]
    lone = FleetIndex(LAYOUT, AHEAD)
    lone.assume(1, FleetPlan(1, (FleetLeg(segment, Traverse.FORWARD, Progress.FORWARD, fixed=True),)))
    assert lone.holders(1, segment) == [] and lone.holders(2, segment) == [1]
    far = next(s for s in SEGMENTS if s not in LAYOUT.conflicts(segment))
    assert lone.holders(2, far) == []


fleet_steps = st.lists(
    st.tuples(
        st.dictionaries(st.integers(1, 5), plans, max_size=5),  # vehicles given new plans
        st.booleans(),  # the fleet lists its vehicles in another order
        st.lists(plans, max_size=2),  # plans assumed (and left) between refreshes, as within a call
    ),
    min_size=1,
    max_size=12,
)


def _shown(
    fleet: dict[int, FleetPlan], order: list[int], version: int | None = None, log: PlanLog | None = None
) -> FleetSnapshot:
    plans = {vehicle: fleet[vehicle] for vehicle in order}
    return FleetSnapshot(0.0, {}, plans, {}, frozenset(), plans_version=version, _log=log)


def in_order(index: FleetIndex) -> list[object]:
    """The tables with the order of their entries (what iterates over them sees)."""
    return [[(key, list(counts.items())) for key, counts in table.items()] for table in tables(index)]


@settings(max_examples=200, deadline=None)
@given(st.dictionaries(st.integers(1, 5), plans, min_size=1, max_size=5), fleet_steps, st.integers(1, 6))
def test_refreshing_from_each_fleet_counts_that_fleet(
    first: dict[int, FleetPlan], steps: list[tuple[dict[int, FleetPlan], bool, list[FleetPlan]]], keep: int
) -> None:
    # Refresh recounts the vehicles whose plans are other objects than those it counts: found in C when
    # the fleet lists the same vehicles in the same order, else one by one, or (with plan versions) those
    # the snapshot's log names and those it assumed itself. A run shows the same plans mapping (and plans
    # version) again until a plan changes, and a refresh from it changes nothing. After a change, every
    # way gives the tables of the fleet counted from scratch, and the versioned way counts them in the same
    # order as the first.
    index = FleetIndex(LAYOUT, AHEAD)
    versioned = FleetIndex(LAYOUT, AHEAD)  # refreshed by plan versions, from a log of ``keep`` changes
    log, version = PlanLog(keep), 0
    fleet = {vehicle: FleetPlan(vehicle, plan.legs) for vehicle, plan in sorted(first.items())}
    order = sorted(fleet)
    shown = _shown(fleet, order)
    index.refresh(shown)
    versioned.refresh(_shown(fleet, order, version, log))
    reordered = False  # (a run's mapping lists its vehicles in one order: the order compared only then)
    for changes, reorder, assumed in steps:
        reordered |= reorder
        changed = False
        for vehicle, plan in changes.items():
            if vehicle in fleet:
                fleet[vehicle] = FleetPlan(vehicle, plan.legs)
                version += 1
                log.add(vehicle)
                changed = True
        for plan in assumed:
            if plan.vehicle_id in fleet:
                index.assume(plan.vehicle_id, plan)
                versioned.assume(plan.vehicle_id, plan)
        if changed or reorder:
            shown = _shown(fleet, order[::-1] if reorder else order)
        index.refresh(shown)
        versioned.refresh(_shown(fleet, order, version, log))
        fresh = FleetIndex(LAYOUT, AHEAD)
        for vehicle, held in sorted(fleet.items()):
            fresh.assume(vehicle, held)
        if changed or reorder:
            assert tables(index) == tables(fresh)
        if changed:
            assert tables(versioned) == tables(fresh)
        if not reordered:
            assert in_order(versioned) == in_order(index)


class _CountedInFull(FleetIndex):
    """The index as it recounted before the short ways: every part of both plans compared in full."""

    def _recount(self, vehicle: int, old: FleetPlan, new: FleetPlan) -> None:
        for table, before, after in zip(self._tables(), _parts(old, AHEAD), _parts(new, AHEAD), strict=True):
            if before != after:
                self._add_all(table, vehicle, _delta(before, after))


def _fix_one_more(plan: FleetPlan) -> FleetPlan:
    legs = plan.legs
    first = len(plan.fixed_legs)
    if first >= len(legs):
        return plan
    return FleetPlan(plan.vehicle_id, (*legs[:first], replace(legs[first], fixed=True), *legs[first + 1 :]))


def _drive_past(plan: FleetPlan) -> FleetPlan:
    legs = plan.legs
    if len(plan.fixed_legs) < 2:
        return plan
    return FleetPlan(plan.vehicle_id, legs[1:])


evolutions = st.lists(
    st.tuples(st.integers(1, 3), st.sampled_from(["fix", "drive", "new"]), plans), min_size=1, max_size=30
)


@settings(max_examples=200, deadline=None)
@given(st.dictionaries(st.integers(1, 3), plans, min_size=1, max_size=3), evolutions)
def test_recounting_a_fixed_leg_or_a_leg_driven_past_changes_the_tables_as_counting_in_full(
    first: dict[int, FleetPlan], steps: list[tuple[int, str, FleetPlan]]
) -> None:
    index, full = FleetIndex(LAYOUT, AHEAD), _CountedInFull(LAYOUT, AHEAD)
    fleet = {vehicle: FleetPlan(vehicle, plan.legs) for vehicle, plan in sorted(first.items())}
    for vehicle, plan in fleet.items():
        index.assume(vehicle, plan)
        full.assume(vehicle, plan)
    for vehicle, how, drawn in steps:
        if vehicle not in fleet:
            continue
        plan = fleet[vehicle]
        if how == "fix":
            plan = _fix_one_more(plan)
        elif how == "drive":
            plan = _drive_past(plan)
        else:
            plan = FleetPlan(vehicle, drawn.legs)
        fleet[vehicle] = plan
        index.assume(vehicle, plan)
        full.assume(vehicle, plan)
        assert in_order(index) == in_order(full)


def test_stamps_say_when_the_holders_and_the_routes_near_a_segment_changed() -> None:
    """A fixed leg stamps every segment it comes near, a drive its own segment; the routes near a segment
    are as new as its newest drive near it."""
    index = FleetIndex(LAYOUT, AHEAD)
    segment = SEGMENTS[0]
    far = next(s for s in SEGMENTS if s not in LAYOUT.conflicts(segment))
    before = index.tick
    assert index.route_stamp(segment) == 0
    index.assume(1, FleetPlan(1, (FleetLeg(segment, Traverse.FORWARD, Progress.FORWARD, fixed=True),)))
    assert index.stamps[segment] > before and far not in index.stamps
    assert index.drive_stamps[segment] > before and far not in index.drive_stamps
    assert index.route_stamp(segment) > before and index.route_stamp(far) == 0


@settings(max_examples=100, deadline=None)
@given(
    st.dictionaries(st.integers(1, 3), plans, max_size=3),
    st.lists(plans, min_size=1, max_size=3, unique_by=lambda p: p.vehicle_id),
)
def test_drives_alone_assumed_count_the_new_drives_and_restore_the_old(
    counted: dict[int, FleetPlan], moved: list[FleetPlan]
) -> None:
    """While the plans of vehicles moved are assumed for their drives alone (a route search's costs read
    nothing else), the drives are those of the fleet with them and everything else that of the fleet
    without; restored, every table is as before, and the index takes whole plans again."""
    index = FleetIndex(LAYOUT, AHEAD)
    for vehicle, plan in sorted(counted.items()):
        index.assume(vehicle, plan)
    before = tables(index)
    undo = [(plan.vehicle_id, index.assume_drives(plan.vehicle_id, plan)) for plan in moved]
    with_them = FleetIndex(LAYOUT, AHEAD)
    for vehicle, plan in sorted({**counted, **{plan.vehicle_id: plan for plan in moved}}.items()):
        with_them.assume(vehicle, plan)
    assert index.drives == with_them.drives
    assert before[:2] == (index.fixed_near, index.ahead_near)
    for vehicle, old in reversed(undo):
        index.restore_drives(vehicle, old)
    assert tables(index) == before
    index.assume(moved[0].vehicle_id, moved[0])  # whole plans again
