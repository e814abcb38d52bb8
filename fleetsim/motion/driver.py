"""Moving one vehicle along its fixed legs over a time step (SPEC §8; thesis section 6.5).

The distance a vehicle may drive is the rest of its current leg plus the following fixed legs, up to the
first *stop point*: a junction where its progress direction flips or its heading changes by more than
the joint angle tolerance (it must turn in place). A speed profile (:class:`SpeedProfile`) runs to the
end of that distance: ``till_end`` when it ends with the fixed legs, ``till_stop`` when it ends at a stop
point before them. New fixed legs under a ``till_end`` profile re-plan it from the current speed; a
``till_stop`` profile runs to its stop first. At a stop point the vehicle takes the next leg's progress
and, if its heading must change, turns in place at its type's ``turn_rate``; then it drives on.

Within a step, time is spent phase by phase (driving, turning, driving on), so the distance per step is
the exact area under the profile and nothing waits for the next step without reason.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from itertools import pairwise
from typing import NamedTuple

from fleetsim.enums import Disturbed, Progress
from fleetsim.layout.layout import Layout
from fleetsim.motion.slowdown import Profile, plan_profile
from fleetsim.motion.track import HeadingTable, Track, nose, wrap
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.snapshot import VehicleState
from fleetsim.scenario import Vehicle

__all__ = ["EPS", "Driver", "StepMotion"]

EPS = 1e-9  # metres or seconds below which a remainder is rounding noise
# Makes a named tuple from a full tuple of its fields without the generated __new__'s keyword handling:
# a fifth of the cost, for the state and motion made for every moving vehicle on every step.
_new = tuple.__new__
# Python 3.11's EnumType.__getattr__ makes every ``Progress.REVERSE`` cost about 0.2 µs (a generic
# attribute hook; 3.12 removed it), so the per-step path reads the member from a module constant.
_REVERSE = Progress.REVERSE


class StepMotion(NamedTuple):
    """What a step did to one vehicle: its plan with passed legs dropped, the legs it entered, how far.

    A named tuple: one is made for every moving vehicle on every step.
    """

    plan: FleetPlan
    entered: tuple[FleetLeg, ...]
    distance: float
    turned: bool
    state: VehicleState | None = None  # the state after the step, when the step already made it

    @property
    def moved(self) -> bool:
        return self.distance > 0.0 or self.turned


class Driver:
    """The motion state of one vehicle; the simulation owns it and steps it once per time step."""

    # Slots: every moving vehicle's driver is read field by field on every step, and a large fleet's
    # drivers should sit compactly in memory rather than each beside a dict of its own.
    __slots__ = (
        "_elapsed", "_headings", "_last_out", "_layout", "_on", "_profile", "_stretch", "_till_stop",
        "_tolerance", "_travelled", "_turn_left", "_turn_rate", "_turn_sign", "_turn_target", "distance",
        "disturbed", "halted", "heading", "id", "odometer", "progress", "speed", "speed_limit", "still_on",
        "type", "x", "y",
    )  # fmt: skip

    def __init__(self, vehicle: Vehicle, layout: Layout, headings: HeadingTable, heading: float) -> None:
        self.id = vehicle.id
        self.type = vehicle.type
        self._layout = layout
        self._headings = headings
        self._tolerance = math.radians(layout.joint_angle_tolerance)
        self._turn_rate = math.radians(vehicle.type.turn_rate)
        self.progress = vehicle.progress
        self.distance = 0.0  # along the current leg
        self.speed = 0.0
        self.heading = heading  # where the nose points
        self.odometer = 0.0
        self._profile: Profile | None = None
        # Disturbances (fleetsim.sim.disturbances): a halted vehicle brakes to rest and stays; a slowed one
        # keeps to ``speed_limit``. ``disturbed`` is what its state shows the planner.
        self.halted = False
        self.speed_limit = vehicle.type.max_speed
        self.disturbed: Disturbed | None = None
        self._elapsed = 0.0
        self._till_stop = False
        self._turn_left = 0.0  # seconds of turning in place still to do
        self._turn_target = heading
        self._turn_sign = 1.0  # +1 counter-clockwise, -1 clockwise
        # The plan this vehicle last found nothing to drive on: while its plan is this same object (plans
        # are immutable), a step leaves it where it is, so the loop skips it without asking.
        self.still_on: FleetPlan | None = None
        # Where the drivable stretch of a plan ends, measured from the start of its first leg.
        self._stretch: tuple[FleetPlan | None, float, bool] = (None, 0.0, False)
        self._travelled = 0.0  # distance_at(elapsed) of the current profile
        # The plan whose fixed legs the profile accounts for: the one the last step returned or checked.
        self._last_out: FleetPlan | None = None
        self._on: tuple[FleetLeg, Track] | None = None  # the current leg and its track
        start = layout.segments[vehicle.start_segment]
        self.x, self.y, _ = start.pose_at(0.0, vehicle.traverse)  # the position, kept with the heading

    # -- the distance available ---------------------------------------------------------------------

    def _length(self, leg: FleetLeg) -> float:
        return self._layout.segments[leg.segment].length

    def stops_between(self, before: FleetLeg, after: FleetLeg) -> bool:
        """A stop point: the progress flips or the nose must turn more than the tolerance."""
        if before.progress is not after.progress:
            return True
        return abs(self._headings.turn_between(before, after)) > self._tolerance

    def reach(self, legs: list[FleetLeg] | tuple[FleetLeg, ...]) -> tuple[float, bool]:
        """Metres drivable from here without stopping, and whether a stop point (not the end) ends them."""
        total, till_stop = self._stretch_of(legs)
        return max(total - self.distance, 0.0), till_stop

    def _stretch_of(self, legs: list[FleetLeg] | tuple[FleetLeg, ...]) -> tuple[float, bool]:
        total = self._length(legs[0])
        for before, after in pairwise(legs):
            if not after.fixed:
                return total, False
            if self.stops_between(before, after):
                return total, True
            total += self._length(after)
        return total, False

    def _reach_in(self, plan: FleetPlan) -> tuple[float, bool]:
        """:meth:`reach` for a plan, remembering the plan's stretch while the plan object stays the same."""
        cached, total, till_stop = self._stretch
        if cached is not plan:
            total, till_stop = self._stretch_of(plan.legs)
            self._stretch = (plan, total, till_stop)
        return max(total - self.distance, 0.0), till_stop

    # -- one step ------------------------------------------------------------------------------------

    def step(self, plan: FleetPlan, dt: float) -> StepMotion:
        if self.still_on is not None:
            if self.still_on is plan:
                return StepMotion(plan, (), 0.0, False, None)
            self.still_on = None
        if self._profile is not None:
            # Only a plan from outside (not the one this driver returned) can bring new fixed legs.
            if plan is not self._last_out and not self._till_stop and not self.halted:
                reach, till_stop = self._reach_in(plan)
                if reach > self._remaining() + EPS:  # new fixed legs: re-plan from the current speed
                    self._start(reach, till_stop)
                self._last_out = plan
            cruised = self.cruise(plan, dt)
            if cruised is not None:
                return _new(StepMotion, (plan, (), cruised[1], False, cruised[0]))
        legs = list(plan.legs)
        entered: list[FleetLeg] = []
        driven = 0.0
        turned = False
        budget = dt
        while budget > EPS:
            if self.halted and self._profile is None:
                break  # at rest (or its turn frozen) until the disturbance ends
            if self._turn_left > 0.0:
                budget -= self._turn(budget)
                turned = True
            elif self._profile is not None:
                spent, distance = self._drive(budget, legs, entered)
                budget -= spent
                driven += distance
            elif self._at_leg_end(legs) and len(legs) > 1 and legs[1].fixed:
                self._cross(legs, entered)
            else:
                reach, till_stop = self.reach(legs)
                if reach <= EPS:
                    break  # nothing fixed ahead: wait
                self._start(reach, till_stop)
        self.odometer += driven
        new_plan = plan if len(legs) == len(plan.legs) else FleetPlan(plan.vehicle_id, tuple(legs))
        motion = StepMotion(new_plan, tuple(entered), driven, turned, None)
        if not motion.moved and not entered and self._profile is None and self._turn_left == 0.0:
            self.still_on = new_plan
        self._last_out = new_plan
        return motion

    def cruise(self, plan: FleetPlan, dt: float) -> tuple[VehicleState, float] | None:
        """The commonest step, done directly: the profile goes on all step long and the leg does not end.
        The new state and the distance driven; ``None`` when the step is anything else, without changing
        anything (then :meth:`step` does the step).

        Exactly what the general step would compute for such a step, without its bookkeeping, and the new
        state made from what was just computed; the point is located as :meth:`Segment.pose_at` does
        (same arithmetic) on the leg's precomputed :class:`Track`. The loop tries this first for every
        vehicle not standing still (:attr:`still_on`); it runs 10^5 times a simulated minute in a large
        fleet, so it reads fields directly.
        """
        profile = self._profile
        if profile is None or self._turn_left != 0.0 or (plan is not self._last_out and not self._till_stop):
            return None  # at rest, turning, or a plan from outside that may bring new fixed legs
        t1 = self._elapsed + dt
        if t1 >= profile.stop_time:
            return None
        travelled, speed = profile.running_at(t1)
        distance = travelled - self._travelled
        if distance <= 0.0:
            return None  # rounding left nothing to drive: the general step says so
        leg = plan.legs[0]
        on = self._on
        track = on[1] if on is not None and on[0] is leg else self._track(leg)
        along = self.distance + distance
        if along >= track.length - EPS:
            return None
        self._travelled = travelled
        self._elapsed = t1
        self.distance = along
        self.speed = speed
        self.odometer += distance
        self._last_out = plan
        coordinate = track.length - along if track.backward else along
        start, ax, ay, dx, dy, piece, _, forward, reverse = track.pieces[
            track.piece_of[bisect_right(track.along, coordinate)]
        ]
        fraction = (coordinate - start) / piece if piece > 0 else 0.0
        x = self.x = ax + fraction * dx
        y = self.y = ay + fraction * dy
        heading = self.heading = reverse if leg.progress is _REVERSE else forward
        state = _new(
            VehicleState,
            (self.id, leg.segment, leg.traverse, self.progress, along, speed, x, y, heading, self.type, self.disturbed),
        )
        return state, distance

    def cruise_terms(self, plan: FleetPlan) -> tuple[Profile, Track] | None:
        """The profile and the track of the current leg when the next step may be a :meth:`cruise` on
        ``plan`` (the plan the last step returned): ``None`` at rest, turning or standing still."""
        if self._profile is None or self._turn_left != 0.0 or plan is not self._last_out or self.still_on is not None:
            return None
        return self._profile, self._track(plan.legs[0])

    def kinematics(self) -> tuple[float, float, float, float, float, float, float, float]:
        """What :meth:`cruise` changes: elapsed and travelled on the profile, odometer, then as in the
        state: distance along the leg, speed, x, y, heading (for
        :class:`~fleetsim.motion.fleet_cruise.FleetCruise`)."""
        return (
            self._elapsed, self._travelled, self.odometer, self.distance, self.speed, self.x, self.y, self.heading
        )  # fmt: skip

    def take_kinematics(
        self,
        elapsed: float,
        travelled: float,
        odometer: float,
        distance: float,
        speed: float,
        x: float,
        y: float,
        heading: float,
    ) -> None:
        """Take back :meth:`kinematics` after cruise steps taken elsewhere."""
        self._elapsed, self._travelled, self.odometer, self.distance = elapsed, travelled, odometer, distance
        self.speed, self.x, self.y, self.heading = speed, x, y, heading

    def _track(self, leg: FleetLeg) -> Track:
        """The track of the leg the vehicle is on, kept while it stays on that leg."""
        on = self._on
        if on is None or on[0] is not leg:
            on = self._on = (leg, self._headings.track(leg.segment, leg.traverse))
        return on[1]

    def _remaining(self) -> float:
        assert self._profile is not None
        return self._profile.distance - self._travelled

    def _start(self, reach: float, till_stop: bool) -> Profile:
        profile = self._profile = plan_profile(self.speed, self.type.acceleration, self.speed_limit, reach)
        self._elapsed = 0.0
        self._travelled = 0.0
        self._till_stop = till_stop
        return profile

    def _at_leg_end(self, legs: list[FleetLeg]) -> bool:
        return self.distance >= self._length(legs[0]) - EPS

    def _drive(self, budget: float, legs: list[FleetLeg], entered: list[FleetLeg]) -> tuple[float, float]:
        """Follow the profile for up to ``budget`` seconds; the time spent and the distance driven."""
        profile = self._profile
        assert profile is not None
        t0 = self._elapsed
        t1 = min(t0 + budget, profile.stop_time)
        travelled = profile.distance_at(t1)
        distance = max(travelled - self._travelled, 0.0)  # the exact area under the profile over [t0, t1]
        self._travelled = travelled
        self._elapsed = t1
        self._move(distance, legs, entered)
        if t1 >= profile.stop_time:
            self._profile = None
            self.speed = 0.0
        else:
            self.speed = profile.speed_at(t1)
        return t1 - t0, distance

    def _move(self, distance: float, legs: list[FleetLeg], entered: list[FleetLeg]) -> None:
        """Advance along the legs; smooth joints are crossed on the move, passed legs dropped."""
        self.distance += distance
        while self._at_leg_end(legs):
            length = self._length(legs[0])
            if len(legs) > 1 and legs[1].fixed and not self.stops_between(legs[0], legs[1]):
                self.distance = max(self.distance - length, 0.0)
                legs.pop(0)
                entered.append(legs[0])
                continue
            self.distance = length  # the end of what may be driven now
            break
        leg = legs[0]
        self.x, self.y, travel = self._layout.segments[leg.segment].pose_at(self.distance, leg.traverse)
        self.heading = nose(travel, leg.progress)

    def _cross(self, legs: list[FleetLeg], entered: list[FleetLeg]) -> None:
        """At rest at a leg's end with the next leg fixed: enter it, take its progress, turn if needed."""
        turn = self._headings.turn_between(legs[0], legs[1])
        legs.pop(0)
        entered.append(legs[0])
        self.distance = 0.0
        self.progress = legs[0].progress
        target = wrap(self.heading + turn)
        if abs(turn) > self._tolerance:
            self._turn_left = abs(turn) / self._turn_rate
            self._turn_target = target
            self._turn_sign = math.copysign(1.0, turn)
        else:
            self.heading = target

    def _turn(self, budget: float) -> float:
        """Turn in place for up to ``budget`` seconds towards the target heading; the time spent."""
        spent = min(budget, self._turn_left)
        self._turn_left -= spent
        if self._turn_left <= EPS:
            self._turn_left = 0.0
            self.heading = self._turn_target
        else:
            self.heading = wrap(self._turn_target - self._turn_sign * self._turn_left * self._turn_rate)
        return spent

    # -- disturbances ---------------------------------------------------------------------------------

    def halt(self) -> float:
        """Brake to rest at the deceleration (within the distance left) and stay until :meth:`release`;
        a turn in place freezes. The seconds until at rest."""
        self.halted = True
        if self._profile is None:
            return 0.0
        a = self.type.acceleration
        braking = min(self._remaining(), self.speed * self.speed / (2.0 * a))
        return self._start(braking, self._till_stop).stop_time

    def release(self) -> None:
        self.halted = False
        self.still_on = None  # may drive again what it stood still on

    def limit_speed(self, speed_limit: float) -> None:
        """Keep to ``speed_limit`` from now on (braking down to it at the deceleration)."""
        self.speed_limit = speed_limit
        self.still_on = None
        if self._profile is not None and not self.halted:
            self._start(self._remaining(), self._till_stop)

    # -- what a planner sees -------------------------------------------------------------------------

    def state(self, plan: FleetPlan) -> VehicleState:
        leg = plan.legs[0]
        x, y, _ = self._layout.segments[leg.segment].pose_at(self.distance, leg.traverse)
        return self._state(leg, x, y)

    def moved_state(self, plan: FleetPlan) -> VehicleState:
        """:meth:`state` after a step that drove: the position computed while driving is reused."""
        leg = plan.legs[0]
        if self.distance == 0.0 and self._turn_left == 0.0:
            return self.state(plan)  # crossed onto a new leg at rest: no position computed yet
        return self._state(leg, self.x, self.y)

    def _state(self, leg: FleetLeg, x: float, y: float) -> VehicleState:
        return VehicleState(
            id=self.id,
            segment=leg.segment,
            traverse=leg.traverse,
            progress=self.progress,
            distance=self.distance,
            speed=self.speed,
            x=x,
            y=y,
            heading=self.heading,
            type=self.type,
            disturbed=self.disturbed,
        )
