"""Cruising vehicles stepped together in arrays (motion/fleet_cruise.py) give exactly what their drivers
give one by one: the same floats to the last bit, so the same traces and hashes.

A vehicle is stepped in the arrays only while its driver's own :meth:`Driver.cruise` would succeed on the
same piece of its track; on the step its profile or its leg ends, or it moves onto another piece of a
polyline, or its plan changed, it is handed back to its driver, up to date.
"""

from __future__ import annotations

import copy
import math
from collections import Counter
from pathlib import Path

import pytest
from loop_switches import run_switched, same_run
from scenario_factory import AGV, TUGGER

from fleetsim.enums import Direction, Progress, Shape, Traverse
from fleetsim.layout import Segment, build_layout
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.motion.driver import Driver
from fleetsim.motion.fleet_cruise import FleetCruise
from fleetsim.motion.slowdown import SlowDownProfile
from fleetsim.motion.track import HeadingTable
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.scenario import Scenario, Vehicle, VehicleType
from fleetsim.sim.loop import run_scenario

DT = 0.1
EPS = 1e-9
F, B = Traverse.FORWARD, Traverse.BACKWARD
FWD, REV = Progress.FORWARD, Progress.REVERSE
SUITES = sorted((Path(__file__).resolve().parents[2] / "scenario_suites").glob("*.fleetsim.yaml"))


def straight(sid: int, start: tuple[float, float], end: tuple[float, float]) -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, (start, end))


def polyline(sid: int, *points: tuple[float, float]) -> Segment:
    return Segment(sid, Shape.PATH, Direction.BOTH, points)


def driver_on(segments: tuple[Segment, ...], start: Traverse = F, vehicle_type: VehicleType = AGV) -> Driver:
    layout = build_layout(segments, vehicle_radius=0.3)
    first = segments[0]
    heading = first.pose_at(0.0, start)[2]
    return Driver(Vehicle(1, first.id, start, FWD, vehicle_type), layout, HeadingTable(layout), heading)


def plan(*legs: tuple[int, Traverse, Progress]) -> FleetPlan:
    return FleetPlan(1, tuple(FleetLeg(s, t, p, fixed=True) for s, t, p in legs))


# Straight east, on along a polyline of several pieces (smooth joints), then back out along a cusp.
ROUTE_SEGMENTS = (
    straight(1, (0.0, 0.0), (3.0, 0.0)),
    polyline(2, (3.0, 0.0), (4.0, 0.05), (5.0, 0.15), (6.0, 0.3), (7.0, 0.5)),
    straight(3, (7.0, 0.5), (3.5, 1.5)),
)
ROUTE = ((1, F, FWD), (2, F, FWD), (3, F, REV))


def hand_back_reason(driver: Driver, route: FleetPlan) -> str:
    """Why a vehicle that was armed could not be stepped in the arrays, from its driver's own fields."""
    profile = driver._profile
    assert profile is not None
    t1 = driver._elapsed + DT
    if t1 >= profile.stop_time:
        return "profile ends"
    travelled, _ = profile.running_at(t1)
    along = driver.distance + travelled - driver._travelled
    track = driver._headings.track(route.legs[0].segment, route.legs[0].traverse)
    if along >= track.length - EPS:
        return "leg ends"
    return "another piece"


@pytest.mark.parametrize(
    ("vehicle_type", "start"),
    [(AGV, F), (TUGGER, F), (AGV, B)],
    ids=["turns-in-place", "follows-curves", "backward-traverse"],
)
def test_each_step_is_taken_in_the_arrays_exactly_when_the_driver_would_cruise_on_the_same_piece(
    vehicle_type: VehicleType, start: Traverse
) -> None:
    """At every step of a drive through acceleration, cruising, braking, smooth joints, the pieces of a
    polyline and a cusp: a copy of the driver armed in the arrays is stepped there exactly when its own
    cruise succeeds without leaving its piece, with the same state, and handed back unchanged otherwise."""
    segments = ROUTE_SEGMENTS
    route = plan(*ROUTE)
    if start is B:  # the same route driven the other way along each segment
        segments = tuple(reversed(ROUTE_SEGMENTS))
        route = plan((3, B, FWD), (2, B, REV), (1, B, REV))
    driver = driver_on(segments, start, vehicle_type)
    reasons: Counter[str] = Counter()
    in_arrays = 0
    before_hand_back: Counter[str] = Counter()  # reasons whose step before went through the arrays
    last_in_arrays = False
    for _ in range(400):
        armed = copy.copy(driver)
        cruise = FleetCruise([armed])
        cruise.arm(0, route)
        was_armed = armed.cruise_terms(route) is not None
        cruised, others = cruise.step(DT)
        ids, states = cruised.ids, cruised.states
        own = driver.cruise(route, DT)
        if ids:
            in_arrays += 1
            assert own is not None and states == [own[0]]
            assert armed.kinematics() != driver.kinematics()  # the armed copy's fields wait for release
            cruise.release(0)
            assert armed.kinematics() == driver.kinematics()
            last_in_arrays = True
            continue
        assert others == [0]
        if was_armed:
            reason = hand_back_reason(armed, route)
            reasons[reason] += 1
            if last_in_arrays:
                before_hand_back[reason] += 1
            assert reason == "another piece" or own is None
        if own is None:
            route = driver.step(route, DT).plan
        last_in_arrays = False
        if not route.legs or (len(route.legs) == 1 and driver._profile is None and driver.speed == 0.0):
            break
    assert in_arrays > 100
    assert set(before_hand_back) == {"profile ends", "leg ends", "another piece"}, reasons


def test_a_vehicle_whose_plan_changed_is_handed_back_before_the_step() -> None:
    driver = driver_on((straight(1, (0.0, 0.0), (20.0, 0.0)), straight(2, (20.0, 0.0), (40.0, 0.0))))
    route = plan((1, F, FWD))
    for _ in range(5):
        route = driver.step(route, DT).plan
    cruise = FleetCruise([driver])
    cruise.arm(0, route)
    cruise.forget([1], {1: route}.__getitem__)  # the same plan object: stays armed
    assert cruise.step(DT).cruised.ids == [1]
    longer = plan((1, F, FWD), (2, F, FWD))
    cruise.forget([1], {1: longer}.__getitem__)
    before = copy.copy(driver)
    cruise.release(0)
    before_fields = driver.kinematics()
    cruise.arm(0, route)
    cruise.forget([1], {1: longer}.__getitem__)
    cruised, others = cruise.step(DT)
    ids = cruised.ids
    assert (ids, others) == ([], [0])
    assert driver.kinematics() == before_fields != before.kinematics()


def test_the_released_mapping_hands_out_drivers_up_to_date_and_no_longer_armed() -> None:
    driver = driver_on((straight(1, (0.0, 0.0), (20.0, 0.0)),))
    twin = driver_on((straight(1, (0.0, 0.0), (20.0, 0.0)),))
    route = plan((1, F, FWD))
    for _ in range(3):
        route = driver.step(route, DT).plan
        twin.step(route, DT)
    cruise = FleetCruise([driver])
    cruise.arm(0, route)
    for _ in range(10):
        assert cruise.step(DT).cruised.ids == [1]
        twin.cruise(route, DT)
    assert driver.odometer != twin.odometer  # still in the arrays
    assert cruise.released[1] is driver
    assert driver.kinematics() == twin.kinematics()
    assert (list(cruise.released), len(cruise.released)) == ([1], 1)
    assert cruise.step(DT).others == [0]  # handed back: its driver steps it now


def test_release_all_brings_every_odometer_up_to_date() -> None:
    segments = (straight(1, (0.0, 0.0), (20.0, 0.0)),)
    drivers = [driver_on(segments), driver_on(segments)]
    route = plan((1, F, FWD))
    for driver in drivers:
        driver.step(route, DT)
    cruise = FleetCruise(drivers[:1])
    cruise.arm(0, route)
    for _ in range(5):
        cruise.step(DT)
        drivers[1].cruise(route, DT)
    cruise.release_all()
    assert drivers[0].odometer == drivers[1].odometer > 0.0


def test_a_vehicle_slowing_down_to_a_lower_limit_is_left_to_its_driver() -> None:
    driver = driver_on((straight(1, (0.0, 0.0), (40.0, 0.0)),))
    route = plan((1, F, FWD))
    for _ in range(20):
        route = driver.step(route, DT).plan
    driver.limit_speed(0.3 * driver.speed)
    assert isinstance(driver._profile, SlowDownProfile)
    cruise = FleetCruise([driver])
    cruise.arm(0, route)
    assert cruise.step(DT).cruised.ids == []
    driver.cruise(route, DT)  # its own cruise goes on slowing down
    assert driver.speed < 0.99 * driver.type.max_speed


def test_unbatched_cruise_arms_nothing() -> None:
    driver = driver_on((straight(1, (0.0, 0.0), (20.0, 0.0)),))
    route = driver.step(plan((1, F, FWD)), DT).plan
    cruise = FleetCruise([driver], batched=False)
    cruise.arm(0, route)
    cruised, others = cruise.step(DT)
    assert (cruised.ids, cruised.states, others) == ([], [], [0])


def test_a_vehicle_at_rest_or_turning_is_not_armed() -> None:
    # A corner over the joint angle tolerance: an in-place vehicle stops there and turns.
    segments = (straight(1, (0.0, 0.0), (2.0, 0.0)), straight(2, (2.0, 0.0), (2.0, 2.0)))
    driver = driver_on(segments)
    route = plan((1, F, FWD), (2, F, FWD))
    assert driver.cruise_terms(route) is None  # at rest
    turning = False
    for _ in range(100):
        route = driver.step(route, DT).plan
        if driver._turn_left > 0.0:
            turning = True
            assert driver.cruise_terms(route) is None
    assert turning and math.isclose(driver.heading, math.pi / 2)


def _runs(scenario: Scenario, planner: type[ReservingPlanner] | type[BFSPlanner]) -> list[object]:
    return [same_run(run_switched(scenario, planner(), batched=batched)) for batched in (True, False)]


@pytest.mark.parametrize("suite_path", SUITES, ids=[p.name.split(".")[0] for p in SUITES])
def test_every_shipped_scenario_runs_the_same_batched_and_one_by_one(suite_path: Path) -> None:
    suite = load_suite(suite_path)
    specs = [spec for spec in suite.scenarios if spec.generate is None]
    assert specs
    for spec in specs:
        scenario = load_scenario(spec, suite)
        for planner in (ReservingPlanner, BFSPlanner):
            batched, one_by_one = _runs(scenario, planner)
            assert batched == one_by_one, (spec.name, planner.__name__)


def test_a_braking_vehicle_is_handed_back_on_the_step_its_profile_ends_and_not_before() -> None:
    """Mid-leg, braking to a halt: its profile ends exactly at the end of the eighth step of 1/8 s (all
    exact binary fractions), and that step is its driver's; the seven before are the arrays'."""
    dt = 0.125
    driver = driver_on((straight(1, (0.0, 0.0), (40.0, 0.0)),))
    route = plan((1, F, FWD))
    for _ in range(8):  # a = 0.5 m/s² for 1 s from rest: exactly 0.5 m/s
        route = driver.step(route, dt).plan
    assert driver.speed == 0.5
    assert driver.halt() == 1.0  # braking at a from 0.5 m/s: at rest after exactly 1 s
    cruise = FleetCruise([driver])
    cruise.arm(0, route)
    for _ in range(7):
        assert cruise.step(dt).cruised.ids == [1]
    assert cruise.step(dt).others == [0]
    assert driver.step(route, dt).distance > 0.0 and driver.speed == 0.0


@pytest.mark.parametrize(("smallest", "in_arrays"), [(2, True), (3, False)])
def test_a_fleet_is_stepped_in_arrays_from_the_smallest_size_that_pays(
    monkeypatch: pytest.MonkeyPatch, smallest: int, in_arrays: bool
) -> None:
    """Below ``FleetCruise.SMALLEST`` vehicles the arrays' fixed cost per step outweighs what they save:
    every vehicle is stepped by its driver (the same run either way)."""
    taken: list[int] = []
    original = FleetCruise._take_pending

    def counted(self: FleetCruise) -> None:
        taken.extend(self._pending)
        original(self)

    monkeypatch.setattr(FleetCruise, "_take_pending", counted)
    monkeypatch.setattr(FleetCruise, "SMALLEST", smallest)
    suite = load_suite(next(p for p in SUITES if p.name.startswith("examples")))
    scenario = load_scenario(next(s for s in suite.scenarios if s.name == "crossing"), suite)
    assert len(scenario.vehicles) == 2
    run_scenario(scenario, ReservingPlanner(), keep_trace=False)
    assert bool(taken) is in_arrays


def test_a_vehicle_about_to_reach_the_end_of_its_leg_or_profile_is_not_armed() -> None:
    """Armed, it would most likely be handed back within ``AHEAD`` steps: its driver steps it. With a
    little more room than that many steps' length at its speed, it is armed and cruises."""
    driver = driver_on((straight(1, (0.0, 0.0), (7.0, 0.0)), straight(2, (7.0, 0.0), (9.0, 0.0))))
    route = plan((1, F, FWD), (2, F, FWD))
    outcomes: Counter[str] = Counter()
    for _ in range(400):
        armed = copy.copy(driver)
        cruise = FleetCruise([armed])
        cruise.step(DT)  # nothing armed yet: the step's length is known from now on
        cruise.arm(0, route)
        in_arrays = cruise.step(DT).cruised.ids == [1]
        profile = driver._profile
        ahead = FleetCruise.AHEAD * DT  # the steps looked ahead, as long as the last
        if profile is not None and armed.cruise_terms(route) is not None:
            room = driver._headings.track(route.legs[0].segment, F).length - EPS - driver.distance
            ends = driver._elapsed + ahead >= profile.stop_time
            if ends or room <= driver.speed * ahead:
                assert not in_arrays
                outcomes["profile ends" if ends else "leg ends"] += 1
            elif room <= driver.speed * (ahead + 0.5 * DT):
                assert in_arrays == (copy.copy(driver).cruise(route, DT) is not None)
                outcomes["armed near the end"] += in_arrays
        if driver.cruise(route, DT) is None:
            route = driver.step(route, DT).plan
        if not route.legs or (len(route.legs) == 1 and driver._profile is None and driver.speed == 0.0):
            break
    assert outcomes["leg ends"] and outcomes["profile ends"] and outcomes["armed near the end"], outcomes
