"""The planner's fleet index counts only what changed between plans; its tables must always equal the
tables counted from scratch, whatever sequence of plans, assumptions and restores it sees."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.enums import Progress, Traverse
from fleetsim.layout import build_layout
from fleetsim.planners.fleet_index import FleetIndex
from fleetsim.planning.plans import FleetLeg, FleetPlan
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
    return (index.fixed_near, index.ahead_near, index.route_near, index.drives)


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


@settings(max_examples=200, deadline=None)
@given(st.dictionaries(st.integers(1, 5), plans, min_size=1, max_size=5), fleet_steps)
def test_refreshing_from_each_fleet_counts_that_fleet(
    first: dict[int, FleetPlan], steps: list[tuple[dict[int, FleetPlan], bool, list[FleetPlan]]]
) -> None:
    # Refresh recounts the vehicles whose plans are other objects than those it counts, found in C when
    # the fleet lists the same vehicles in the same order, else one by one; either way the tables must be
    # those of the fleet, counted from scratch.
    index = FleetIndex(LAYOUT, AHEAD)
    fleet = {vehicle: FleetPlan(vehicle, plan.legs) for vehicle, plan in sorted(first.items())}
    index.refresh(dict(fleet))
    for changes, reorder, assumed in steps:
        for vehicle, plan in changes.items():
            if vehicle in fleet:
                fleet[vehicle] = FleetPlan(vehicle, plan.legs)
        for plan in assumed:
            if plan.vehicle_id in fleet:
                index.assume(plan.vehicle_id, plan)
        shown = dict(reversed(list(fleet.items()))) if reorder else dict(fleet)
        index.refresh(shown)
        fresh = FleetIndex(LAYOUT, AHEAD)
        for vehicle, held in sorted(fleet.items()):
            fresh.assume(vehicle, held)
        assert tables(index) == tables(fresh)
