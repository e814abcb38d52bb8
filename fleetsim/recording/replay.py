"""Replaying a run from its trace: the fleet as it was at the end of each step.

The trace (SPEC §10) holds, per step, the vehicles that changed (quantised pose and speed), the plans
accepted and the events. Replayed against the scenario it came from, it gives back every vehicle's pose
and the plans in force: an accepted plan replaces the vehicle's plan, and as the vehicle drives on, the
legs before its current one fall away (the simulation drops passed legs the same way). The alerts in
force follow from the plans (SPEC §7). Recordings (MCAP) and pictures (SVG) are drawn from these frames,
so they show exactly what the hashed trace says happened.
"""

from __future__ import annotations

import contextlib
import gc
import json
import math
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, NamedTuple

import orjson

from fleetsim.enums import Progress, Traverse
from fleetsim.errors import FleetsimError
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.reservations import CollisionAlert, ConflictTable, ReservationIndex
from fleetsim.planning.snapshot import initial_plan, initial_state
from fleetsim.scenario import Scenario
from fleetsim.sim.trace import TRACE_FORMAT

__all__ = ["Frame", "Pose", "TraceError", "collector_paused", "frame_at", "replay"]

_TRAVERSE = {"f": Traverse.FORWARD, "b": Traverse.BACKWARD}
_PROGRESS = {"f": Progress.FORWARD, "r": Progress.REVERSE}


class TraceError(FleetsimError, ValueError):
    """A trace that is not one this version writes, or does not belong to the scenario."""


class Pose(NamedTuple):
    """A vehicle as the trace has it: metres, radians (where the nose points), m/s (a named tuple: one
    is made for every vehicle that moved in every step replayed)."""

    segment: int
    traverse: Traverse
    progress: Progress
    x: float
    y: float
    heading: float
    speed: float


@dataclass(frozen=True, slots=True)
class Frame:
    """The fleet at the end of one step."""

    step: int
    time: float  # seconds at the end of the step
    poses: Mapping[int, Pose]
    plans: Mapping[int, FleetPlan]
    alerts: tuple[CollisionAlert, ...]  # in force over these plans
    events: tuple[tuple[Any, ...], ...]
    moved: tuple[int, ...]  # vehicles whose pose changed in this step
    replanned: tuple[int, ...]  # vehicles whose plan was accepted or passed a leg in this step, in id order
    # Vehicles a disturbance stops or slows in this step, by id: "stop" or "slow" (the trace's
    # "disturb"/"resume" events; a disturbance that begins at t and ends at t' marks the frames in (t, t']).
    disturbed: Mapping[int, str] = field(default_factory=lambda: MappingProxyType({}))

    @property
    def plans_changed(self) -> bool:
        """A plan was accepted or a vehicle passed a leg in this step."""
        return bool(self.replanned)


_new = tuple.__new__
_RADIANS_PER_CENTIDEGREE = math.pi / 18000.0


def _pose(record: Sequence[Any]) -> Pose:
    _, segment, traverse, progress, x, y, heading, speed = record
    return _new(
        Pose,
        (
            segment,
            _TRAVERSE[traverse],
            _PROGRESS[progress],
            x / 1000.0,
            y / 1000.0,
            heading * _RADIANS_PER_CENTIDEGREE,
            speed / 1000.0,
        ),
    )


def _plan(record: Sequence[Any]) -> FleetPlan:
    vehicle_id, legs = record
    return FleetPlan(
        vehicle_id,
        tuple(FleetLeg(segment, _TRAVERSE[t], _PROGRESS[p], bool(fixed), goal) for segment, t, p, fixed, goal in legs),
    )


def _passed(plan: FleetPlan, pose: Pose) -> FleetPlan:
    """``plan`` without the legs before the one the vehicle is on (unchanged if it is on the first)."""
    for index, leg in enumerate(plan.legs):
        if leg.segment == pose.segment and leg.traverse is pose.traverse and leg.progress is pose.progress:
            return plan if index == 0 else FleetPlan(plan.vehicle_id, plan.legs[index:])
    return plan


def _header(line: str, scenario: Scenario) -> dict[str, Any]:
    try:
        header = json.loads(line)
    except json.JSONDecodeError as error:
        msg = f"trace header={line[:80]!r} is not JSON ({error.msg})"
        raise TraceError(msg) from None
    if not isinstance(header, dict) or header.get("format") != TRACE_FORMAT:
        found = header.get("format") if isinstance(header, dict) else header
        msg = f"trace format={found!r} must be {TRACE_FORMAT!r}"
        raise TraceError(msg)
    ids = sorted(v.id for v in scenario.vehicles)
    if header.get("vehicles") != ids:
        msg = f"trace vehicles={header.get('vehicles')!r} must be scenario {scenario.name!r}'s vehicles {ids!r}"
        raise TraceError(msg)
    return header


def replay(scenario: Scenario, lines: Iterable[str]) -> Iterator[Frame]:
    """Every step of a run of ``scenario`` from its trace lines (header first), in order."""
    iterator = iter(lines)
    header = _header(next(iterator, ""), scenario)
    dt = header["time_step_us"] / 1e6
    layout = scenario.layout
    segments = layout.segments
    poses = {}
    for vehicle in sorted(scenario.vehicles, key=lambda v: v.id):
        state = initial_state(vehicle, layout)
        poses[vehicle.id] = Pose(state.segment, state.traverse, state.progress, state.x, state.y, state.heading, 0.0)
    plans = {v.id: initial_plan(v) for v in sorted(scenario.vehicles, key=lambda v: v.id)}
    index = ReservationIndex(ConflictTable(layout))
    # A run with the reservation check off raised no alert, so none is shown (its plans may overlap).
    alerts = index.alerts(plans) if scenario.settings.checks.reservations else ()
    reported = bool(alerts)
    disturbed: dict[int, list[str]] = {}
    shown: Mapping[int, str] = MappingProxyType({})
    for number, line in enumerate(iterator, start=2):
        try:
            step, vehicles, accepted, events = orjson.loads(line)  # as json.loads, several times faster
        except (json.JSONDecodeError, ValueError, TypeError):
            msg = f"trace line {number}={line[:80]!r} is not a step record [step, vehicles, plans, events]"
            raise TraceError(msg) from None
        replanned = set()
        for record in accepted:
            plan = _plan(record)
            unknown = [leg.segment for leg in plan.legs if leg.segment not in layout.segments]
            if plan.vehicle_id not in plans or unknown:
                what = f"segment {unknown[0]}" if unknown else f"vehicle {plan.vehicle_id}"
                msg = f"trace line {number} names {what}, which scenario {scenario.name!r} does not have"
                raise TraceError(msg)
            plans[plan.vehicle_id] = plan
            replanned.add(plan.vehicle_id)
        moved = []
        for record in vehicles:
            vehicle_id = record[0]
            if vehicle_id not in poses or record[1] not in segments:
                msg = f"trace line {number} places vehicle {vehicle_id} on segment {record[1]}, which scenario {scenario.name!r} does not have"
                raise TraceError(msg)
            poses[vehicle_id] = pose = _pose(record)
            moved.append(vehicle_id)
            plan = plans[vehicle_id]
            # Most vehicles are on their plan's first leg, which leaves the plan as it is.
            first = plan.legs[0] if plan.legs else None
            if first is not None and (first.segment, first.traverse, first.progress) == pose[:3]:
                continue
            passed = _passed(plan, pose)
            if passed is not plan:
                plans[vehicle_id] = passed
                replanned.add(vehicle_id)
        # An alert in force was reported (an "alert" event) when it appeared, so before the first report
        # there is nothing to compute; and legs driven past reserve nothing more, so dropping them can
        # end an alert but never raise one.
        reported = reported or any(event[0] == "alert" for event in events)
        if reported and (accepted or (replanned and alerts)):
            alerts = index.alerts(plans)
        if any(event[0] in ("disturb", "resume") for event in events):
            shown = _disturbed(disturbed, events)
        yield Frame(
            step=step,
            time=(step + 1) * dt,
            poses=MappingProxyType(dict(poses)),
            plans=MappingProxyType(dict(plans)),
            alerts=alerts,
            events=tuple(tuple(event) for event in events),
            moved=tuple(moved),
            replanned=tuple(sorted(replanned)),
            disturbed=shown,
        )


def _disturbed(going: dict[int, list[str]], events: Sequence[Sequence[Any]]) -> Mapping[int, str]:
    """Apply a step's disturbance events to ``going`` (vehicle -> kinds); each vehicle's shown kind
    (a stop over a slow)."""
    for event in events:
        if event[0] == "disturb":
            going.setdefault(event[1], []).append(event[2])
        elif event[0] == "resume" and event[2] in going.get(event[1], []):
            going[event[1]].remove(event[2])
    shown = {v: "stop" if {"stop", "pause"} & set(kinds) else "slow" for v, kinds in sorted(going.items()) if kinds}
    return MappingProxyType(shown)  # a paused vehicle (VDA 5050 startPause) is shown as stopped


def frame_at(scenario: Scenario, lines: Iterable[str], step: int) -> Frame:
    """The frame of step ``step`` (``-1``: the last one)."""
    last: Frame | None = None
    for frame in replay(scenario, lines):
        last = frame
        if frame.step == step:
            return frame
    if last is None:
        msg = "the trace has no steps"
        raise TraceError(msg)
    if step == -1:
        return last
    msg = f"step={step!r} must be between 0 and {last.step} (the run's last step)"
    raise TraceError(msg)


@contextlib.contextmanager
def collector_paused() -> Iterator[None]:
    """The cyclic garbage collector paused, for a reader that makes a great many small objects from the
    frames and keeps many of them (a recording, a view document): they hold no cycles, and the collector
    would otherwise walk them, and the whole run still in memory, again and again as they pile up."""
    paused = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if paused:
            gc.enable()
