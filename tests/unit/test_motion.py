"""Motion along fixed legs (SPEC §8): stop times against the thesis's closed forms, stop points, turns."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from scenario_factory import AGV, TUGGER, make_scenario

from fleetsim.enums import Direction, Progress, Shape, Traverse
from fleetsim.layout import Segment, build_layout
from fleetsim.motion.driver import Driver
from fleetsim.motion.track import HeadingTable
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.scenario import Vehicle, VehicleType
from fleetsim.sim.loop import run_scenario

DT = 0.1
A, VMAX = 0.5, 1.0  # the default vehicle type's acceleration and top speed
F, B = Traverse.FORWARD, Traverse.BACKWARD
FWD, REV = Progress.FORWARD, Progress.REVERSE


def straight(sid: int, start: tuple[float, float], end: tuple[float, float]) -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, (start, end))


def driver_on(segments: tuple[Segment, ...], vehicle_type: VehicleType = AGV) -> Driver:
    layout = build_layout(segments, vehicle_radius=0.3)
    first = segments[0]
    heading = math.atan2(first.waypoints[1][1] - first.waypoints[0][1], first.waypoints[1][0] - first.waypoints[0][0])
    return Driver(Vehicle(1, first.id, F, FWD, vehicle_type), layout, HeadingTable(layout), heading)


def plan(*legs: tuple[int, Traverse, Progress]) -> FleetPlan:
    return FleetPlan(1, tuple(FleetLeg(s, t, p, fixed=True) for s, t, p in legs))


def time_to_stop(driver: Driver, route: FleetPlan, start: float = 0.0, limit: float = 60.0) -> float:
    """Step until the vehicle has moved and come to rest; the end time of that step."""
    now = start
    moved = False
    while now < limit:
        motion = driver.step(route, DT)
        route = motion.plan
        now += DT
        moved = moved or motion.moved
        if moved and driver.speed == 0.0 and not motion.moved:
            return now - DT  # the step before was the one that ended at rest
    raise AssertionError("the vehicle never stopped")


def eq12(v0: float, s: float) -> float:
    vp = math.sqrt(A * s + v0 * v0 / 2)
    assert vp <= VMAX
    return (2 * vp - v0) / A


def eq14(v0: float, s: float) -> float:
    assert math.sqrt(A * s + v0 * v0 / 2) > VMAX
    return (v0 * v0 - 2 * v0 * VMAX + 2 * VMAX * VMAX + 2 * A * s) / (2 * A * VMAX)


@pytest.mark.parametrize(
    ("length", "expected"), [(1.5, eq12(0.0, 1.5)), (8.0, eq14(0.0, 8.0))], ids=["triangle", "trapezoid"]
)
def test_stop_time_from_rest_matches_the_closed_form(length: float, expected: float) -> None:
    driver = driver_on((straight(1, (0.0, 0.0), (length, 0.0)),))
    assert time_to_stop(driver, plan((1, F, FWD))) == pytest.approx(expected, abs=DT)
    assert driver.distance == pytest.approx(length)


def _moving_start(first_length: float, more_length: float, at: float) -> tuple[float, float, Driver]:
    """Drive a ``first_length`` leg; at time ``at`` a second leg is fixed. Returns (stop time, v0, driver)."""
    driver = driver_on(
        (
            straight(1, (0.0, 0.0), (first_length, 0.0)),
            straight(2, (first_length, 0.0), (first_length + more_length, 0.0)),
        )
    )
    one = plan((1, F, FWD))
    now = 0.0
    for _ in range(round(at / DT)):
        one = driver.step(one, DT).plan
        now += DT
    v0 = driver.speed
    both = plan((1, F, FWD), (2, F, FWD))
    return time_to_stop(driver, both, start=now) - at, v0, driver


def test_stop_time_from_a_moving_start_matches_eq12_when_legs_are_added() -> None:
    elapsed, v0, _ = _moving_start(1.0, 0.5, at=1.0)
    assert v0 == pytest.approx(0.5)
    remaining = 1.5 - 0.25  # 1.0 + 0.5 m in all, 0.25 m driven in the first second
    assert elapsed == pytest.approx(eq12(v0, remaining), abs=DT)


def test_stop_time_from_a_moving_start_matches_eq14_when_legs_are_added() -> None:
    elapsed, v0, driver = _moving_start(4.0, 4.0, at=2.0)
    assert v0 == pytest.approx(1.0)
    assert elapsed == pytest.approx(eq14(v0, 8.0 - 1.0), abs=DT)
    assert driver.distance == pytest.approx(4.0)  # at the end of the second leg, which is now the current one


def test_distance_per_step_is_the_area_under_the_profile() -> None:
    driver = driver_on((straight(1, (0.0, 0.0), (8.0, 0.0)),))
    route = plan((1, F, FWD))
    for _ in range(10):  # one second of acceleration from rest: a·t²/2
        route = driver.step(route, DT).plan
    assert driver.distance == pytest.approx(0.5 * A * 1.0**2, abs=1e-12)
    assert driver.speed == pytest.approx(A * 1.0)


def _cusp() -> tuple[Segment, ...]:
    # 1 runs east to (4, 0); 2 leaves (4, 0) back towards the west-north-west: a cusp.
    return (straight(1, (0.0, 0.0), (4.0, 0.0)), straight(2, (4.0, 0.0), (0.5, 1.5)))


def test_curve_vehicle_stops_and_reverses_at_a_cusp_without_turning() -> None:
    driver = driver_on(_cusp(), TUGGER)
    route = plan((1, F, FWD), (2, F, REV))
    samples = []
    headings = []
    for _ in range(200):
        motion = driver.step(route, DT)
        route = motion.plan
        samples.append((route.legs[0].segment, driver.speed))
        headings.append(driver.heading)
    first_on_2 = next(i for i, (segment, _) in enumerate(samples) if segment == 2)
    # It came to rest at the cusp within the step it crossed, so it re-accelerated for less than a step.
    assert samples[first_on_2][1] <= A * DT + 1e-9
    assert samples[first_on_2 - 1][1] <= A * DT + 1e-9  # and was braking to a stop just before
    assert route.legs[0].segment == 2 and driver.progress is REV
    assert driver.distance == pytest.approx(_cusp()[1].length)
    # Backing out along segment 2 the nose still points roughly east: no turn in place happened.
    assert abs(math.remainder(driver.heading - _cusp()[1].pose_at(0.0, F)[2] - math.pi, math.tau)) < 1e-9
    assert max(abs(h) for h in headings) < math.radians(30)


def test_in_place_vehicle_stops_and_turns_at_a_corner_for_angle_over_turn_rate() -> None:
    segments = (straight(1, (0.0, 0.0), (4.0, 0.0)), straight(2, (4.0, 0.0), (4.0, 4.0)))
    driver = driver_on(segments, AGV)
    route = plan((1, F, FWD), (2, F, FWD))
    arrive = time_to_stop(driver, plan((1, F, FWD)))  # time to reach the corner alone
    driver = driver_on(segments, AGV)
    turning_steps = []
    now = 0.0
    while now < 30.0:
        motion = driver.step(route, DT)
        route = motion.plan
        now += DT
        if motion.turned and motion.distance == 0.0:
            turning_steps.append((now, driver.heading))
    duration = len(turning_steps) * DT
    assert duration == pytest.approx(90.0 / AGV.turn_rate, abs=DT + 1e-9)  # 90° at 90°/s
    assert turning_steps[0][0] == pytest.approx(arrive + DT, abs=DT)
    middle = turning_steps[len(turning_steps) // 2][1]
    assert 0.0 < middle < math.pi / 2  # turning counter-clockwise from east to north
    assert driver.heading == pytest.approx(math.pi / 2)
    assert route.legs[0].segment == 2 and driver.distance == pytest.approx(4.0)


def test_driving_on_to_a_smooth_continuation_does_not_stop() -> None:
    segments = (straight(1, (0.0, 0.0), (4.0, 0.0)), straight(2, (4.0, 0.0), (8.0, 0.0)))
    driver = driver_on(segments)
    route = plan((1, F, FWD), (2, F, FWD))
    speeds = []
    while route.legs[0].segment == 1:
        motion = driver.step(route, DT)
        route = motion.plan
        speeds.append(driver.speed)
    assert speeds[-1] > 0.9  # still at top speed when entering segment 2: no stop at the joint
    assert time_to_stop(driver, route, start=len(speeds) * DT) == pytest.approx(eq14(0.0, 8.0), abs=DT)


def test_passed_legs_are_dropped_and_the_entered_legs_reported() -> None:
    segments = (
        straight(1, (0.0, 0.0), (1.0, 0.0)),
        straight(2, (1.0, 0.0), (2.0, 0.0)),
        straight(3, (2.0, 0.0), (3.0, 0.0)),
    )
    driver = driver_on(segments)
    route = plan((1, F, FWD), (2, F, FWD), (3, F, FWD))
    entered = []
    for _ in range(100):
        motion = driver.step(route, DT)
        route = motion.plan
        entered += [leg.segment for leg in motion.entered]
    assert entered == [2, 3]
    assert [leg.segment for leg in route.legs] == [3]


def test_a_vehicle_moves_only_along_fixed_legs() -> None:
    segments = (straight(1, (0.0, 0.0), (4.0, 0.0)), straight(2, (4.0, 0.0), (8.0, 0.0)))
    driver = driver_on(segments)
    route = FleetPlan(1, (FleetLeg(1, F, FWD, fixed=True), FleetLeg(2, F, FWD, fixed=False)))
    for _ in range(300):
        route = driver.step(route, DT).plan
    assert route.legs[0].segment == 1 and driver.distance == pytest.approx(4.0) and driver.speed == 0.0


def test_tasks_complete_in_queue_order(tmp_path: Path) -> None:
    segments = tuple(straight(i, (4.0 * (i - 1), 0.0), (4.0 * i, 0.0)) for i in range(1, 5))
    scenario = make_scenario(tmp_path, segments, "1,1,forward,,\n", "1,2,\n1,4,\n1,3,\n")
    result = run_scenario(scenario, __import__("fleetsim.planners", fromlist=["ReservingPlanner"]).ReservingPlanner())
    assert result.status == "passed", [f.message for f in result.failures]
    lines = result.trace.lines if result.trace else []
    completions = [
        event[1] for line in lines[1:] for event in __import__("json").loads(line)[3] if event[0] == "complete"
    ]
    assert completions == [1, 2, 3]  # task 2 (segment 4) before task 3 (segment 3): queue order, not distance


def _driven_with_cruise_first(driver: Driver, route: FleetPlan, steps: int) -> list[tuple[object, ...]]:
    """Each step as the loop does it: the plain cruise when there is one, else the general step."""
    seen = []
    cruises = 0
    for _ in range(steps):
        cruised = driver.cruise(route, DT)
        if cruised is not None:
            cruises += 1
            seen.append((route, cruised[0], driver.odometer))
            continue
        motion = driver.step(route, DT)
        route = motion.plan
        seen.append((route, driver.state(route) if route.legs else None, driver.odometer))
    assert cruises > steps // 3  # the short path was taken, and often
    return seen


def _driven_with_step_only(driver: Driver, route: FleetPlan, steps: int) -> list[tuple[object, ...]]:
    seen = []
    for _ in range(steps):
        motion = driver.step(route, DT)
        route = motion.plan
        seen.append((route, motion.state or (driver.state(route) if route.legs else None), driver.odometer))
    return seen


@pytest.mark.parametrize("vehicle_type", [AGV, TUGGER])
def test_the_plain_cruise_gives_exactly_what_the_general_step_gives(vehicle_type: VehicleType) -> None:
    """The loop's short path (``Driver.cruise``) leaves every state, plan and odometer reading equal to
    driving by ``step`` alone: through acceleration, cruising, smooth joints, a cusp and the stop."""
    segments = (*_cusp(), straight(3, (0.5, 1.5), (-6.0, 1.5 + 6.5 * 3.0 / 7.0)))
    legs = ((1, F, FWD), (2, F, REV), (3, F, REV))
    by_cruise = _driven_with_cruise_first(driver_on(segments, vehicle_type), plan(*legs), 250)
    by_step = _driven_with_step_only(driver_on(segments, vehicle_type), plan(*legs), 250)
    assert by_cruise == by_step


def test_cruise_declines_without_changing_anything_when_the_step_is_not_a_plain_cruise() -> None:
    segments = (straight(1, (0.0, 0.0), (4.0, 0.0)), straight(2, (4.0, 0.0), (8.0, 0.0)))
    driver = driver_on(segments)
    route = plan((1, F, FWD))
    assert driver.cruise(route, DT) is None  # at rest: no speed profile yet
    assert (driver.distance, driver.speed, driver.odometer) == (0.0, 0.0, 0.0)
    for _ in range(3):
        route = driver.step(route, DT).plan
    assert driver.cruise(route, DT) is not None  # the same plan, mid-leg: a plain cruise
    longer = plan((1, F, FWD), (2, F, FWD))  # a new fixed leg from outside: the general step re-plans
    before = (driver.distance, driver.speed, driver.odometer, driver.x, driver.y, driver.heading)
    assert driver.cruise(longer, DT) is None
    assert (driver.distance, driver.speed, driver.odometer, driver.x, driver.y, driver.heading) == before
