"""Disturbances in a run (issue 20): vehicles that stop or slow down unexpectedly, declared or drawn.

Semantics. A vehicle follows its fixed legs as always, only slower or not at all; its plan, and so its
reservations, stay as they are; the plan checks are unchanged.

* A **stop** starts at the first step whose start time is at or after ``at`` (or at the first step the
  vehicle starts on segment ``on_segment``): the vehicle brakes at its type's deceleration (harder only
  if its fixed legs end sooner), a turn in place freezes, and it stands ``stop`` seconds once at rest.
  The stop ends at the first step at or after that; then the vehicle drives on as usual.
* A **slow** limits the vehicle's speed to ``slow`` × its max speed for ``for`` seconds; a faster
  vehicle brakes down to the limit at its deceleration and never exceeds it afterwards.
* A disturbance due while the vehicle is under another of the same kind waits until that one ends.
* While any vehicle stands in a stop, the deadlock timer does not run: it counts from the stop's end.
* The planner sees ``VehicleState.disturbed`` (``stopped``/``slowed``/``None``), not how long it lasts.

Random stops (``random_disturbances``) are drawn before the run, vehicle by vehicle in ascending id,
each from its own generator ``random.Random(f"fleetsim-disturbances/{seed}/{vehicle}")`` (seeded from
the string by SHA-512: the same numbers on every platform and Python ≥ 3.2). Each step ``k`` of the time
limit while the vehicle has no drawn stop going, a stop starts with probability
``p = stops_per_vehicle_hour / 3600 × time_step``: when ``getrandbits(32) < int(p × 2³²)``; its duration
is ``low + (high − low) × getrandbits(32) / 2³²`` rounded to milliseconds. Only integer draws and
correctly rounded arithmetic: no ``log`` or other libm call whose last bit may differ between platforms.

Determinism: the declared and drawn schedule goes into the trace header and every start and end into
the step's events (``["disturb", vehicle, kind]``, ``["resume", vehicle, kind]``), so they are part of
the hash; a run without disturbances has neither, and hashes as before.
"""

from __future__ import annotations

import random
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from fleetsim.enums import Disturbed
from fleetsim.motion.driver import Driver
from fleetsim.planning.controller import FleetController
from fleetsim.scenario import Disturbance, RandomDisturbances, Scenario

__all__ = ["DisturbanceEvent", "Disturber", "draw_stops", "schedule_of"]

_EPS = 1e-9


@dataclass(frozen=True, slots=True)
class DisturbanceEvent:
    """A disturbance that happened: when (``end`` None: still going when the run ended) and where it began."""

    vehicle: int
    kind: Literal["stop", "slow"]
    start: float
    end: float | None
    segment: int
    x: float
    y: float
    factor: float | None = None  # slow only

    def to_dict(self) -> dict[str, Any]:
        return {
            "vehicle": self.vehicle,
            "kind": self.kind,
            "start": round(self.start, 6),
            "end": None if self.end is None else round(self.end, 6),
            "segment": self.segment,
            "x": round(self.x, 3),
            "y": round(self.y, 3),
            **({"factor": self.factor} if self.factor is not None else {}),
        }

    def covers(self, time: float) -> bool:
        """Whether the vehicle was disturbed at ``time`` (a frame's time)."""
        return self.start - _EPS <= time and (self.end is None or time < self.end - _EPS)

    def label(self) -> str:
        return "STOP" if self.kind == "stop" else f"SLOW ×{self.factor:g}"


def draw_stops(
    spec: RandomDisturbances, vehicles: tuple[int, ...], time_limit: float, time_step: float
) -> tuple[Disturbance, ...]:
    """The stops ``spec`` draws for ``vehicles`` over ``time_limit`` (see the module's description)."""
    steps = max(1, round(time_limit / time_step))
    threshold = int(spec.stops_per_vehicle_hour / 3600.0 * time_step * 2**32)
    low, high = spec.stop
    drawn: list[Disturbance] = []
    for vehicle in sorted(vehicles):
        generator = random.Random(f"fleetsim-disturbances/{spec.seed}/{vehicle}")
        free_from = 0
        for step in range(steps):
            if step < free_from or generator.getrandbits(32) >= threshold:
                continue
            duration = round(low + (high - low) * generator.getrandbits(32) / 2**32, 3)
            drawn.append(Disturbance(vehicle, "stop", duration, at=round(step * time_step, 6)))
            free_from = step + 1 + int(duration / time_step)
    return tuple(drawn)


def schedule_of(scenario: Scenario) -> tuple[Disturbance, ...]:
    """Declared disturbances, then drawn ones, each group in its own order."""
    drawn: tuple[Disturbance, ...] = ()
    if scenario.random_disturbances is not None:
        ids = tuple(v.id for v in scenario.vehicles)
        drawn = draw_stops(scenario.random_disturbances, ids, scenario.settings.time_limit, scenario.settings.time_step)
    return scenario.disturbances + drawn


def _record(d: Disturbance) -> list[Any]:
    """Canonical, integer form for the trace header: times in ms, the factor in thousandths."""
    at = None if d.at is None else round(d.at * 1000)
    return [d.vehicle, d.kind, at, d.on_segment, round(d.duration * 1000), round(d.factor * 1000)]


class _Going:
    """A disturbance under way: when it ends (None: a stop still braking to rest) and its record index."""

    __slots__ = ("disturbance", "ends", "index")

    def __init__(self, disturbance: Disturbance, ends: float | None, index: int) -> None:
        self.disturbance = disturbance
        self.ends = ends
        self.index = index


class Disturber:
    """Starts and ends the scenario's disturbances, step by step, on the drivers (the loop's hook)."""

    def __init__(self, scenario: Scenario, drivers: Mapping[int, Driver], controller: FleetController) -> None:
        self.schedule = schedule_of(scenario)
        self._drivers = drivers
        self._controller = controller
        # Due ones in schedule order; those by time sorted by it (stably: ties keep the schedule's order).
        self._waiting = sorted(self.schedule, key=lambda d: (d.at is None, d.at or 0.0))
        self._going: dict[tuple[int, str], _Going] = {}
        self._happened: list[DisturbanceEvent] = []

    def header(self) -> list[list[Any]]:
        return [_record(d) for d in self.schedule]

    def step(self, now: float, events: list[list[Any]]) -> bool:
        """Step ``now``'s starts and ends; True while some vehicle stands in a stop (no deadlock then)."""
        changed: set[int] = set()
        for key in sorted(self._going):
            going = self._going[key]
            if going.ends is None:  # a stop braking: at rest from now on, it stands its duration
                driver = self._drivers[key[0]]
                if driver.speed == 0.0:
                    going.ends = now + going.disturbance.duration
            if going.ends is not None and now >= going.ends - _EPS:
                self._end(key, now, events)
                changed.add(key[0])
        still: list[Disturbance] = []
        for disturbance in self._waiting:
            if self._due(disturbance, now) and (disturbance.vehicle, disturbance.kind) not in self._going:
                self._start(disturbance, now, events)
                changed.add(disturbance.vehicle)
            else:
                still.append(disturbance)
        self._waiting = still
        if changed:
            self._show(changed)
        return any(kind == "stop" for _, kind in self._going)

    def happened(self) -> tuple[DisturbanceEvent, ...]:
        return tuple(self._happened)

    def _due(self, disturbance: Disturbance, now: float) -> bool:
        if disturbance.at is not None:
            return now >= disturbance.at - _EPS
        return self._controller.state_of(disturbance.vehicle).segment == disturbance.on_segment

    def _start(self, disturbance: Disturbance, now: float, events: list[list[Any]]) -> None:
        vehicle = disturbance.vehicle
        driver = self._drivers[vehicle]
        state = self._controller.state_of(vehicle)
        if disturbance.kind == "stop":
            braking = driver.halt()
            ends = now + disturbance.duration if braking == 0.0 and driver.speed == 0.0 else None
            factor = None
        else:
            driver.limit_speed(disturbance.factor * driver.type.max_speed)
            ends = now + disturbance.duration
            factor = disturbance.factor
        index = len(self._happened)
        self._happened.append(
            DisturbanceEvent(vehicle, disturbance.kind, now, None, state.segment, state.x, state.y, factor)
        )
        self._going[(vehicle, disturbance.kind)] = _Going(disturbance, ends, index)
        events.append(["disturb", vehicle, disturbance.kind])

    def _end(self, key: tuple[int, str], now: float, events: list[list[Any]]) -> None:
        going = self._going.pop(key)
        driver = self._drivers[key[0]]
        if key[1] == "stop":
            driver.release()
        else:
            driver.limit_speed(driver.type.max_speed)
        event = self._happened[going.index]
        self._happened[going.index] = DisturbanceEvent(
            event.vehicle, event.kind, event.start, now, event.segment, event.x, event.y, event.factor
        )
        events.append(["resume", key[0], key[1]])

    def _show(self, vehicles: set[int]) -> None:
        """What the planner sees: each changed vehicle's state carries its disturbance now."""
        states = {}
        for vehicle in sorted(vehicles):
            driver = self._drivers[vehicle]
            kinds = {kind for v, kind in self._going if v == vehicle}
            driver.disturbed = Disturbed.STOPPED if "stop" in kinds else Disturbed.SLOWED if "slow" in kinds else None
            states[vehicle] = self._controller.state_of(vehicle)._replace(disturbed=driver.disturbed)
        self._controller.set_states(list(states), states.values())
