"""Slowing down to a lower speed limit without stopping: the profile of a slowed vehicle (issue 20).

When a vehicle's speed limit drops below its current speed (a ``slow`` disturbance starts), it brakes at
its type's deceleration down to the new limit, holds it, and brakes to rest at the end of the distance
available, as :class:`~fleetsim.motion.profile.SpeedProfile` does from a lower speed. Three phases,
speed linear in time:

* brake from ``v0`` to ``limit`` at ``a``: ``t1 = (v0 − limit)/a``, ``d1 = (v0² − limit²)/(2a)``;
* hold ``limit`` for ``d2 = s − d1 − limit²/(2a)`` metres;
* brake to rest at ``a``: ``limit/a`` seconds, ``limit²/(2a)`` metres.

When ``s`` is shorter than the stopping distance ``v0²/(2a)`` there is no room to hold the limit: the
vehicle brakes to rest within ``s`` (:meth:`SpeedProfile.plan`'s ``brake`` case, harder than ``a``).
:func:`plan_profile` picks the profile for a speed and a limit; its result has the members the driver
uses (``distance``, ``stop_time``, ``distance_at``, ``speed_at``, ``running_at``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fleetsim.motion.profile import SpeedProfile

__all__ = ["Profile", "SlowDownProfile", "plan_profile"]

_SLACK = 1e-9


@dataclass(frozen=True, slots=True)
class SlowDownProfile:
    """Brake from ``v0`` to ``limit``, hold it, brake to rest after exactly ``distance`` metres."""

    v0: float
    acceleration: float
    limit: float
    distance: float
    slowed_at: float  # t1: the limit is reached
    brake_from: float
    stop_time: float
    _slowed_distance: float
    _held_distance: float

    @classmethod
    def plan(cls, v0: float, acceleration: float, limit: float, distance: float) -> SlowDownProfile:
        a = acceleration
        slowed_at = (v0 - limit) / a
        slowed = (v0 * v0 - limit * limit) / (2.0 * a)
        held = max(distance - slowed - limit * limit / (2.0 * a), 0.0)
        brake_from = slowed_at + held / limit
        return cls(v0, a, limit, distance, slowed_at, brake_from, brake_from + limit / a, slowed, slowed + held)

    def speed_at(self, t: float) -> float:
        t = min(max(t, 0.0), self.stop_time)
        if t >= self.stop_time:
            return 0.0
        return self.running_at(t)[1]

    def distance_at(self, t: float) -> float:
        t = min(max(t, 0.0), self.stop_time)
        if t >= self.stop_time:
            return self.distance
        return self.running_at(t)[0]

    def running_at(self, t: float) -> tuple[float, float]:
        """``(distance_at(t), speed_at(t))`` for ``0 <= t < stop_time``; each phase kept within its bounds."""
        a = self.acceleration
        if t <= self.slowed_at:
            return min(self._slowed_distance, t * (self.v0 - 0.5 * a * t)), max(self.limit, self.v0 - a * t)
        if t <= self.brake_from:
            return min(self._held_distance, self._slowed_distance + self.limit * (t - self.slowed_at)), self.limit
        speed = min(self.limit, a * (self.stop_time - t))
        return min(self.distance, max(self._held_distance, self.distance - 0.5 * speed * (self.stop_time - t))), speed


Profile = SpeedProfile | SlowDownProfile


def plan_profile(v0: float, acceleration: float, limit: float, distance: float) -> Profile:
    """The profile from ``v0`` to rest after ``distance`` metres that keeps to ``limit`` (or brakes down to it)."""
    if v0 <= limit * (1.0 + _SLACK):  # at or under the limit (rounding noise above it is clamped)
        return SpeedProfile.plan(min(v0, limit), acceleration, limit, distance)
    if acceleration * distance < v0 * v0 / 2.0 or not math.isfinite(distance):
        return SpeedProfile.plan(v0, acceleration, v0, distance)  # no room to hold the limit: brake to rest
    return SlowDownProfile.plan(v0, acceleration, limit, distance)
