"""What the viewer page draws, as one JSON document made from a run's trace (``fleetsim-view/1``).

The page (:mod:`fleetsim.view.page`) knows nothing of fleetsim's objects: it reads this document, which
is made from the trace format (:mod:`fleetsim.recording.replay` gives the fleet at the end of every step)
and the result document. Static parts come first — the map's segments, the vehicles' footprints and
colours, the tasks — then one compact record per step, holding only what changed in it, as the trace
does:

``[step, poses, plans, alerts, events, disturbed, orders]``

- ``poses``: the trace's own records of the vehicles whose pose changed (every vehicle at step 0), as
  they are: ``[vehicle, segment, traverse "f"|"b", progress "f"|"r", x mm, y mm, heading centidegrees,
  speed mm/s]``.
- ``plans``: ``[vehicle, [[segment, way, fixed, task], ...]]`` for each vehicle whose plan was accepted
  or passed a leg in the step (``task``: the task the leg completes, or ``null``).
- ``alerts``: the collision alerts in force, ``[segment, [primary], [secondary]]`` each, when they changed
  (``null`` when not).
- ``events``: the trace's events of the step, as they are.
- ``disturbed``: ``{vehicle: "stop" | "slow"}`` when it changed, else ``null``.
- ``orders``: in a run with transport orders, what the step changed of them
  (:mod:`fleetsim.recording.orders`), else ``null``: ``carry`` ``{vehicle: [orders, loaded 0|1, stop,
  stops, dwell since s | null, dwell s | null, stalled 0|1] | null}`` (``null``: no order, not stalled),
  ``waiting`` ``{station segment: [orders waiting there]}``, ``open`` and ``done`` (counts, at step 0
  and whenever they change) and ``backlog`` (the open orders sampled at the step's start, once a minute,
  as the run's measures sample them).

A live run sends the same static part first, then the same step records as they happen
(:mod:`fleetsim.view.live`).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import Any

import orjson

from fleetsim.enums import Direction, Progress, Traverse
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.recording.colours import hex_colour, vehicle_colours
from fleetsim.recording.orders import Carry, OrderChanges, OrderTracker
from fleetsim.recording.picture import failure_step, stuck_details
from fleetsim.recording.replay import Frame, collector_paused, replay
from fleetsim.recording.stuck import contested_segments, root_vehicles, stuck_relations
from fleetsim.scenario import Scenario
from fleetsim.sim.result import Failure

__all__ = ["VIEW_FORMAT", "StepRecords", "outcome_part", "records_of", "scene_part", "view_document"]

VIEW_FORMAT = "fleetsim-view/1"

_DIRECTION = {Direction.BOTH: 0, Direction.FORWARD: 1, Direction.BACKWARD: 2}


def _way(traverse: Traverse, progress: Progress) -> int:
    return 2 * (traverse is Traverse.BACKWARD) + (progress is Progress.REVERSE)


def scene_part(scenario: Scenario, about: Mapping[str, Any]) -> dict[str, Any]:
    """The static part of a run's view: ``about`` (planner, suite, ...), the map, vehicles and tasks."""
    layout = scenario.layout
    segments = []
    for sid in sorted(layout.segments):
        segment = layout.segments[sid]
        points = [round(c, 3) for point in segment.waypoints for c in point]
        segments.append([sid, segment.shape.value, _DIRECTION[segment.direction], " / ".join(segment.names), points])
    colours = vehicle_colours(scenario)
    vehicles = [
        [v.id, v.type.name, round(v.type.length, 3), round(v.type.width, 3), hex_colour(colours[v.id])]
        for v in sorted(scenario.vehicles, key=lambda v: v.id)
    ]
    tasks = [[t.id, t.vehicle_id, t.goal_segment] for t in sorted(scenario.tasks, key=lambda t: t.id)]
    return {
        "format": VIEW_FORMAT,
        "scenario": scenario.name,
        **{key: about[key] for key in sorted(about)},
        "time_step": scenario.settings.time_step,
        "time_limit": scenario.settings.time_limit,
        "segments": segments,
        "vehicles": vehicles,
        "tasks": tasks,
    }


class StepRecords:
    """Frames as the document's step records, each holding what changed since the one before.

    ``header``: the trace's header line, for the run's orders; :meth:`header` gives it later (a live run's
    header comes with its first line)."""

    def __init__(self, header: str | None = None) -> None:
        self._orders = OrderTracker.of_trace([header] if header is not None else [])
        self._alerts: tuple[Any, ...] | None = None
        self._disturbed: Mapping[int, str] | None = None
        self._legs: dict[int, tuple[FleetLeg, list[Any]]] = {}  # id(leg) -> the leg and its record

    def record(self, frame: Frame, line: str) -> list[Any]:
        """The record of ``frame``, whose trace line is ``line`` (its vehicle records are taken as they are)."""
        first = self._alerts is None
        poses = orjson.loads(line)[1]
        plans = [[vid, self._plan(frame.plans[vid])] for vid in (sorted(frame.plans) if first else frame.replanned)]
        alerts = None
        if first or frame.alerts != self._alerts:
            alerts = [[a.segment, list(a.primary), list(a.secondary)] for a in frame.alerts]
            self._alerts = frame.alerts
        disturbed = None
        if first or frame.disturbed != self._disturbed:
            disturbed = {str(vid): kind for vid, kind in sorted(frame.disturbed.items())}
            self._disturbed = frame.disturbed
        orders = self._orders_record(self._orders.follow(frame))
        return [frame.step, poses, plans, alerts, [list(event) for event in frame.events], disturbed, orders]

    def header(self, line: str) -> None:
        """The trace's header line (before the first frame)."""
        self._orders = OrderTracker.of_trace([line])

    def _orders_record(self, changes: OrderChanges) -> dict[str, Any] | None:
        if not changes:
            return None
        tracker = self._orders
        record: dict[str, Any] = {}
        if changes.vehicles:
            record["carry"] = {str(v): _carry(tracker.carry_of(v)) for v in sorted(changes.vehicles)}
        if changes.stations:
            record["waiting"] = {str(s): list(tracker.waiting_at(s)) for s in sorted(changes.stations)}
        if changes.counts:
            record["open"], record["done"] = tracker.open, tracker.done
        if changes.sample is not None:
            record["backlog"] = changes.sample
        return record

    def _plan(self, plan: FleetPlan) -> list[Any]:
        # A plan that passed a leg keeps the same leg objects: each is encoded once.
        legs = self._legs
        encoded = []
        for leg in plan.legs:
            known = legs.get(id(leg))
            if known is None or known[0] is not leg:
                known = legs[id(leg)] = (
                    leg,
                    [leg.segment, _way(leg.traverse, leg.progress), int(leg.fixed), leg.goal_for_task],
                )
            encoded.append(known[1])
        return encoded


def _carry(carry: Carry) -> list[Any] | None:
    if not carry.orders and not carry.stalled:
        return None
    since, seconds = carry.dwell if carry.dwell is not None else (None, None)
    return [
        list(carry.orders),
        int(carry.loaded),
        carry.stop,
        carry.stops,
        None if since is None else round(since, 6),
        seconds,
        int(carry.stalled),
    ]


def records_of(frames: Iterable[Frame], lines: Sequence[str]) -> Iterator[list[Any]]:
    """The step records of a trace's frames (``lines``: the trace, header first)."""
    records = StepRecords(lines[0] if lines else None)
    for frame in frames:
        yield records.record(frame, lines[frame.step + 1])


def outcome_part(
    document: Mapping[str, Any], failures: Sequence[Failure], time_step: float, last_step: int
) -> dict[str, Any]:
    """How the run ended, for the page: status, how many failures, the moment to jump to, the contacts and who
    waits for whom at the end (from ``result.json``'s document; empty for a run that never ended)."""
    found = failure_step(failures, time_step, last_step) if failures else None
    stuck = None
    for failure in failures:
        details = stuck_details(failure)
        if details is not None:
            stuck = _stuck(details, f"{failure.kind}: {failure.message}")
            break
    # A contact's moment is its failure's time: read back from result.json, its details have no "time" of
    # their own (the failure's and the contact's are one key there).
    contacts = [
        {
            "time": round(f.time, 6),
            "x": float(f.details["x"]),
            "y": float(f.details["y"]),
            "vehicles": [int(v) for v in f.details["vehicles"]],
        }
        for f in failures
        if f.kind == "contact" and {"x", "y", "vehicles"} <= set(f.details)
    ]
    return {
        "status": document.get("status"),
        "ended": document.get("ended"),
        "trace_hash": document.get("trace_hash"),
        # How many, not each: a run with an alert a step has tens of thousands (result.json has them all),
        # and a page that keeps them in memory draws a quarter slower.
        "failure_count": len(failures),
        "failure": None
        if found is None
        else {"step": found[0], "kind": found[1].kind, "time": round(found[1].time, 6), "message": found[1].message},
        "contacts": contacts,
        "stuck": stuck,
        # A shift's stalls with why each vehicle stands (the trace says who and when; result.json why).
        "stalls": [
            {"vehicle": s["vehicle"], "time": s["time"], "orders": s["orders"], "reason": s["reason"]}
            for s in document.get("stalls") or ()
            if isinstance(s, Mapping) and {"vehicle", "time", "orders", "reason"} <= set(s)
        ],
    }


def _stuck(details: Mapping[str, Any], headline: str) -> dict[str, Any]:
    """Who waits for whom: ``[from, to, "wait-for" | "planned-near", in a cycle]`` relations, the root-cause
    vehicles and the contested segments."""
    return {
        "headline": headline,
        "relations": [
            [r.source, r.target, "wait-for" if r.waits else "planned-near", r.cycle] for r in stuck_relations(details)
        ],
        "roots": root_vehicles(details),
        "contested": contested_segments(details),
    }


def view_document(
    scenario: Scenario,
    lines: Sequence[str],
    about: Mapping[str, Any],
    outcome: Mapping[str, Any],
    notes: Sequence[str] = (),
) -> dict[str, Any]:
    """The whole view of a recorded run whose trace is ``lines`` (header first): the scene, every step's
    record, how it ended and ``notes`` (a trace that ends early says so here)."""
    frames = replay(scenario, lines)
    # Millions of small lists that live until the page is written (half the time of a large run with the
    # collector on).
    with collector_paused():
        steps = list(records_of(frames, lines))
    return {
        **scene_part(scenario, about),
        "live": False,
        "steps": steps,
        "outcome": dict(outcome),
        "notes": list(notes),
    }
