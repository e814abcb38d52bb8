"""The simulation loop, in the fixed order of SPEC §9 (determinism depends on it).

Each step, at time t: (1) bookkeeping — completed tasks leave their queues; (2) planning — every
``planning_period``, each vehicle with tasks, in ascending id, is asked ``plan_routes`` (head task
unrouted) or ``fix_legs``, and each response is checked and applied at once; (3) the reservation check;
(4) motion over [t, t + dt] with task completions; (5) t ← t + dt and the step goes into the trace;
(6) the end: all tasks done, the time limit, a stop-on event, a planner error, deadlock (tasks
pending, nothing moved and no plan changed for ``deadlock_after`` seconds), or a stop signal
(:mod:`fleetsim.sim.interrupt`; ``interrupted``, with an ``["interrupted", signal]`` event in the
step's trace line; a planner call in progress is cut short and the step ends without its answer).

Event times: every event of a step (a rejection, a route error, a planner error, a collision alert, a
completed task, the end of the run) is stamped t + dt, the end of the step it happened in. That is the
time of the step's frame in the trace, the recording and the pictures, so the fleet a reviewer sees at a
reported time is the fleet at that event. The planner's calls of that step see ``fleet.time`` = t.
"""

from __future__ import annotations

import gc
import math
import threading
import time
import traceback
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from itertools import chain
from operator import itemgetter
from pathlib import Path
from types import MappingProxyType
from typing import Any, ClassVar, Literal, cast

import numpy as np

from fleetsim.contact.monitor import Contact, ContactMonitor
from fleetsim.dispatch.protocol import Dispatcher
from fleetsim.errors import PlannerError, ScenarioError
from fleetsim.motion.driver import Driver
from fleetsim.motion.fleet_cruise import FleetCruise, StateColumns
from fleetsim.motion.track import HeadingTable
from fleetsim.planning.controller import CallOutcome, FleetController
from fleetsim.planning.protocol import Planner, SteppedPlanner
from fleetsim.planning.reservations import CollisionAlert
from fleetsim.planning.snapshot import VehicleState
from fleetsim.scenario import Scenario, Task
from fleetsim.sim.diagnosis import Diagnosis, StuckFacts, diagnose
from fleetsim.sim.dispatching import Dispatching
from fleetsim.sim.disturbances import Disturber
from fleetsim.sim.guard import PlannerFault, PlannerGuard
from fleetsim.sim.interrupt import PlannerInterrupted, StopSignals, signal_name
from fleetsim.sim.measures import Stall
from fleetsim.sim.result import (
    AlertEvent,
    DeadlockReport,
    Ending,
    Failure,
    Metrics,
    Pacing,
    RejectionEvent,
    RunResult,
    judge,
)
from fleetsim.sim.stalls import StallWatch
from fleetsim.sim.trace import Trace, TraceFile, plan_record
from fleetsim.specs.dispatcher import DispatcherSpecError, import_dispatcher_factory

__all__ = ["RunProgress", "run_scenario"]

# Metres: two footprints farther apart than this do not count towards a run's clearance (it is "more").
_CLEARANCE_REACH = 2.0
# A vehicle state's pose (x, y, heading), for the contact check: a slice of the named tuple, which reads
# the three fields at once (faster than by name).
_X = VehicleState._fields.index("x")
assert VehicleState._fields[_X : _X + 3] == ("x", "y", "heading")
_POSE = itemgetter(slice(_X, _X + 3))


@dataclass(frozen=True, slots=True)
class RunProgress:
    """Where a run is, for a live progress line."""

    time: float
    steps: int
    completed: int
    total: int


class _Run:
    """The mutable state of one run; everything a result is built from."""

    # Cruising vehicles stepped together in arrays (FleetCruise): None, when the fleet is large enough
    # for that to pay; True or False always or never (for tests that compare the two). Class variables,
    # so that setting them on the class reaches the compiled build too (fleetsim/compiled.py).
    batched: ClassVar[bool | None] = None
    # A planner's quiet hint honoured (fleetsim.planning.quiet); False for tests that compare the two.
    quiet: ClassVar[bool] = True

    def __init__(
        self,
        scenario: Scenario,
        planner: Planner,
        guard: PlannerGuard,
        keep_trace: bool,
        dispatcher: Dispatcher | None = None,
    ) -> None:
        self.scenario = scenario
        self.planner = planner
        self.guard = guard
        self.settings = scenario.settings
        self.controller = FleetController(scenario, invoke=guard, invoke_round=guard.round, quiet=self.quiet)
        headings = HeadingTable(scenario.layout)
        states = self.controller.states
        self.drivers = {
            v.id: Driver(v, scenario.layout, headings, states[v.id].heading)
            for v in sorted(scenario.vehicles, key=lambda v: v.id)
        }
        self.ids = list(self.drivers)
        self.driver_list = list(self.drivers.values())
        batched = len(self.driver_list) >= FleetCruise.SMALLEST if self.batched is None else self.batched
        self.cruise = FleetCruise(self.driver_list, batched=batched)
        self.trace = Trace(keep_lines=keep_trace)
        # Only a scenario with disturbances has a disturber: without, the run (and its hash) is as before.
        # It reaches the drivers through the cruise, which hands each back up to date first.
        has_disturbances = bool(scenario.disturbances) or scenario.random_disturbances is not None
        self.disturber = Disturber(scenario, self.cruise.released, self.controller) if has_disturbances else None
        self.rejections: list[RejectionEvent] = []
        self.collisions: list[AlertEvent] = []
        self.route_errors: list[dict[str, Any]] = []
        self.active_alerts: tuple[CollisionAlert, ...] = ()  # the last check's, by segment
        self.waiting_time = dict.fromkeys(self.drivers, 0.0)
        shift = scenario.shift
        index = {vehicle: i for i, vehicle in enumerate(self.ids)}
        self.stall_watch = StallWatch(shift.stall_after, index) if shift is not None else None
        # Only a scenario with transport orders dispatches (fleetsim.sim.dispatching): without, as before.
        self.dispatching = (
            Dispatching(scenario, dispatcher, self.controller, self.cruise.released, guard.dispatch)
            if dispatcher is not None
            else None
        )
        self.last_activity = 0.0
        # For explaining a stuck fleet at the end (never hashed): when each vehicle last moved, when the
        # planner last changed its plan, and how many changed plans were accepted in all.
        self.last_moved = np.full(len(self.ids), np.nan)  # by index; NaN: never
        self.plan_changed: dict[int, float] = {}
        self.accepted_plans = 0
        self.planner_error: Failure | None = None
        self.interrupted_planning = False
        self.stepped = planner if isinstance(planner, SteppedPlanner) else None
        self.paused: set[int] = set()  # the vehicles a stepped planner holds still (a pause: an event)
        self.awaiting: set[int] = set()  # those that stand until a plan of its is accepted for them
        self.held: set[int] = set()  # both: the drivers halted
        # The contact check (fleetsim.contact): every vehicle's pose, by index, kept up to date from what
        # moved; contacts, clearance and near misses are judged from it and enter no trace.
        checks = scenario.settings.checks
        self.stepped_at: list[int] = []  # the indices of the vehicles the last step moved one by one
        self.poses = np.array(
            [[states[v].x for v in self.ids], [states[v].y for v in self.ids], [states[v].heading for v in self.ids]]
        )
        types = {v.id: v.type for v in scenario.vehicles}
        self.contact = (
            ContactMonitor(
                self.ids,
                [types[v].length for v in self.ids],
                [types[v].width for v in self.ids],
                safety_margin=checks.safety_margin,
                near_miss=checks.near_miss,
                reach=max(_CLEARANCE_REACH, scenario.expect.clearance or 0.0),
            )
            if checks.contact
            else None
        )

    # -- the steps -----------------------------------------------------------------------------------

    def begin_step(self, now: float, stamp: float, events: list[list[Any]]) -> bool:
        """Tell a stepped planner (:class:`SteppedPlanner`) that the step at ``now`` begins, every vehicle's
        state brought up to date first; record the messages it refused as rejections. False when it
        failed and the run must end."""
        assert self.stepped is not None
        self.cruise.release_all()  # the snapshot holds every vehicle where it is now
        try:
            refused = list(self.stepped.begin_step(self.controller.snapshot(now), self.scenario.layout))
        except PlannerError as exc:  # a fault the planner names itself (a master control gone): its sentence
            self._planner_failed(exc, stamp, events)
            return False
        except Exception as exc:
            fault = PlannerFault(f"begin_step raised {type(exc).__name__}: {exc}", details=traceback.format_exc())
            self._planner_failed(fault, stamp, events)
            return False
        for rejection in refused:
            self.rejections.append(RejectionEvent(stamp, rejection))
            events.append(["reject", rejection.code.value, rejection.vehicle_id, rejection.leg_index])
        asked = getattr(self.stepped, "paused", None)
        paused = set(asked()) if callable(asked) else set()
        awaiting = getattr(self.stepped, "awaiting_plan", None)
        self.awaiting = set(awaiting()) if callable(awaiting) else set()
        self._hold(paused | self.awaiting)
        for vehicle in sorted(paused - self.paused):
            events.append(["disturb", vehicle, "pause"])  # shown and recorded as a stop
        for vehicle in sorted(self.paused - paused):
            events.append(["resume", vehicle, "pause"])
        self.paused = paused
        return True

    def all_done(self) -> bool:
        """Every task done and, with orders, every order completed and none to come."""
        done = self.controller.tasks.all_done()
        return done if self.dispatching is None else done and self.dispatching.done()

    def has_work(self) -> bool:
        """Some vehicle has a task or some order is open (a fleet waiting for orders, or done with its tasks
        before its shift ends, is not stuck)."""
        if self.controller.tasks.heads():
            return True
        return self.dispatching is not None and self.dispatching.book.open_count() > 0

    def dispatch(self, step: int, now: float, stamp: float, events: list[list[Any]]) -> bool:
        """Dwells, releases and the dispatcher's call at the start of the step; False when the dispatcher
        failed (raised, overran its time, answered garbage) and the run must end."""
        assert self.dispatching is not None
        try:
            refused = self.dispatching.begin_step(step, now, stamp, events)
        except (PlannerFault, PlannerError) as fault:
            self._planner_failed(fault, stamp, events)
            return False
        except PlannerInterrupted:  # a stop signal in the dispatcher's call: the step ends without its answer
            self.guard.forget_call()
            self.interrupted_planning = True
            return True
        for rejection in refused:
            self.rejections.append(RejectionEvent(stamp, rejection))
            events.append(["reject", rejection.code.value, rejection.vehicle_id, rejection.leg_index])
        if self.dispatching.dwelling() or any(e[0] in ("release", "assign", "served") for e in events):
            self.last_activity = now  # a vehicle dwelling at a stop will drive on: the deadlock timer waits
        return True

    def _hold(self, held: set[int]) -> None:
        """Halt the vehicles newly held still (they brake within their fixed legs), release the others."""
        for vehicle in sorted(held - self.held):
            self.drivers[vehicle].halt()
        for vehicle in sorted(self.held - held):
            self.drivers[vehicle].release()
        self.held = held

    def plan(self, now: float, stamp: float, events: list[list[Any]], plans: list[list[Any]]) -> bool:
        """Step 2 at ``now`` (what the planner sees); its events are stamped ``stamp``, the step's end.
        False when the planner failed and the run must end. A stop signal during a planner call ends
        the planning of the step there (``interrupted_planning``); the call's answer is not waited for."""
        try:
            for outcome in self.controller.consult_all(self.planner, now):
                self._note(outcome, now, stamp, events, plans)
        except (PlannerFault, PlannerError) as fault:
            self._planner_failed(fault, stamp, events)
            return False
        except PlannerInterrupted:
            self.guard.forget_call()
            self.interrupted_planning = True
        return True

    def _planner_failed(self, fault: PlannerFault | PlannerError, stamp: float, events: list[list[Any]]) -> None:
        details: dict[str, Any] = {"vehicle": fault.vehicle_id}
        if isinstance(fault, PlannerFault) and fault.details:
            details["traceback"] = fault.details
        self.planner_error = Failure("planner-error", stamp, str(fault), details)
        events.append(["planner-error", fault.vehicle_id])

    def _note(
        self, outcome: CallOutcome, now: float, stamp: float, events: list[list[Any]], plans: list[list[Any]]
    ) -> None:
        for plan in outcome.accepted:
            plans.append(plan_record(plan))
            if plan.vehicle_id in self.awaiting:  # it may drive what the plan fixes from this step on
                self.awaiting.discard(plan.vehicle_id)
                self._hold(self.paused | self.awaiting)
            if plan.vehicle_id != outcome.vehicle_id or plan != outcome.previous:
                self.last_activity = now
                self.plan_changed[plan.vehicle_id] = stamp
                self.accepted_plans += 1
        for rejection in outcome.rejections:
            self.rejections.append(RejectionEvent(stamp, rejection))
            events.append(["reject", rejection.code.value, rejection.vehicle_id, rejection.leg_index])
        for error in outcome.route_errors:
            vehicle = error.vehicle_id if error.vehicle_id is not None else outcome.vehicle_id
            self.route_errors.append({"time": round(stamp, 6), "vehicle": vehicle, "message": error.message})
            events.append(["route-error", vehicle, error.message])
        for task_id in outcome.completed:
            events.append(["complete", task_id])
            self.last_activity = now
            if self.dispatching is not None:
                self.dispatching.reached(task_id, stamp, events)

    def check_reservations(self, stamp: float, events: list[list[Any]]) -> int:
        """Step 3; alerts are reported when they appear, not again while they persist. The index keeps an
        alert the same object while its holders stay the same, and the check hands back the same tuple
        while no plan changed, so what is new is found without comparing every alert in force."""
        alerts = self.controller.alerts()
        if alerts is self.active_alerts:
            return 0
        before = {alert.segment: alert for alert in self.active_alerts}
        fresh = [
            alert
            for alert in alerts  # by segment, one alert each
            if (old := before.get(alert.segment)) is not alert and old != alert
        ]
        self.active_alerts = alerts
        for alert in fresh:
            self.collisions.append(AlertEvent(stamp, alert))
            events.append(["alert", alert.segment, list(alert.primary), list(alert.secondary)])
        return len(fresh)

    def move(self, dt: float, end: float, events: list[list[Any]]) -> tuple[list[VehicleState], StateColumns]:
        """Step 4: every vehicle over the step ending at ``end``; entering a goal leg completes its task.

        The vehicles that cruise all step long are stepped together (:class:`FleetCruise`); the rest one
        by one, after which those that may cruise on are armed for the next step. (The per-vehicle path
        reads the motion's fields directly.) Returns the new states of the vehicles that moved, each part
        ascending by id: those stepped one by one, and the cruising ones with their columns (for the
        trace).
        """
        controller = self.controller
        tasks = controller.tasks
        plan_of = controller.plan_of
        cruise = self.cruise
        arming = cruise.batched
        replanned = controller.take_replanned()
        if arming:
            cruise.forget(replanned, plan_of)
        cruised, others = cruise.step(dt)
        busy = tasks.heads()  # the vehicles with tasks
        waiting = self.waiting_time
        ids = self.ids
        drivers = self.driver_list
        stepped: list[VehicleState] = []
        stepped_at: list[int] = []  # their indices
        for i in others:
            vehicle_id = ids[i]
            driver = drivers[i]
            plan = plan_of(vehicle_id)
            if driver.still_on is plan:  # standing still with nothing new to drive: the step changes nothing
                if vehicle_id in busy:
                    waiting[vehicle_id] += dt
                continue
            cruised_alone = driver.cruise(plan, dt)  # the commonest step, in short; None for any other
            if cruised_alone is not None:
                state = cruised_alone[0]
            else:
                new_plan, entered, distance, turned, step_state = driver.step(plan, dt)
                if new_plan is not plan:
                    controller.drive_past(new_plan)
                    plan = new_plan
                for leg in entered:
                    if leg.goal_for_task is not None and tasks.complete(leg.goal_for_task, end):
                        events.append(["complete", leg.goal_for_task])
                        if self.dispatching is not None:
                            self.dispatching.reached(leg.goal_for_task, end, events)
                if not (distance > 0.0 or turned or entered):
                    if vehicle_id in busy:
                        waiting[vehicle_id] += dt
                    if arming:
                        cruise.arm(i, plan)
                    continue
                state = step_state or driver.moved_state(plan)
            stepped.append(state)
            stepped_at.append(i)
            if arming:
                cruise.arm(i, plan)
        self.stepped_at = stepped_at
        if stepped or cruised.ids:
            self.last_activity = end
            self.last_moved.put(stepped_at, end)  # (faster than indexing with a list)
            self.last_moved[cruised.positions] = end
            controller.set_states([ids[i] for i in stepped_at], stepped)
            controller.set_states(cruised.ids, cruised.states)
        return stepped, cruised

    def check_contacts(
        self, start: float, end: float, stepped: list[VehicleState], cruised: StateColumns | None
    ) -> list[Contact]:
        """The contacts that began in the step from ``start`` to ``end``, the poses brought up to date
        with what moved in it."""
        contact = self.contact
        assert contact is not None
        if contact.few or not self.cruise.batched:
            # Told only what moved (the monitor keeps the poses; self.poses is not kept up to date then): it
            # judges the step in plain Python while few moved, as vehicles stepped one by one mostly are.
            moved_at, moved_poses = list(self.stepped_at), list(map(_POSE, stepped))
            if cruised is not None and len(cruised.positions):
                moved_at += cruised.positions.tolist()
                moved_poses += zip(*cruised.motion[1:4].tolist(), strict=True)
            return contact.step_moved(start, end, moved_at, moved_poses)
        poses = self.poses
        if stepped:  # by index, as move() stepped them
            values = np.fromiter(chain.from_iterable(map(_POSE, stepped)), dtype=np.float64, count=3 * len(stepped))
            at = np.array(self.stepped_at, dtype=np.intp)
            poses.T[at] = values.reshape(-1, 3)  # (rows of the transposed view: twice as fast)
        if cruised is not None and len(cruised.positions):
            poses[:, cruised.positions] = cruised.motion[1:4]
        moved = self.last_moved == end  # move() stamps each vehicle that moved with the step's end
        return contact.step(start, end, poses[0], poses[1], poses[2], moved)

    def diagnose(self, kind: Literal["deadlock", "timeout"], now: float) -> Diagnosis:
        """Why the vehicles with pending tasks have not finished them (at the run's end)."""
        controller = self.controller
        heads = controller.tasks.heads()
        facts = StuckFacts(
            kind=kind,
            time=now,
            layout=self.scenario.layout,
            plans=controller.plans,
            states=controller.states,
            heads=heads,
            last_moved={
                vehicle: moved
                for vehicle, moved in zip(self.ids, self.last_moved.tolist(), strict=True)
                if not math.isnan(moved)
            },
            plan_changed=self.plan_changed,
            route_errors=self.route_errors,
            accepted_plans=self.accepted_plans,
            notes=self.wait_notes(heads, now),
        )
        return diagnose(facts)

    def check_stalls(self, end: float, events: list[list[Any]]) -> list[Stall]:
        """A shift's vehicles found stalled at ``end`` (fleetsim.sim.stalls), each explained as a stuck
        fleet is, with the orders held up."""
        assert self.dispatching is not None and self.stall_watch is not None
        dispatching = self.dispatching
        found = self.stall_watch.look(
            end, self.controller.tasks.heads(), self.last_moved.tolist(), dispatching.is_dwelling
        )
        if not found:
            return []
        findings = {finding.vehicle: finding for finding in self.diagnose("deadlock", end).findings}
        stalls = []
        for vehicle in found:
            events.append(["stall", vehicle])
            reason = findings[vehicle].text() if vehicle in findings else f"vehicle {vehicle} stands"
            since = self.stall_watch.stalled[vehicle]
            stalls.append(Stall(vehicle, since, end, dispatching.book.sequence(vehicle), reason))
        return stalls

    def wait_notes(self, heads: Mapping[int, Task], now: float) -> dict[int, str]:
        """A stepped planner's word on why each vehicle with a pending task waits (``explain_wait``), if it
        has one; a planner that raises is named in the note instead, and the diagnosis goes on."""
        explain = getattr(self.stepped, "explain_wait", None)
        if not callable(explain):
            return {}
        notes = {}
        for vehicle in sorted(heads):
            try:
                note = explain(vehicle, now)
            except Exception as exc:
                note = f"(the planner's explain_wait raised {type(exc).__name__}: {exc})"
            if note:
                notes[vehicle] = str(note)
        return notes


def run_scenario(
    scenario: Scenario,
    planner: Planner,
    *,
    planner_name: str = "",
    planner_timeout: float | None = 10.0,
    keep_trace: bool = True,
    on_progress: Callable[[RunProgress], None] | None = None,
    stop: StopSignals | None = None,
    trace_file: Path | None = None,
    watch: Callable[[str], None] | None = None,
    dispatcher: Dispatcher | None = None,
) -> RunResult:
    """Simulate ``scenario`` with ``planner`` (a fresh instance) and judge the run against its ``expect``.

    A planner with a ``close()`` method (a planner process, say) is closed when the run ends, however it ends.
    ``stop``: the active ``StopSignals``; once it has received a signal, the run ends at the end of
    the step (``ended: "interrupted"``). ``trace_file``: where to write the trace while the run goes
    (``TraceFile``); it holds every step written, however the run ends. ``watch``: called with each trace
    line as it is written, in the loop's thread (a live view: it may pace the run, never change it).
    ``dispatcher``: a fresh dispatcher for a scenario with transport orders; without one, the planner is
    the dispatcher if it has a ``dispatch`` method. A scenario with orders and neither fails at once.
    """
    if scenario.orders or scenario.order_stream is not None:
        try:
            dispatcher = _dispatcher_for(scenario, planner, dispatcher)
        except (DispatcherSpecError, ScenarioError, PlannerError) as error:
            details = getattr(error, "details", "") if isinstance(error, PlannerError) else ""
            failure = Failure("planner-error", 0.0, str(error), {"traceback": details} if details else {})
            close = getattr(planner, "close", None)
            if callable(close):  # a planner process started to say whether it dispatches
                close()
            return RunResult.unrun(
                scenario.name, planner_name or type(planner).__name__, (failure,), ended="planner-error"
            )
    else:
        dispatcher = None
    sink = TraceFile(trace_file) if trace_file is not None else None
    try:
        with PlannerGuard(planner_timeout) as guard, _COLLECTOR.spared(len(scenario.vehicles)):
            if stop is not None:
                stop.guard = guard
            return _simulate(
                scenario, planner, guard, planner_name, keep_trace, on_progress, stop, sink, watch, dispatcher
            )
    finally:
        if stop is not None:
            stop.guard = None
        try:
            if sink is not None:
                sink.close()
        finally:
            close = getattr(planner, "close", None)
            if callable(close):
                close()


class _Collector:
    """The cyclic garbage collector tuned for runs, for as long as any run in the process goes.

    What exists when a run starts (the scenario, its layout, conflict tables and the planner's own
    tables: millions of objects for a large site) is set aside (``gc.freeze``): otherwise each full
    collection walks it all again (2 s a time for 10,000 vehicles). And the youngest generation is
    collected after a number of new objects that grows with the fleet, not after every 700: a step's own
    objects live for one step, and with a fixed threshold a large fleet's step spans many collections,
    every one of which found them alive and moved them on to the older generations, which are walked
    again and again. Nothing set aside is freed or changed; all is handed back when the last run ends,
    however it ends. Collection timing never touches a result or a hash.
    """

    # New objects per vehicle before a collection of the youngest generation: about five steps' worth. A
    # run makes next to no cyclic garbage (its collections find none), and what a collection costs is the
    # objects that are still alive then, so fewer collections cost less: at 10,000 vehicles over 20 s,
    # 616 ms of collections instead of 1,104 with 20 per vehicle (about one step), and 11.22-11.35 us of
    # harness per vehicle-step against 11.31-11.71; the peak memory is the same (3.63-3.66 GiB).
    OBJECTS_PER_VEHICLE = 100

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._runs = 0
        self._thresholds = gc.get_threshold()

    @contextmanager
    def spared(self, vehicles: int) -> Iterator[None]:
        with self._lock:
            if self._runs == 0:
                self._thresholds = gc.get_threshold()
            self._runs += 1
            young, *older = gc.get_threshold()
            gc.set_threshold(max(young, self.OBJECTS_PER_VEHICLE * vehicles), *older)
            gc.freeze()
        try:
            yield
        finally:
            with self._lock:
                self._runs -= 1
                if self._runs == 0:
                    gc.unfreeze()
                    gc.set_threshold(*self._thresholds)

    def set_aside(self) -> None:
        """What a run built before its first step (its tables, its drivers), too."""
        gc.freeze()


_COLLECTOR = _Collector()


def _simulate(
    scenario: Scenario,
    planner: Planner,
    guard: PlannerGuard,
    planner_name: str,
    keep_trace: bool,
    on_progress: Callable[[RunProgress], None] | None,
    stop: StopSignals | None,
    sink: TraceFile | None,
    watch: Callable[[str], None] | None = None,
    dispatcher: Dispatcher | None = None,
) -> RunResult:
    started = time.perf_counter()
    run = _Run(scenario, planner, guard, keep_trace, dispatcher)
    _COLLECTOR.set_aside()
    run.trace.sink = sink
    run.trace.watcher = watch
    settings = scenario.settings
    dt = settings.time_step
    period = max(1, round(settings.planning_period / dt))
    shift = scenario.shift
    max_steps = max(1, math.ceil((shift.duration if shift is not None else settings.time_limit) / dt - 1e-9))
    header: dict[str, Any] = {
        "time_step_us": round(dt * 1e6),
        "planning_period_steps": period,
        "vehicles": [v.id for v in sorted(scenario.vehicles, key=lambda v: v.id)],
        "tasks": len(scenario.tasks),
    }
    if run.disturber is not None:
        header["disturbances"] = run.disturber.header()
    if run.dispatching is not None:
        header["orders"] = run.dispatching.header()
    run.trace.begin(header)
    if run.contact is not None:
        run.contact.begin(run.poses[0], run.poses[1], run.poses[2])
    ended: Ending = "time-limit"
    deadlock: DeadlockReport | None = None
    # A shift looks for stalled vehicles every simulated second.
    stall_every = max(1, round(1.0 / dt)) if shift is not None and run.dispatching is not None else 0
    stalls: list[Stall] = []
    step = 0
    for step in range(max_steps):
        now = step * dt
        events: list[list[Any]] = []
        plans: list[list[Any]] = []
        run.controller.bookkeeping()
        if run.disturber is not None and run.disturber.step(now, events):
            run.last_activity = now  # a vehicle stands in a stop: the deadlock timer counts from its end
        # Every event of the step is stamped with its end, when the step enters the trace and the recording
        # (the planner is asked at ``now``). Times are multiples of dt, never sums of them.
        end = (step + 1) * dt
        planned_ok = run.dispatch(step, now, end, events) if run.dispatching is not None else True
        if planned_ok and run.stepped is not None:
            planned_ok = run.begin_step(now, end, events)
        if planned_ok and step % period == 0 and not run.interrupted_planning:
            planned_ok = run.plan(now, end, events, plans)
        rejected = any(e[0] == "reject" for e in events)
        alerted = run.check_reservations(end, events) > 0 if planned_ok and settings.checks.reservations else False
        moved, cruised = run.move(dt, end, events) if planned_ok else ([], None)
        touched = (
            bool(run.check_contacts(now, end, moved, cruised)) if planned_ok and run.contact is not None else False
        )
        stalled = False
        if stall_every and planned_ok and step % stall_every == 0:
            found = run.check_stalls(end, events)
            stalls += found
            stalled = bool(found)
        # The trace holds what changed; at step 0 that is everyone (the start), later only who moved.
        if step == 0:
            moved, cruised = [run.controller.state_of(v) for v in run.drivers], None
        if not planned_ok:
            ended = "planner-error"
        elif run.interrupted_planning:  # the step's planning was cut short: no other ending can be judged
            ended = "interrupted"
        elif shift is None and run.all_done():  # a shift runs its length: its end is the normal one
            ended = "completed"
        elif rejected and "rejection" in settings.stop_on:
            ended = "rejection"
        elif alerted and "collision" in settings.stop_on:
            ended = "collision"
        elif touched and "contact" in settings.stop_on:
            ended = "contact"
        elif stalled and shift is not None and shift.on_stall == "end":
            ended = "stall"
        elif end - run.last_activity >= settings.deadlock_after - 1e-9 and run.has_work():
            ended = "deadlock"
            deadlock = DeadlockReport(end, run.diagnose("deadlock", end))
        elif stop is not None and stop.requested:
            ended = "interrupted"
        else:
            run.trace.record(step, moved, plans, events, cruised)
            if on_progress is not None and step % 50 == 0:
                on_progress(
                    RunProgress(end, step + 1, len(run.controller.tasks.completed()), run.controller.tasks.total)
                )
            continue
        if ended == "interrupted":
            events.append(["interrupted", signal_name(stop.signum or 0) if stop is not None else "signal"])
        run.trace.record(step, moved, plans, events, cruised)
        break
    run.cruise.release_all()  # the drivers' odometers up to date
    if ended == "time-limit" and shift is not None:
        ended = "shift-end"
    steps = step + 1
    sim_time = steps * dt
    completed = run.controller.tasks.completed()
    diagnosis = deadlock.diagnosis if deadlock is not None else None
    if ended in ("time-limit", "interrupted") and not run.controller.tasks.all_done():
        diagnosis = run.diagnose("timeout", sim_time)  # who is still driving, who waits for whom
    makespan = max(completed.values()) if completed and run.all_done() else None
    orders = run.dispatching.book.records if run.dispatching is not None else {}
    if orders and run.all_done():
        makespan = max((r.completed for r in orders.values() if r.completed is not None), default=makespan)
    open_orders = tuple(o for o, r in orders.items() if r.completed is None)
    contact = run.contact.report() if run.contact is not None else None
    measures = run.dispatching.measures(sim_time, stalls) if run.dispatching is not None else None
    failures = judge(
        scenario.expect,
        ended=ended,
        end_time=sim_time,
        tasks_total=run.controller.tasks.total,
        tasks_completed=len(completed),
        pending=run.controller.tasks.pending(),
        makespan=makespan,
        rejections=tuple(run.rejections),
        collisions=tuple(run.collisions),
        deadlock=deadlock,
        planner_error=run.planner_error,
        contact=contact,
        diagnosis=diagnosis,
        interrupted_by=signal_name(stop.signum or 0) if ended == "interrupted" and stop is not None else None,
        open_orders=open_orders,
        stalls=tuple(stalls),
        stall_ends=shift is not None and shift.on_stall == "end",
        measures=measures,
    )
    metrics = Metrics(
        makespan=makespan,
        distance=MappingProxyType({vid: d.odometer for vid, d in run.drivers.items()}),
        waiting_time=MappingProxyType(dict(run.waiting_time)),
        planner_calls=guard.calls,
        planner_wall_time=guard.wall_time,
        wall_time=time.perf_counter() - started,
        sim_time=sim_time,
        clearance=None if contact is None or contact.clearance is None else contact.clearance.distance,
    )
    return RunResult(
        scenario=scenario.name,
        planner=planner_name or type(planner).__name__,
        status="failed" if failures else "passed",
        failures=failures,
        trace_hash=run.trace.digest,
        sim_time=sim_time,
        steps=steps,
        tasks_total=run.controller.tasks.total,
        tasks_completed=len(completed),
        pending=run.controller.tasks.pending(),
        rejections=tuple(run.rejections),
        collisions=tuple(run.collisions),
        route_errors=tuple(run.route_errors),
        ended=ended,
        deadlock=deadlock,
        metrics=metrics,
        diagnosis=diagnosis,
        checkpoints=tuple(run.trace.checkpoints),
        disturbances=run.disturber.happened() if run.disturber is not None else (),
        paced=_paced(planner),
        pacing=_pacing(planner),
        contact=contact,
        orders=tuple(record.to_dict() for record in orders.values()),
        measures=measures,
        stalls=tuple(stalls),
        trace=run.trace if keep_trace else None,
    )


NO_DISPATCHER = (
    "scenario {name!r} has transport orders but no dispatcher: name one (--dispatcher module:Class, or the "
    "suite's 'dispatcher:'), or give the planner a dispatch(board, fleet, layout) method"
)


def _dispatcher_for(scenario: Scenario, planner: Planner, given: Dispatcher | None) -> Dispatcher:
    """The run's dispatcher: the one given, else a fresh one of the spec the scenario names (its suite's
    ``dispatcher:``), else the planner itself when it is a dispatcher too (one object, both jobs)."""
    if given is not None:
        return given
    if scenario.dispatcher is not None:
        return import_dispatcher_factory(scenario.dispatcher)()
    begin_run = getattr(planner, "begin_run", None)
    if callable(begin_run):  # a planner process starts now: its ready message says whether it dispatches
        begin_run(scenario)
    if callable(getattr(planner, "dispatch", None)):
        return cast(Dispatcher, planner)
    raise ScenarioError(NO_DISPATCHER.format(name=scenario.name))


def _pacing(planner: Planner) -> Pacing | None:
    """How a planner on a wall clock kept the pace (its ``pacing()``), else None; one that raises or answers
    something else is left out: these figures judge nothing."""
    asked = getattr(planner, "pacing", None)
    if not callable(asked):
        return None
    try:
        pacing = asked()
    except Exception:
        return None
    return pacing if isinstance(pacing, Pacing) else None


def _paced(planner: Planner) -> float | None:
    """The speed a planner on a wall clock paced the run at (its ``paced`` attribute), else None."""
    speed = getattr(planner, "paced", None)
    return float(speed) if isinstance(speed, int | float) and not isinstance(speed, bool) else None
