"""What a run yields (SPEC §10): status, failures, trace hash, events, metrics; and its JSON form.

A run's events (rejections, collision alerts, route errors, the way it ended) are judged against the
scenario's ``expect`` block; every way in which they fall short is a :class:`Failure` with a kind:
``rejection``, ``collision``, ``timeout``, ``deadlock``, ``planner-error``, ``hash-mismatch``,
``interrupted`` (a stop signal ended the run early), or ``expectation`` (something the scenario required
did not happen).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Literal

from fleetsim.contact.monitor import ContactReport
from fleetsim.planning.checks import Rejection
from fleetsim.planning.plans import FleetPlan
from fleetsim.planning.reservations import CollisionAlert
from fleetsim.scenario import Expectations, Task
from fleetsim.sim.diagnosis import Diagnosis
from fleetsim.sim.disturbances import DisturbanceEvent
from fleetsim.sim.measures import OrderMeasures, Stall
from fleetsim.sim.trace import Trace

__all__ = [
    "MOMENTLESS",
    "AlertEvent",
    "DeadlockReport",
    "Failure",
    "Metrics",
    "Pacing",
    "RejectionEvent",
    "RunResult",
    "judge",
    "plan_legs",
]

# "no-counterexample": a generated suite entry whose hunt found no scenario the planner fails.
# "interrupted": SIGINT or SIGTERM ended the run at the end of a step (fleetsim.sim.interrupt).
Ending = Literal[
    "completed",
    "time-limit",
    "shift-end",
    "stall",
    "deadlock",
    "rejection",
    "collision",
    "contact",
    "planner-error",
    "interrupted",
    "load-error",
    "no-counterexample",
]


# Failures without a moment of their own: the run's trace hash against the recorded one, its figures
# against a baseline's, and a scenario that did not load (so never ran).
MOMENTLESS = frozenset({"hash-mismatch", "hash-missing", "regression", "load-error"})


@dataclass(frozen=True, slots=True)
class Failure:
    """One reason a run failed its scenario.

    Attributes:
        kind: What went wrong: ``rejection``, ``collision``, ``contact``, ``timeout``, ``deadlock``,
            ``planner-error``, ``interrupted``, ``expectation`` (something the scenario's ``expect``
            required did not happen); when hashes are checked, ``hash-mismatch``, ``hash-missing`` or
            ``nondeterministic``; ``regression`` for a figure worse than a baseline's by more than
            ``--fleetsim-compare-fail`` allows; ``load-error`` for a scenario that did not load.
        time: Simulated seconds when it happened (the run's end for what is judged at the end).
        message: The failure in words, as the report shows it.
        details: More about it, by kind (a rejection's code, vehicle and leg, say), as in the JSON form.
    """

    kind: str
    time: float
    message: str
    details: Mapping[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "time": round(self.time, 6), "message": self.message, **self.details}


@dataclass(frozen=True, slots=True)
class RejectionEvent:
    """A plan the checks rejected during a run.

    Attributes:
        time: Simulated seconds: the step it was rejected at.
        rejection: The [`Rejection`][fleetsim.planning.checks.Rejection]: its code, vehicle, leg and
            message, and the plan refused.
    """

    time: float
    rejection: Rejection

    def to_dict(self) -> dict[str, Any]:
        r = self.rejection
        return {
            "time": round(self.time, 6),
            "code": r.code.value,
            "vehicle": r.vehicle_id,
            "leg_index": r.leg_index,
            "segment": r.segment,
            "message": r.message,
            **({"plan": plan_legs(r.plan)} if r.plan is not None else {}),
        }


def plan_legs(plan: FleetPlan) -> list[dict[str, Any]]:
    """A plan's legs as JSON objects, in driving order."""
    return [
        {
            "segment": leg.segment,
            "traverse": leg.traverse.value,
            "progress": leg.progress.value,
            "fixed": leg.fixed,
            **({"goal_for_task": leg.goal_for_task} if leg.goal_for_task is not None else {}),
        }
        for leg in plan.legs
    ]


@dataclass(frozen=True, slots=True)
class AlertEvent:
    """A collision alert raised during a run.

    Attributes:
        time: Simulated seconds: the step it was raised at.
        alert: The [`CollisionAlert`][fleetsim.planning.reservations.CollisionAlert]: the segment and
            the vehicles whose reservations overlap on it.
    """

    time: float
    alert: CollisionAlert

    def to_dict(self) -> dict[str, Any]:
        a = self.alert
        return {
            "time": round(self.time, 6),
            "segment": a.segment,
            "primary": list(a.primary),
            "secondary": list(a.secondary),
            "text": a.text(),
        }


@dataclass(frozen=True, slots=True)
class DeadlockReport:
    time: float
    diagnosis: Diagnosis  # why each waiting vehicle waits, the cycles and the root causes

    @property
    def waiting(self) -> tuple[int, ...]:
        return self.diagnosis.waiting

    @property
    def cycle(self) -> tuple[int, ...]:
        """The first (shortest) wait-for cycle; empty if there is none."""
        return self.diagnosis.cycles[0] if self.diagnosis.cycles else ()

    @property
    def message(self) -> str:
        return self.diagnosis.headline()


@dataclass(frozen=True, slots=True)
class Metrics:
    """What a run measured, for comparing planners and runs.

    Attributes:
        makespan: Simulated seconds when the last task was completed, or ``None`` when not all were.
        distance: Metres driven, by vehicle id.
        waiting_time: Seconds each vehicle stood still with tasks pending, by vehicle id.
        planner_calls: How many times the planner was called.
        planner_wall_time: Wall-clock seconds spent inside the planner (never in the trace hash).
        wall_time: Wall-clock seconds for the whole run.
        sim_time: Seconds simulated.
        clearance: The closest any two footprints came (metres), or ``None``: the contact check was off,
            or no two came within its reach (2 m, or the expected clearance if more).
    """

    makespan: float | None
    distance: Mapping[int, float]
    waiting_time: Mapping[int, float]
    planner_calls: int
    planner_wall_time: float
    wall_time: float
    sim_time: float
    clearance: float | None = None

    @property
    def realtime_factor(self) -> float | None:
        """Simulated seconds per wall-clock second, or ``None`` for a run that took no measurable time."""
        return None if self.wall_time <= 0 else self.sim_time / self.wall_time

    def to_dict(self) -> dict[str, Any]:
        harness = max(self.wall_time - self.planner_wall_time, 0.0)
        return {
            "makespan": None if self.makespan is None else round(self.makespan, 6),
            "distance": {str(vid): round(d, 6) for vid, d in sorted(self.distance.items())},
            "waiting_time": {str(vid): round(w, 6) for vid, w in sorted(self.waiting_time.items())},
            "planner_calls": self.planner_calls,
            "planner_wall_time": round(self.planner_wall_time, 6),
            "wall_time": round(self.wall_time, 6),
            "realtime_factor": None if self.realtime_factor is None else round(self.realtime_factor, 3),
            "harness_share": None if self.wall_time <= 0 else round(harness / self.wall_time, 4),
            "clearance": None if self.clearance is None else round(self.clearance, 4),
        }


@dataclass(frozen=True, slots=True)
class Pacing:
    """How a run that a wall clock paced kept its pace, and how soon its planner's orders took effect (a VDA
    5050 master control's): figures of the wall clock, so they vary from run to run and enter no hash.

    Attributes:
        speed: The multiple of real time the run was paced at.
        lag: The most wall seconds a step began behind its paced time (0: the pace was kept throughout).
        late_steps: Steps that began more than one step's wall time behind.
        latencies: Wall seconds from each order's arrival at its vehicle to fleetsim's verdict on its plan,
            in arrival order.
    """

    speed: float
    lag: float
    late_steps: int
    latencies: tuple[float, ...]

    def to_dict(self) -> dict[str, Any]:
        """``pacing`` in ``result.json``: latencies as their count, median, 90th percentile and maximum."""
        ordered = sorted(self.latencies)
        latency = (
            None
            if not ordered
            else {
                "orders": len(ordered),
                "median": round(statistics.median(ordered), 6),
                "p90": round(ordered[min(len(ordered) - 1, math.ceil(0.9 * len(ordered)) - 1)], 6),
                "max": round(ordered[-1], 6),
            }
        )
        return {
            "speed": self.speed,
            "lag_max": round(self.lag, 6),
            "late_steps": self.late_steps,
            "order_latency": latency,
        }


@dataclass(frozen=True, slots=True)
class RunResult:
    """Everything a run produced; ``to_dict`` is its JSON document (``schemas/result.schema.json``): a
    line of ``fleetsim run --json``, a run's ``result.json``, a sweep's record.

    Attributes:
        scenario: The scenario's name.
        planner: The planner's name: the spec it was given by, else its class's name.
        status: ``"passed"`` when the run met its scenario's ``expect``, else ``"failed"``.
        failures: Why it failed, in a fixed order; empty when it passed.
        trace_hash: The hex digest of the run's trace: equal for runs that behaved the same.
        sim_time: Seconds simulated.
        steps: Simulation steps run (``sim_time`` / ``time_step``).
        tasks_total: How many tasks the scenario has.
        tasks_completed: How many of them were completed.
        pending: The tasks not completed, in task order.
        rejections: Every plan rejected, in order ([`RejectionEvent`][fleetsim.sim.result.RejectionEvent]).
        collisions: Every collision alert, in order ([`AlertEvent`][fleetsim.sim.result.AlertEvent]).
        route_errors: Every route error a planner answered, as ``{time, vehicle, message}``.
        ended: How the run ended: ``completed``, ``time-limit``, ``shift-end`` (a shift's normal end),
            ``deadlock``, ``rejection``,
            ``collision`` (a ``stop_on`` event), ``planner-error`` or ``interrupted``.
        deadlock: The deadlock that ended the run (when, who waits for whom), or ``None``.
        metrics: What the run measured ([`Metrics`][fleetsim.sim.result.Metrics]).
        diagnosis: Why tasks were still pending at a deadlock or the time limit, or ``None``.
        checkpoints: ``(step, digest so far)`` every 100 steps, for finding where two runs diverge.
        disturbances: The disturbances that happened, in the order they began.
        paced: The multiple of real time the run was paced at when its planner runs on a wall clock (a VDA
            5050 master control), else ``None``. Such a run's hash is not repeatable, so it is not gated.
        orders: Every order released, in release order, with its times and vehicle (a run with transport
            orders; empty otherwise): ``id``, ``stops``, ``release``, ``deadline``, ``priority``,
            ``vehicle``, ``assigned``, ``started``, ``served``, ``completed``, ``reassigned``,
            ``deadline_missed``.
        measures: What a run with transport orders delivered: throughput, service times, utilisation,
            backlog ([`OrderMeasures`][fleetsim.sim.measures.OrderMeasures]); ``None`` without orders. A
            run of a League of Robot Runners problem also has the competition's counts in its ``lorr``
            ([`LorrCounts`][fleetsim.sim.lorr_counts.LorrCounts]), which the JSON document gives as ``lorr``.
        stalls: A shift's vehicles found with work and not moving for its ``stall_after`` seconds, each with
            its reason and the orders held up ([`Stall`][fleetsim.sim.measures.Stall]), in the order found.
        contact: What the contact check found (contacts, clearance, near misses:
            [`ContactReport`][fleetsim.contact.monitor.ContactReport]), or ``None`` when it was off.
        pacing: How such a run kept its pace and how soon its orders took effect
            ([`Pacing`][fleetsim.sim.result.Pacing]), else ``None``.
        artifacts: Files the run left (recording, picture, trace), by kind; empty unless a caller
            recorded them.
        trace: The trace itself (every step's lines), unless the run was asked not to keep it.
    """

    scenario: str
    planner: str
    status: Literal["passed", "failed"]
    failures: tuple[Failure, ...]
    trace_hash: str
    sim_time: float
    steps: int
    tasks_total: int
    tasks_completed: int
    pending: tuple[Task, ...]
    rejections: tuple[RejectionEvent, ...]
    collisions: tuple[AlertEvent, ...]
    route_errors: tuple[dict[str, Any], ...]
    ended: Ending
    deadlock: DeadlockReport | None
    metrics: Metrics
    diagnosis: Diagnosis | None = None  # why tasks are pending at a deadlock or the time limit
    checkpoints: tuple[tuple[int, str], ...] = ()
    disturbances: tuple[DisturbanceEvent, ...] = ()  # those that happened, in the order they began
    paced: float | None = None  # paced at this many times real time by a planner on a wall clock
    pacing: Pacing | None = None  # how that pace was kept, and the planner's order latencies
    contact: ContactReport | None = None  # contacts, clearance and near misses (None: the check was off)
    orders: tuple[dict[str, Any], ...] = ()  # every released order's life (a run with transport orders)
    measures: OrderMeasures | None = None  # what a run with transport orders delivered
    stalls: tuple[Stall, ...] = ()  # a shift's stalled vehicles, in the order found
    artifacts: Mapping[str, str] = field(default_factory=lambda: MappingProxyType({}))
    trace: Trace | None = field(default=None, compare=False, repr=False)

    @property
    def passed(self) -> bool:
        """Whether ``status`` is ``"passed"``."""
        return self.status == "passed"

    @classmethod
    def unrun(
        cls,
        scenario: str,
        planner: str,
        failures: tuple[Failure, ...] = (),
        *,
        status: Literal["passed", "failed"] = "failed",
        ended: Ending = "load-error",
    ) -> RunResult:
        """The result of a scenario that never ran (it did not load, its planner did not start, a hunt
        ran no example): shaped like any other, with no steps, tasks or hash."""
        metrics = Metrics(None, {}, {}, planner_calls=0, planner_wall_time=0.0, wall_time=0.0, sim_time=0.0)
        return cls(
            scenario=scenario, planner=planner, status=status, failures=failures, trace_hash="", sim_time=0.0,
            steps=0, tasks_total=0, tasks_completed=0, pending=(), rejections=(), collisions=(), route_errors=(),
            ended=ended, deadlock=None, metrics=metrics,
        )  # fmt: skip

    def to_dict(self) -> dict[str, Any]:
        """The run's JSON document, as ``schemas/result.schema.json`` describes it (``trace_hash`` is
        ``None`` for a run that never ran)."""
        return (
            {
                "scenario": self.scenario,
                "planner": self.planner,
                "status": self.status,
                "failures": [f.to_dict() for f in self.failures],
                "trace_hash": self.trace_hash or None,  # None: nothing ran
                "sim_time": round(self.sim_time, 6),
                "steps": self.steps,
                "tasks": {"total": self.tasks_total, "completed": self.tasks_completed},
                "rejections": [r.to_dict() for r in self.rejections],
                "collisions": [c.to_dict() for c in self.collisions],
                "route_errors": list(self.route_errors),
                "ended": self.ended,
                "deadlock": None
                if self.deadlock is None
                else {
                    "time": round(self.deadlock.time, 6),
                    "waiting": list(self.deadlock.waiting),
                    "cycle": list(self.deadlock.cycle),
                    "cycles": [list(cycle) for cycle in self.deadlock.diagnosis.cycles],
                },
                "metrics": self.metrics.to_dict(),
                "disturbances": [d.to_dict() for d in self.disturbances],
                "contact": None if self.contact is None else self.contact.to_dict(),
                "artifacts": dict(self.artifacts),
            }
            | ({} if self.paced is None else {"paced": self.paced})
            | ({} if self.pacing is None else {"pacing": self.pacing.to_dict()})
            | ({"orders": list(self.orders)} if self.orders else {})
            | ({} if self.measures is None else {"measures": self.measures.to_dict()})
            | ({"stalls": [s.to_dict() for s in self.stalls]} if self.measures is not None else {})
            | ({} if self.measures is None or self.measures.lorr is None else {"lorr": self.measures.lorr.to_dict()})
        )


def _first(events: tuple[RejectionEvent, ...] | tuple[AlertEvent, ...]) -> float:
    return events[0].time if events else 0.0


def judge(
    expect: Expectations,
    *,
    ended: Ending,
    end_time: float,
    tasks_total: int,
    tasks_completed: int,
    pending: tuple[Task, ...],
    makespan: float | None,
    rejections: tuple[RejectionEvent, ...],
    collisions: tuple[AlertEvent, ...],
    deadlock: DeadlockReport | None,
    planner_error: Failure | None,
    diagnosis: Diagnosis | None = None,
    interrupted_by: str | None = None,
    contact: ContactReport | None = None,
    open_orders: tuple[str, ...] = (),
    stalls: tuple[Stall, ...] = (),
    stall_ends: bool = False,
    measures: OrderMeasures | None = None,
) -> tuple[Failure, ...]:
    """Every way the run falls short of ``expect`` (SPEC §13), in a fixed order.

    An interrupted run (``interrupted_by``: the signal's name) fails with an ``interrupted`` failure,
    listed first, and keeps the failures of what did happen (rejections, alerts, a planner error);
    what the scenario expected to happen later (tasks, alerts, a deadlock) is not judged: the run
    did not get there.
    """
    if interrupted_by is not None:
        stopped = _interrupted(interrupted_by, end_time, tasks_total, tasks_completed, pending, diagnosis)
        rest = judge(
            expect, ended="completed", end_time=end_time, tasks_total=tasks_total, tasks_completed=tasks_total, pending=(),
            makespan=makespan, rejections=rejections, collisions=collisions, deadlock=None, planner_error=planner_error,
            contact=contact,
        )  # fmt: skip
        return (stopped, *(f for f in rest if f.kind != "expectation"))
    failures: list[Failure] = []
    if planner_error is not None:
        failures.append(planner_error)
    failures += _judge_rejections(expect, rejections)
    failures += _judge_collisions(expect, collisions)
    failures += _judge_contact(expect, contact, end_time)
    if stall_ends and stalls:  # the shift ends at its first stall: that is the failure
        first = stalls[0]
        failures.append(Failure("stall", first.time, first.message(), first.to_dict()))
    if deadlock is not None and not expect.deadlock:
        stuck = {"waiting": list(deadlock.waiting), "cycle": list(deadlock.cycle), **deadlock.diagnosis.to_dict()}
        failures.append(Failure("deadlock", deadlock.time, deadlock.message, stuck))
    if expect.deadlock and deadlock is None:
        failures.append(
            Failure(
                "expectation",
                end_time,
                "the scenario expects a deadlock, but the run ended without one",
                {"expect": "deadlock"},
            )
        )
    wanted = tasks_total if expect.tasks == "all" else expect.tasks
    if ended == "shift-end":  # a shift ends with work under way: what it must deliver is in its measures
        wanted = 0
    elif open_orders and ended == "time-limit" and planner_error is None:
        listing = ", ".join(repr(order) for order in open_orders[:5])
        more = f" and {len(open_orders) - 5} more" if len(open_orders) > 5 else ""
        msg = f"the time limit was reached with {len(open_orders)} orders open: {listing}{more}"
        failures.append(Failure("timeout", end_time, msg, {"open_orders": list(open_orders), "expect": "tasks"}))
    if tasks_completed < wanted and planner_error is None and (deadlock is None or not expect.deadlock):
        listing = ", ".join(f"task {t.id} (vehicle {t.vehicle_id} to segment {t.goal_segment})" for t in pending[:5])
        more = f" and {len(pending) - 5} more" if len(pending) > 5 else ""
        kind = "timeout" if ended == "time-limit" else "expectation"
        reason = "the time limit was reached" if ended == "time-limit" else f"the run ended ({ended})"
        msg = f"{tasks_completed} of {tasks_total} tasks completed, {wanted} expected; {reason} with {listing}{more} pending"
        details: dict[str, Any] = {"pending": [t.id for t in pending], "expect": "tasks"}
        if kind == "timeout" and diagnosis is not None:
            msg = f"{msg}; {diagnosis.headline()}"
            details.update(diagnosis.to_dict())
        failures.append(Failure(kind, end_time, msg, details))
    if measures is not None:
        failures += _judge_measures(expect, measures, end_time)
    if expect.max_makespan is not None and makespan is not None and makespan > expect.max_makespan:
        msg = f"makespan {makespan:.2f} s exceeds max_makespan {expect.max_makespan:g} s"
        failures.append(Failure("expectation", makespan, msg, {"expect": "max_makespan"}))
    return tuple(failures)


def _judge_measures(expect: Expectations, measures: OrderMeasures, end_time: float) -> list[Failure]:
    """Each bound on a measure of a run with orders that the run missed (``min_orders_per_hour``, ...)."""
    failures = []
    for bound in expect.measures:
        value = measures.value(bound.measure)
        details = {"expect": bound.key, "value": value, "bound": bound.value}
        if value is None:
            msg = f"{bound.measure} has no value in this run (no order it is measured over), {bound.key} {bound.value:g} expected"
        elif bound.bound == "min" and value < bound.value - 1e-9:
            msg = f"{bound.measure} {value:.4g} is below {bound.key} {bound.value:g}"
        elif bound.bound == "max" and value > bound.value + 1e-9:
            msg = f"{bound.measure} {value:.4g} exceeds {bound.key} {bound.value:g}"
        else:
            continue
        failures.append(Failure("expectation", end_time, msg, details))
    if expect.overloaded is not None and measures.overloaded != expect.overloaded:
        grows = f"the backlog grows by {measures.backlog_slope:.1f} orders per hour"
        msg = (
            f"the fleet is overloaded: {grows}; the scenario expects it to keep up"
            if measures.overloaded
            else f"the fleet keeps up (backlog slope {measures.backlog_slope:.1f} orders per hour); the scenario expects it overloaded"
        )
        failures.append(Failure("expectation", end_time, msg, {"expect": "overloaded", "value": measures.overloaded}))
    return failures


def _interrupted(
    signal: str,
    end_time: float,
    tasks_total: int,
    tasks_completed: int,
    pending: tuple[Task, ...],
    diagnosis: Diagnosis | None,
) -> Failure:
    msg = f"stopped by {signal} at the end of the step, with {tasks_completed} of {tasks_total} tasks completed"
    details: dict[str, Any] = {"signal": signal, "pending": [t.id for t in pending]}
    if diagnosis is not None and diagnosis.roots:
        msg = f"{msg}; {diagnosis.headline()}"
    if diagnosis is not None:
        details.update(diagnosis.to_dict())
    return Failure("interrupted", end_time, msg, details)


def _rejection_details(rejection: Rejection) -> dict[str, Any]:
    details: dict[str, Any] = {"code": rejection.code.value, "vehicle": rejection.vehicle_id}
    if rejection.leg_index is not None:
        details["leg_index"] = rejection.leg_index
        details["segment"] = rejection.segment
    if rejection.plan is not None:
        details["plan"] = plan_legs(rejection.plan)
    return details


def _judge_rejections(expect: Expectations, rejections: tuple[RejectionEvent, ...]) -> list[Failure]:
    if expect.rejections == "none":
        return [
            Failure("rejection", e.time, f"plan rejected: {e.rejection}", _rejection_details(e.rejection))
            for e in rejections
        ]
    if expect.rejections == "any":
        return (
            []
            if rejections
            else [
                Failure(
                    "expectation",
                    0.0,
                    "the scenario expects plan rejections, but there were none",
                    {"expect": "rejections"},
                )
            ]
        )
    seen = {e.rejection.code.value for e in rejections}
    missing = [code for code in expect.rejections if code not in seen]
    return [
        Failure(
            "expectation",
            _first(rejections),
            f"the scenario expects a {code} rejection, but there was none",
            {"expect": "rejections"},
        )
        for code in missing
    ]


def _judge_contact(expect: Expectations, contact: ContactReport | None, end_time: float) -> list[Failure]:
    """A contact each, unless contacts are expected (then none at all fails, as for collisions); a
    clearance below the expected one."""
    failures = []
    if contact is not None and expect.contacts == "none":
        for c in contact.contacts:
            a, b = c.vehicles
            deep = f", overlapping up to {c.depth:.3f} m" if c.depth > 0 else ""
            msg = f"vehicles {a} and {b} touched at t = {c.time:.2f} s at ({c.x:.2f}, {c.y:.2f}){deep}"
            failures.append(Failure("contact", c.time, msg, c.to_dict()))
    if expect.contacts == "any":
        if contact is None:
            msg = "the scenario expects contacts, but its contact check is off (checks: contact)"
            failures.append(Failure("expectation", end_time, msg, {"expect": "contacts"}))
        elif not contact.contacts:
            msg = "the scenario expects contacts, but no two footprints touched"
            failures.append(Failure("expectation", end_time, msg, {"expect": "contacts"}))
    if expect.clearance is not None:
        if contact is None:
            msg = f"the scenario expects a clearance of {expect.clearance:g} m, but its contact check is off (checks: contact)"
            failures.append(Failure("expectation", end_time, msg, {"expect": "clearance"}))
        elif contact.clearance is not None and contact.clearance.distance < expect.clearance:
            closest = contact.clearance
            a, b = closest.vehicles
            msg = (
                f"vehicles {a} and {b} came within {closest.distance:.3f} m of each other at t = {closest.time:.2f} s "
                f"at ({closest.x:.2f}, {closest.y:.2f}); the scenario expects a clearance of {expect.clearance:g} m"
            )
            failures.append(Failure("expectation", closest.time, msg, {"expect": "clearance", **closest.to_dict()}))
    return failures


def _judge_collisions(expect: Expectations, collisions: tuple[AlertEvent, ...]) -> list[Failure]:
    if expect.collisions == "none":
        return [
            Failure("collision", e.time, str(e.alert), {"segment": e.alert.segment, "vehicles": list(e.alert.vehicles)})
            for e in collisions
        ]
    if expect.collisions == "any":
        return (
            []
            if collisions
            else [
                Failure(
                    "expectation",
                    0.0,
                    "the scenario expects collision alerts, but there were none",
                    {"expect": "collisions"},
                )
            ]
        )
    seen = {e.alert.segment for e in collisions}
    missing = [segment for segment in expect.collisions if segment not in seen]
    return [
        Failure(
            "expectation",
            _first(collisions),
            f"the scenario expects a collision alert on segment {segment}, but there was none",
            {"expect": "collisions"},
        )
        for segment in missing
    ]
