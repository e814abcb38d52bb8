"""The plan checks remember drives that passed (``DriveMemo``): a sequence of plans, legal and not, gets
exactly the same verdicts, codes, legs and messages with the memory as without it."""

from __future__ import annotations

from dataclasses import replace

from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.enums import JointKind, Progress, Traverse, TurnCapability
from fleetsim.layout import build_layout
from fleetsim.planning.checks import CheckContext, DriveMemo, check_plan
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.snapshot import initial_plan
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Vehicle
from fleetsim.strategies.geometry import grid

LAYOUT = build_layout(grid(3), vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius)
SEGMENTS = sorted(LAYOUT.segments)
TYPES = {
    1: replace(DEFAULT_VEHICLE_TYPE, name="agv", turn_capability=TurnCapability.IN_PLACE),
    2: replace(DEFAULT_VEHICLE_TYPE, name="tugger", turn_capability=TurnCapability.CURVE),
}
START = {vehicle: FleetLeg(SEGMENTS[0], Traverse.FORWARD, Progress.FORWARD, fixed=True) for vehicle in TYPES}


@st.composite
def walks(draw: st.DrawFn) -> FleetPlan:
    """Mostly connected walks from the start (so that many pass), now and then any leg at all."""
    vehicle = draw(st.sampled_from(sorted(TYPES)))
    legs = [START[vehicle]]
    for _ in range(draw(st.integers(0, 8))):
        last = legs[-1]
        onward = sorted(LAYOUT.successors(last.segment, last.traverse))
        if onward and draw(st.integers(0, 9)) > 0:
            segment, traverse, _joint = draw(st.sampled_from(onward))
        else:
            segment, traverse = draw(st.sampled_from(SEGMENTS)), draw(st.sampled_from(list(Traverse)))
        legs.append(FleetLeg(segment, traverse, draw(st.sampled_from(list(Progress))), fixed=False))
    return FleetPlan(vehicle, tuple(legs))


def _verdict(plan: FleetPlan, memo: DriveMemo | None) -> object:
    plans = {vehicle: FleetPlan(vehicle, (START[vehicle],)) for vehicle in TYPES}
    ctx = CheckContext(LAYOUT, TYPES, plans, dict.fromkeys(TYPES, ()), drives=memo)
    rejection = check_plan(plan, ctx)
    return None if rejection is None else (rejection.code, rejection.leg_index, rejection.message)


@settings(max_examples=300, deadline=None)
@given(st.lists(walks(), min_size=1, max_size=30))
def test_a_remembered_drive_changes_no_verdict(plans: list[FleetPlan]) -> None:
    memo = DriveMemo()
    for plan in plans:
        assert _verdict(plan, memo) == _verdict(plan, None)


def test_the_start_plan_passes() -> None:
    vehicle = Vehicle(1, SEGMENTS[0], Traverse.FORWARD, Progress.FORWARD, TYPES[1])
    assert _verdict(initial_plan(vehicle), DriveMemo()) is None


def _legal_two_legs() -> FleetPlan:
    """The tugger's start leg and a legal one after it, straight on."""
    first = START[2]
    onward = sorted(LAYOUT.successors(first.segment, first.traverse))
    segment, traverse, _joint = next(step for step in onward if step[2] is JointKind.SAME)
    return FleetPlan(2, (first, FleetLeg(segment, traverse, Progress.FORWARD, fixed=False)))


def test_a_plan_of_remembered_drives_with_one_new_pair_is_still_judged_in_full() -> None:
    legal = _legal_two_legs()
    first = legal.legs[0]
    memo = DriveMemo()
    assert _verdict(legal, memo) is None and memo.passed(legal, TurnCapability.CURVE)
    # The same drives, then back onto the first leg's segment the other way: not connected.
    back = FleetLeg(first.segment, Traverse.BACKWARD, Progress.FORWARD, fixed=False)
    broken = FleetPlan(2, (*legal.legs, back))
    assert not memo.passed(broken, TurnCapability.CURVE)
    assert _verdict(broken, memo) == _verdict(broken, None) is not None


@settings(max_examples=200, deadline=None)
@given(st.lists(walks(), min_size=1, max_size=10), st.data())
def test_a_plan_that_ends_as_the_last_one_passed_gets_the_same_verdict(
    plans: list[FleetPlan], data: st.DataObject
) -> None:
    """The memory keeps each vehicle's last plan that passed: the same route again, with legs fixed or
    driven past, or changed at one leg (another drive, backing instead of nose first), gets the verdict
    the checks give without any memory."""
    memo = DriveMemo()
    for plan in plans:
        assert _verdict(plan, memo) == _verdict(plan, None)
        legs = plan.legs
        skip = data.draw(st.integers(0, len(legs) - 1))
        fixed = data.draw(st.integers(0, len(legs)))
        variants = [
            FleetPlan(plan.vehicle_id, tuple(replace(leg, fixed=k < fixed) for k, leg in enumerate(legs[skip:])))
        ]
        at = data.draw(st.integers(0, len(legs) - 1))
        changed = replace(
            legs[at], progress=Progress.REVERSE if legs[at].progress is Progress.FORWARD else Progress.FORWARD
        )
        variants.append(FleetPlan(plan.vehicle_id, (*legs[:at], changed, *legs[at + 1 :])))
        for variant in variants:
            assert _verdict(variant, memo) == _verdict(variant, None)


def test_the_last_plan_that_passed_lets_the_same_route_pass_without_its_drives() -> None:
    legal = _legal_two_legs()
    first = legal.legs[0]
    memo = DriveMemo()
    assert _verdict(legal, memo) is None
    memo._legs.clear()  # (forgotten drives: only the last plan can say it passed)
    memo._pairs.clear()
    fixed = FleetPlan(2, (first, replace(legal.legs[1], fixed=True)))
    assert memo.passed(fixed, TurnCapability.CURVE)  # the same drives, a leg fixed
    assert memo.passed(FleetPlan(2, legal.legs[1:]), TurnCapability.CURVE)  # the first driven past
    assert not memo.passed(legal, TurnCapability.IN_PLACE)  # another capability: its own last plan
    backing = FleetPlan(2, (first, replace(legal.legs[1], progress=Progress.REVERSE)))
    assert not memo.passed(backing, TurnCapability.CURVE)
