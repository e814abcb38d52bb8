"""The reservation check (SPEC §7): fixed legs reserve, conflicting reservations of two vehicles alert."""

from __future__ import annotations

import itertools
from collections.abc import Mapping

from hypothesis import given, settings
from hypothesis import strategies as st

from fleetsim.enums import Direction, Progress, Shape, Traverse
from fleetsim.layout import Layout, Segment, build_layout
from fleetsim.planning import CollisionAlert, ConflictTable, FleetLeg, FleetPlan, find_alerts
from fleetsim.planning.reservations import ReservationIndex

RADIUS = 0.5  # two segments conflict when closer than 1 m


def _straight(sid: int, start: tuple[float, float], end: tuple[float, float]) -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, (start, end))


# A lane 11 → 12 → 13 along y=0 (neighbours touch, so they conflict; 11 and 13 are 5 m apart and do not),
# and 21 → 22 along y=10, far from all of them.
LAYOUT = build_layout(
    [
        _straight(11, (0.0, 0.0), (5.0, 0.0)),
        _straight(12, (5.0, 0.0), (10.0, 0.0)),
        _straight(13, (10.0, 0.0), (15.0, 0.0)),
        _straight(21, (0.0, 10.0), (5.0, 10.0)),
        _straight(22, (5.0, 10.0), (10.0, 10.0)),
    ],
    vehicle_radius=RADIUS,
)
TABLE = ConflictTable(LAYOUT)


def _plan(vehicle_id: int, fixed: tuple[int, ...] = (), planned: tuple[int, ...] = ()) -> FleetPlan:
    legs = [FleetLeg(sid, Traverse.FORWARD, Progress.FORWARD, fixed=True) for sid in fixed]
    legs += [FleetLeg(sid, Traverse.FORWARD, Progress.FORWARD, fixed=False) for sid in planned]
    return FleetPlan(vehicle_id, tuple(legs))


def _alerts(*plans: FleetPlan) -> tuple[CollisionAlert, ...]:
    return find_alerts({plan.vehicle_id: plan for plan in plans}, TABLE)


def test_the_example_layout_has_the_conflicts_the_tests_rely_on() -> None:
    assert LAYOUT.conflicts(11) == {11, 12}
    assert LAYOUT.conflicts(12) == {11, 12, 13}
    assert LAYOUT.conflicts(21) == {21, 22}
    assert LAYOUT.conflicts(11).isdisjoint(LAYOUT.conflicts(21))


def test_two_vehicles_with_fixed_legs_on_one_segment_are_both_primary_holders() -> None:
    assert _alerts(_plan(1, fixed=(11,)), _plan(2, fixed=(11,))) == (CollisionAlert(11, (1, 2), ()),)


def test_fixed_legs_on_conflicting_segments_alert_on_both_segments() -> None:
    alerts = _alerts(_plan(1, fixed=(11,)), _plan(2, fixed=(12,)))
    assert alerts == (
        CollisionAlert(11, primary=(1,), secondary=(2,)),
        CollisionAlert(12, primary=(2,), secondary=(1,)),
    )


def test_fixed_legs_with_disjoint_conflict_sets_give_no_alert() -> None:
    assert _alerts(_plan(1, fixed=(11,)), _plan(2, fixed=(21, 22))) == ()


def test_fixed_legs_on_segments_that_do_not_conflict_give_no_alert() -> None:
    # 11 and 13 both conflict with 12, but a secondary reservation alone never alerts.
    assert _alerts(_plan(1, fixed=(11,)), _plan(2, fixed=(13,))) == ()


def test_planned_legs_never_reserve() -> None:
    assert _alerts(_plan(1, fixed=(11,)), _plan(2, fixed=(13,), planned=(12, 11))) == ()
    assert _alerts(_plan(1, fixed=(11,)), _plan(2, planned=(11,))) == ()


def test_fixing_a_planned_leg_makes_it_reserve() -> None:
    alerts = _alerts(_plan(1, fixed=(11,)), _plan(2, fixed=(13, 12), planned=(11,)))
    assert alerts == (CollisionAlert(11, (1,), (2,)), CollisionAlert(12, (2,), (1,)))


def test_a_vehicles_own_consecutive_fixed_legs_never_alert() -> None:
    assert _alerts(_plan(1, fixed=(11, 12, 13))) == ()
    assert _alerts(_plan(1, fixed=(11, 12, 13)), _plan(2, fixed=(21, 22))) == ()


def test_no_plans_or_no_fixed_legs_give_no_alert() -> None:
    assert find_alerts({}, TABLE) == ()
    assert _alerts(_plan(1, planned=(11,)), _plan(2, planned=(11,))) == ()


def test_alerts_are_sorted_by_segment_and_holders_are_sorted() -> None:
    plans = {
        9: _plan(9, fixed=(11,)),
        5: _plan(5, fixed=(12,)),
        3: _plan(3, fixed=(11,)),
        10**6: _plan(10**6, fixed=(22,)),
        0: _plan(0, fixed=(21,)),
    }
    assert find_alerts(plans, TABLE) == (
        CollisionAlert(11, primary=(3, 9), secondary=(5,)),
        CollisionAlert(12, primary=(5,), secondary=(3, 9)),
        CollisionAlert(21, primary=(0,), secondary=(10**6,)),
        CollisionAlert(22, primary=(10**6,), secondary=(0,)),
    )


def test_alert_text_is_the_thesis_form() -> None:
    alert = CollisionAlert(11, primary=(1,), secondary=(2,))
    assert alert.text() == (
        "COLLISION ALERT: Possible collision detected on segment '11'\n"
        "Primary reservations\n"
        " - vehicle_1\n"
        "Secondary reservations\n"
        " - vehicle_2"
    )


def test_alert_text_lists_every_holder_and_an_empty_secondary_section() -> None:
    alert = CollisionAlert(11, primary=(1, 2), secondary=())
    assert alert.text().splitlines()[1:] == [
        "Primary reservations",
        " - vehicle_1",
        " - vehicle_2",
        "Secondary reservations",
    ]


def test_alert_names_every_vehicle_involved() -> None:
    alert = CollisionAlert(12, primary=(5,), secondary=(3, 9))
    assert alert.vehicles == (3, 5, 9)
    assert str(alert) == "possible collision on segment 12: primary 5; secondary 3, 9"


# -- property: the incremental check agrees with a plain set-based reference ------------------------------


def reference_alerts(plans: Mapping[int, FleetPlan], layout: Layout) -> tuple[CollisionAlert, ...]:
    """SPEC §7 read literally, with Python sets."""
    fixed = {
        vid: {leg.segment for leg in itertools.takewhile(lambda leg: leg.fixed, plan.legs)}
        for vid, plan in plans.items()
    }
    alerts = []
    for segment in sorted(set().union(*fixed.values())):
        primary = {vid for vid, segments in fixed.items() if segment in segments}
        secondary = {
            vid
            for vid, segments in fixed.items()
            if vid not in primary and any(segment in layout.conflicts(other) for other in segments)
        }
        if len(primary) > 1 or secondary:
            alerts.append(CollisionAlert(segment, tuple(sorted(primary)), tuple(sorted(secondary))))
    return tuple(alerts)


coordinate = st.integers(0, 12).map(float)


@st.composite
def layouts(draw: st.DrawFn) -> Layout:
    count = draw(st.integers(1, 8))
    ids = draw(st.lists(st.integers(0, 10**6), min_size=count, max_size=count, unique=True))
    segments = []
    for sid in ids:
        start = draw(st.tuples(coordinate, coordinate))
        end = draw(st.tuples(coordinate, coordinate).filter(lambda point, start=start: point != start))
        segments.append(_straight(sid, start, end))
    return build_layout(segments, vehicle_radius=draw(st.sampled_from([0.2, 0.5, 1.5])))


@st.composite
def fleets(draw: st.DrawFn, layout: Layout) -> dict[int, FleetPlan]:
    vehicle_id = st.one_of(st.integers(0, 20), st.integers(0, 10**9), st.just(10**6))
    plans = {}
    for vid in draw(st.sets(vehicle_id, max_size=6)):
        segments = draw(st.lists(st.sampled_from(sorted(layout.segments)), min_size=1, max_size=5))
        fixed_count = draw(st.integers(0, len(segments)))
        legs = tuple(
            FleetLeg(sid, draw(st.sampled_from(Traverse)), draw(st.sampled_from(Progress)), index < fixed_count)
            for index, sid in enumerate(segments)
        )
        plans[vid] = FleetPlan(vid, legs)
    return plans


@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_find_alerts_agrees_with_a_set_based_reference(data: st.DataObject) -> None:
    layout = data.draw(layouts())
    plans = data.draw(fleets(layout))
    assert find_alerts(plans, ConflictTable(layout)) == reference_alerts(plans, layout)


@settings(max_examples=100, deadline=None)
@given(data=st.data())
def test_an_index_kept_across_plan_changes_agrees_with_the_reference_at_every_check(data: st.DataObject) -> None:
    # One index sees a sequence of fleets: vehicles change plans, keep the same plan object, leave, come
    # back; the sums it folds changes into must give what a from-scratch check gives each time.
    # A second index is told which vehicles changed (as a run's controller tells it) instead of comparing
    # every plan; it must agree too.
    layout = data.draw(layouts())
    index = ReservationIndex(ConflictTable(layout))
    told = ReservationIndex(ConflictTable(layout))
    plans: dict[int, FleetPlan] = {}
    for _ in range(data.draw(st.integers(1, 6))):
        changes = data.draw(fleets(layout))
        leaving = data.draw(st.sets(st.sampled_from(sorted(plans)), max_size=2)) if plans else set()
        plans = {vid: plan for vid, plan in plans.items() if vid not in leaving} | changes
        expected = reference_alerts(plans, layout)
        assert index.alerts(plans) == expected
        assert told.alerts(plans, changed=set(changes) | leaving) == expected


@settings(max_examples=100, deadline=None)
@given(data=st.data())
def test_an_index_follows_legs_driven_past_newly_fixed_and_replaced(data: st.DataObject) -> None:
    # The changes a run makes most: a vehicle drives past its first leg, gets its next planned leg fixed,
    # or is given a new route; each kind moves only some reservations, and the index must move exactly those.
    layout = data.draw(layouts())
    index = ReservationIndex(ConflictTable(layout))
    told = ReservationIndex(ConflictTable(layout))  # told which vehicle changed
    plans = data.draw(fleets(layout))
    assert index.alerts(plans) == told.alerts(plans, changed=set(plans)) == reference_alerts(plans, layout)
    for _ in range(data.draw(st.integers(1, 8))):
        if not plans:
            break
        vid = data.draw(st.sampled_from(sorted(plans)))
        legs = plans[vid].legs
        fixed = sum(1 for leg in itertools.takewhile(lambda leg: leg.fixed, legs))
        change = data.draw(st.sampled_from(["drive past", "fix next", "new route"]))
        if change == "drive past" and len(legs) > 1:
            legs = legs[1:]
        elif change == "fix next" and fixed < len(legs):
            legs = (
                *legs[:fixed],
                FleetLeg(legs[fixed].segment, legs[fixed].traverse, legs[fixed].progress, True),
                *legs[fixed + 1 :],
            )
        else:
            legs = data.draw(fleets(layout).filter(bool)).popitem()[1].legs
        plans = {**plans, vid: FleetPlan(vid, legs)}
        assert index.alerts(plans) == told.alerts(plans, changed={vid}) == reference_alerts(plans, layout)


def test_an_index_drops_the_alert_of_a_vehicle_that_drove_past_the_shared_segment() -> None:
    index = ReservationIndex(TABLE)
    both = {1: _plan(1, fixed=(11, 12)), 2: _plan(2, fixed=(21,), planned=(22,))}
    assert index.alerts(both) == ()
    closer = {**both, 2: _plan(2, fixed=(13,))}  # a new route: 13 conflicts with vehicle 1's 12
    assert index.alerts(closer) == (CollisionAlert(12, (1,), (2,)), CollisionAlert(13, (2,), (1,)))
    past = {**closer, 1: _plan(1, fixed=(11,))}  # vehicle 1 no longer holds 12; 11 is clear of 13
    assert index.alerts(past) == ()


def test_an_alert_stays_the_same_object_while_its_holders_stay_the_same() -> None:
    # What is new is then told by identity (the loop reports an alert when it appears, not while it lasts).
    index = ReservationIndex(TABLE)
    closer = {1: _plan(1, fixed=(11, 12)), 2: _plan(2, fixed=(13,))}
    first = index.alerts(closer)
    assert index.alerts(closer) is first  # nothing changed: the same tuple
    # Vehicle 2 gets another plan object that holds the same segments: same holders, the same alerts.
    again = index.alerts({**closer, 2: _plan(2, fixed=(13,), planned=(22,))}, changed={2})
    assert again == first and all(a is b for a, b in zip(again, first, strict=True))
    # Vehicles 3 and 4 meet on 21 and 22, far away: new alerts there, the old ones the same objects.
    elsewhere = {**closer, 3: _plan(3, fixed=(21,)), 4: _plan(4, fixed=(22,))}
    third = index.alerts(elsewhere, changed={3, 4})
    assert third[0] is first[0] and third[1] is first[1]
    assert third[2:] == (CollisionAlert(21, (3,), (4,)), CollisionAlert(22, (4,), (3,)))
    # Vehicle 3 joins vehicle 2 on 13: the alerts of 12 and 13 change holders and are new objects.
    crowded = {**elsewhere, 3: _plan(3, fixed=(13,))}
    fourth = index.alerts(crowded, changed={3})
    assert fourth[:2] == (CollisionAlert(12, (1,), (2, 3)), CollisionAlert(13, (2, 3), (1,)))
    assert fourth[0] is not first[0] and fourth[1] is not first[1]
