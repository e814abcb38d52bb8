"""The speed profile (SPEC §8; thesis section 6.5, eqs. 1-14): speed linear in time, ending at rest.

A vehicle at speed ``v0`` that must stop after exactly ``distance`` metres accelerates at ``acceleration``
and brakes at the same rate. Two cases follow from the thesis:

* **triangle** (eq. 12): the peak ``vp = sqrt(a·s + v0²/2)`` is within ``max_speed``; accelerate to
  ``vp``, brake at once; stop time ``tz = (2·vp − v0) / a``.
* **trapezoid** (eq. 14): accelerate to ``max_speed``, cruise, brake;
  ``tz = (v0² − 2·v0·vmax + 2·vmax² + 2·a·s) / (2·a·vmax)``.

A third case is not in the thesis: **brake**, when ``distance`` is shorter than the stopping distance
``v0²/(2a)`` (float rounding, or the distance available shrank abruptly). The vehicle then brakes at the
rate ``v0²/(2s)`` needed to stop within ``distance``, so the profile still ends at rest after exactly
``distance`` instead of yielding a negative peak or NaN. For ``distance == 0`` that rate is infinite:
the stop is instantaneous (``stop_time == 0``).

Times are relative to the moment the profile was planned. The distance per simulation step is the exact
area under the profile (``advance``); it never runs backwards and never overshoots ``distance``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

__all__ = ["SpeedProfile"]

# ``v0`` above ``max_speed`` by at most this (relative, and absolute below 1 m/s) is rounding noise from
# the previous profile; it is clamped to ``max_speed`` rather than rejected.
_SPEED_SLACK = 1e-9


@dataclass(frozen=True, slots=True)
class SpeedProfile:
    """Speed against time from ``v0`` to rest over ``distance``; build one with :meth:`plan`.

    Phases: accelerate on ``[0, accelerate_until]``, hold ``peak`` on ``[accelerate_until, brake_from]``,
    brake at ``deceleration`` on ``[brake_from, stop_time]``; any phase may be empty.
    """

    v0: float
    acceleration: float
    max_speed: float
    distance: float
    peak: float  # highest speed reached
    accelerate_until: float  # time the acceleration phase ends
    brake_from: float  # time the deceleration phase starts
    stop_time: float  # tz
    deceleration: float  # normally == acceleration; larger only in the "brake" case
    # distance_at(accelerate_until) and distance_at(brake_from), computed once for the per-step path.
    _accelerated_distance: float = field(init=False, repr=False, compare=False)
    _cruised_distance: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        accelerated = self._accelerated()
        object.__setattr__(self, "_accelerated_distance", accelerated)
        object.__setattr__(self, "_cruised_distance", self._cruised(accelerated))

    @classmethod
    def plan(cls, v0: float, acceleration: float, max_speed: float, distance: float) -> SpeedProfile:
        """The profile that starts at ``v0`` and comes to rest after exactly ``distance``.

        Raises ``ValueError`` for a negative or non-finite ``v0`` or ``distance``, a non-positive or
        non-finite ``acceleration`` or ``max_speed``, or ``v0`` above ``max_speed`` by more than rounding.
        """
        v0, a, vmax, s = _checked(v0, acceleration, max_speed, distance)
        kind = _classify(v0, a, vmax, s)
        if kind == "brake":
            # v0 > 0 here, since a·s < v0²/2 is impossible from rest.
            deceleration = v0 * v0 / (2.0 * s) if s > 0.0 else math.inf
            return cls(v0, a, vmax, s, v0, 0.0, 0.0, 2.0 * s / v0, deceleration)
        if kind == "triangle":
            # max() guards the peak against rounding below v0 at the brake boundary.
            vp = max(v0, math.sqrt(a * s + v0 * v0 / 2.0))
            accelerate_until = (vp - v0) / a
            stop_time = (2.0 * vp - v0) / a  # eq. 12
            return cls(v0, a, vmax, s, vp, accelerate_until, accelerate_until, stop_time, a)
        accelerate_until = (vmax - v0) / a  # eq. 5
        # Eq. 14 with v0² − 2·v0·vmax + vmax² folded into (vmax − v0)², which avoids cancellation.
        stop_time = ((vmax - v0) ** 2 + vmax * vmax + 2.0 * a * s) / (2.0 * a * vmax)
        brake_from = min(stop_time, max(accelerate_until, stop_time - vmax / a))  # eqs. 6-7
        return cls(v0, a, vmax, s, vmax, accelerate_until, brake_from, stop_time, a)

    @property
    def kind(self) -> Literal["triangle", "trapezoid", "brake"]:
        """Which case :meth:`plan` chose, by the same test."""
        return _classify(self.v0, self.acceleration, self.max_speed, self.distance)

    def speed_at(self, t: float) -> float:
        """Speed at time ``t``, clamped to ``[0, stop_time]``; 0 from ``stop_time`` on."""
        t = self._clamped(t, "t")
        if t >= self.stop_time:
            return 0.0
        if t <= self.accelerate_until:
            return min(self.peak, self.v0 + self.acceleration * t)
        if t <= self.brake_from:
            return self.peak
        return self._braking_speed(t)

    def distance_at(self, t: float) -> float:
        """Exact area under the profile from 0 to ``t`` (clamped); exactly ``distance`` from ``stop_time``.

        Each phase's value is kept inside the distances at its own boundaries, so rounding can neither
        make the result decrease in ``t`` nor exceed ``distance``.
        """
        t = self._clamped(t, "t")
        if t >= self.stop_time:
            return self.distance
        accelerated = self._accelerated_distance
        if t <= self.accelerate_until:
            return min(accelerated, t * (self.v0 + 0.5 * self.acceleration * t))
        cruised = self._cruised_distance
        if t <= self.brake_from:
            return min(cruised, accelerated + self.peak * (t - self.accelerate_until))
        return max(cruised, self._braked_at(t))

    def running_at(self, t: float) -> tuple[float, float]:
        """``(distance_at(t), speed_at(t))`` for ``0 <= t < stop_time``, unchecked: the per-step path.

        The same arithmetic as those two methods, so the values are identical to theirs.
        """
        if t <= self.accelerate_until:
            return (
                min(self._accelerated_distance, t * (self.v0 + 0.5 * self.acceleration * t)),
                min(self.peak, self.v0 + self.acceleration * t),
            )
        if t <= self.brake_from:
            return min(
                self._cruised_distance, self._accelerated_distance + self.peak * (t - self.accelerate_until)
            ), self.peak
        return max(self._cruised_distance, self._braked_at(t)), self._braking_speed(t)

    def running_terms(self) -> tuple[float, float, float, float, float, float, float, float, float, float, float]:
        """The constants :meth:`running_at` computes with, for stepping many profiles at once in arrays
        (:class:`~fleetsim.motion.fleet_cruise.FleetCruise`): stop_time, accelerate_until, brake_from,
        v0, acceleration, 0.5 · acceleration, peak, deceleration, distance, and the distances at the end
        of the acceleration and of the hold."""
        a = self.acceleration
        return (
            self.stop_time, self.accelerate_until, self.brake_from, self.v0, a, 0.5 * a, self.peak,
            self.deceleration, self.distance, self._accelerated_distance, self._cruised_distance,
        )  # fmt: skip

    def advance(self, t0: float, t1: float) -> float:
        """Distance covered from ``t0`` to ``t1`` (``t0 <= t1``): the exact area under the step."""
        start, end = self._clamped(t0, "t0"), self._clamped(t1, "t1")
        if t1 < t0:
            msg = f"t1={t1!r} must not be before t0={t0!r}"
            raise ValueError(msg)
        return self.distance_at(end) - self.distance_at(start)

    def _clamped(self, t: float, name: str) -> float:
        if math.isnan(t):
            msg = f"{name}={t!r} must be a number"
            raise ValueError(msg)
        return min(max(t, 0.0), self.stop_time)

    def _braking_speed(self, t: float) -> float:
        # Measured back from the stop, so it is exactly 0 at stop_time; min() also tames an infinite rate.
        return min(self.peak, self.deceleration * (self.stop_time - t))

    def _braked_at(self, t: float) -> float:
        # Distance left to go is the triangle under the braking line from t to stop_time.
        return self.distance - 0.5 * self._braking_speed(t) * (self.stop_time - t)

    def _accelerated(self) -> float:
        t = self.accelerate_until
        return min(self.distance, t * (self.v0 + 0.5 * self.acceleration * t))

    def _cruised(self, accelerated: float) -> float:
        return max(accelerated, self._braked_at(self.brake_from))


def _checked(v0: float, acceleration: float, max_speed: float, distance: float) -> tuple[float, float, float, float]:
    for name, value, positive in (
        ("v0", v0, False),
        ("acceleration", acceleration, True),
        ("max_speed", max_speed, True),
        ("distance", distance, False),
    ):
        if not math.isfinite(value) or (value <= 0.0 if positive else value < 0.0):
            msg = f"{name}={value!r} must be {'positive' if positive else 'non-negative'} and finite"
            raise ValueError(msg)
    if v0 > max_speed:
        if v0 - max_speed > _SPEED_SLACK * max(1.0, max_speed):
            msg = f"v0={v0!r} must not exceed max_speed={max_speed!r}"
            raise ValueError(msg)
        v0 = max_speed
    return float(v0), float(acceleration), float(max_speed), float(distance)


def _classify(v0: float, a: float, vmax: float, s: float) -> Literal["triangle", "trapezoid", "brake"]:
    # vp² < v0² exactly when a·s < v0²/2: the distance is shorter than the stopping distance v0²/(2a).
    if a * s < v0 * v0 / 2.0:
        return "brake"
    return "triangle" if math.sqrt(a * s + v0 * v0 / 2.0) <= vmax else "trapezoid"
