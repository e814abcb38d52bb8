"""The fleet controller: consults the planner, checks and applies its plans, keeps tasks and alerts.

This is steps 1–3 of the loop (SPEC §9): bookkeeping, planning for each vehicle in ascending id (head
task unrouted → ``plan_routes``, else ``fix_legs``; each response checked and applied at once so later
calls see it), and the reservation check. Motion comes on top of it.

A planner that answers a round's calls in one go (a :class:`~fleetsim.planning.protocol.RoundPlanner`)
is asked about all the calls left at once; it answers them in order up to the first that changes
something, which are applied exactly as if made one by one, and the calls after it are asked again,
against the fleet as changed. Every other planner is called one call at a time, as before.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any, Literal, cast

from fleetsim.errors import PlannerError
from fleetsim.layout.layout import Layout
from fleetsim.planning.checks import CheckContext, DriveMemo, Rejection, check_plans
from fleetsim.planning.plans import FleetPlan, RouteError, hands_back
from fleetsim.planning.protocol import Planner, RoundCall, RoundPlanner
from fleetsim.planning.quiet import Quiet, Resting
from fleetsim.planning.reservations import CollisionAlert, ConflictTable, ReservationIndex
from fleetsim.planning.snapshot import FleetSnapshot, PlanLog, VehicleState, initial_plan, initial_state, read_only
from fleetsim.planning.tasks import TaskBook
from fleetsim.planning.views import LiveCopy, held_only_here
from fleetsim.scenario import Scenario, Task

__all__ = ["CallOutcome", "FleetController", "validate_response"]

Method = Literal["plan_routes", "fix_legs"]
# How a planner method is called: (method name, bound method, vehicle id, task, snapshot, layout).
Invoke = Callable[[str, Callable[..., object], int, Task, FleetSnapshot, Layout], object]
# At most this many calls in one round message. A round may take the per-call timeout once per call, so
# this bounds how long a hung planner goes unnoticed (8 x the per-call timeout); the round trip a round
# saves is already small per call at 8 (a pipe round trip is 4-12 us).
ROUND_CALLS = 8

# How a round is asked: (the planner's plan_round, the calls, snapshot, layout) -> the answers' responses.
InvokeRound = Callable[
    [Callable[..., Sequence[tuple[object, float | None]]], Sequence[RoundCall], FleetSnapshot, Layout], Sequence[object]
]


def _direct(
    method: str, call: Callable[..., object], vehicle_id: int, task: Task, fleet: FleetSnapshot, layout: Layout
) -> object:
    return call(task, fleet, layout)


def _direct_round(
    call: Callable[..., Sequence[tuple[object, float | None]]],
    calls: Sequence[RoundCall],
    fleet: FleetSnapshot,
    layout: Layout,
) -> list[object]:
    return [response for response, _seconds in call(calls, fleet, layout)]


def _optional(planner: object, name: str) -> Callable[..., Any] | None:
    """The planner's optional method ``name``, or None when it has none."""
    method = getattr(planner, name, None)
    return method if callable(method) else None


@dataclass(frozen=True, slots=True)
class CallOutcome:
    """What one planner call did: plans accepted, plans rejected, route errors, tasks completed."""

    vehicle_id: int
    method: Method
    task: Task
    previous: FleetPlan  # the vehicle's plan in force when it was consulted
    accepted: tuple[FleetPlan, ...]
    rejections: tuple[Rejection, ...]
    route_errors: tuple[RouteError, ...]
    completed: tuple[int, ...]  # task ids whose goal leg an accepted plan put under the vehicle


def validate_response(response: object, method: Method, vehicle_id: int) -> tuple[FleetPlan | RouteError, ...]:
    """The response's items, or a :class:`PlannerError` saying exactly what is wrong with it."""
    if type(response) is list and not response:
        return ()  # the common "nothing to change"
    where = f"{method}() for vehicle {vehicle_id}"
    if isinstance(response, (str, bytes, Mapping)) or not isinstance(response, Sequence):
        msg = f"{where} returned {response!r}; it must return a list of FleetPlan or RouteError items"
        raise PlannerError(msg, vehicle_id=vehicle_id)
    for index, item in enumerate(response):
        if not isinstance(item, (FleetPlan, RouteError)):
            msg = f"{where} returned item {index} = {item!r}; each item must be a FleetPlan or a RouteError"
            raise PlannerError(msg, vehicle_id=vehicle_id)
    return tuple(response)


class FleetController:
    """The mutable planning state of one run: plans, vehicle states, task queues."""

    def __init__(
        self,
        scenario: Scenario,
        invoke: Invoke = _direct,
        invoke_round: InvokeRound = _direct_round,
        *,
        quiet: bool = True,
    ) -> None:
        self.layout: Layout = scenario.layout
        self._invoke = invoke
        self._invoke_round = invoke_round
        self.tasks = TaskBook(scenario.tasks, (v.id for v in scenario.vehicles))
        self._types = {v.id: v.type for v in scenario.vehicles}
        self._plans: dict[int, FleetPlan] = {v.id: initial_plan(v) for v in scenario.vehicles}
        self._states: dict[int, VehicleState] = {v.id: initial_state(v, self.layout) for v in scenario.vehicles}
        # One vehicle's plan or state in force (no copy of the whole fleet's). The dicts' own lookups:
        # the loop asks for every vehicle on every step, and a method around them would double the cost.
        self.plan_of: Callable[[int], FleetPlan] = self._plans.__getitem__
        self.state_of: Callable[[int], VehicleState] = self._states.__getitem__
        self._reservations = ReservationIndex(ConflictTable(self.layout))
        # The last snapshot handed out; reused until something it shows changes (most calls change nothing).
        self._snapshot: FleetSnapshot | None = None
        self._stale = False  # something the last snapshot shows has changed since
        self._plans_version = 0  # counts plan changes (FleetSnapshot.plans_version)
        self._plan_log = PlanLog(4 * len(self._plans) + 64)  # whose they were, the recent ones
        self._drives = DriveMemo()  # drives the plan checks found legal on this layout
        # The read-only copies of the states and plans that snapshots show, brought up to date by what
        # changed (a planning round changes plans many times and states not at all).
        self._states_copy = LiveCopy(self._states)
        self._plans_copy = LiveCopy(self._plans)
        # The vehicles whose plans changed since the reservation index last saw them.
        self._unfolded: set[int] = set(self._plans)
        # The vehicles whose plans changed since the motion last asked (take_replanned).
        self._replanned: set[int] = set()
        # The alerts of the last reservation check, valid while no plan has changed since. Plans that
        # only lost legs (driven past) reserve less, so they can end alerts but never start one.
        self._alerts: tuple[CollisionAlert, ...] | None = None
        # The vehicles a planner's quiet hint lets rest (fleetsim.planning.quiet); None: hints ignored.
        self.resting: Resting | None = Resting(self.layout.conflicts) if quiet else None

    # -- views ---------------------------------------------------------------------------------------

    @property
    def plans(self) -> Mapping[int, FleetPlan]:
        return read_only(self._plans)

    @property
    def states(self) -> Mapping[int, VehicleState]:
        return read_only(self._states)

    def snapshot(self, time: float) -> FleetSnapshot:
        """An immutable view for a planner call: rebuilt when the fleet or the time has changed."""
        if self._snapshot is not None and not self._stale and self._snapshot.time == time:
            return self._snapshot
        # Held by nobody else, the last snapshot's copies may be brought up to date in place.
        exclusive = self._snapshot is not None and held_only_here(self, "_snapshot")
        self._snapshot = FleetSnapshot(
            time=time,
            vehicles=self._states_copy.view(exclusive),
            plans=self._plans_copy.view(exclusive),
            tasks=self.tasks.queues(),
            routed=self.tasks.routed_for_snapshot(exclusive),
            plans_version=self._plans_version,
            _log=self._plan_log,
        )
        self._stale = False
        return self._snapshot

    def alerts(self) -> tuple[CollisionAlert, ...]:
        """The reservation check over the plans in force (step 3)."""
        if self._alerts is None:
            self._alerts = self._reservations.alerts(self._plans, self._unfolded)
            self._unfolded.clear()
        return self._alerts

    # -- changes -------------------------------------------------------------------------------------

    def _put_plan(self, plan: FleetPlan) -> None:
        self._plans_version += 1
        self._plan_log.add(plan.vehicle_id)
        if self.resting is not None:
            self.resting.plan_changed(self._plans.get(plan.vehicle_id), plan)
        self._plans[plan.vehicle_id] = plan
        self._plans_copy.changed(plan.vehicle_id)
        self._unfolded.add(plan.vehicle_id)
        self._replanned.add(plan.vehicle_id)
        self._stale = True

    def take_replanned(self) -> set[int]:
        """The vehicles whose plans changed since the last call (the first call: since the start)."""
        replanned = self._replanned
        self._replanned = set()
        return replanned

    def set_plan(self, plan: FleetPlan) -> None:
        """Replace a vehicle's plan without checks."""
        self._put_plan(plan)
        self._alerts = None

    def drive_past(self, plan: FleetPlan) -> None:
        """The vehicle drove past its first legs: ``plan`` is its plan without them."""
        self._put_plan(plan)
        if self._alerts:  # with no alerts in force, fewer reservations cannot raise one
            self._alerts = None

    def set_state(self, state: VehicleState) -> None:
        self._states[state.id] = state
        self._states_copy.changed(state.id)
        self._stale = True

    def set_states(self, ids: Sequence[int], states: Iterable[VehicleState]) -> None:
        """:meth:`set_state` for many vehicles (a step's motion): ``states`` are those of ``ids``."""
        if ids:
            self._states.update(zip(ids, states, strict=True))
            self._states_copy.changed_many(ids)
            self._stale = True

    def consult(self, planner: Planner, vehicle_id: int, time: float) -> CallOutcome | None:
        """Step 2 for one vehicle: ask the planner, check the response, apply what passes.

        ``None`` when the vehicle has no more tasks or the planner changed nothing. A :class:`RouteError`
        raised by the planner fails the whole request; any other exception propagates to the caller
        (which reports a planner error).
        """
        task = self.tasks.head(vehicle_id)
        if task is None:
            return None
        return next(self._calls(planner, time, ((vehicle_id, task),)), None)

    def consult_all(self, planner: Planner, time: float) -> Iterator[CallOutcome]:
        """Step 2: :meth:`consult` each vehicle with tasks, by ascending id, yielding the outcomes of the
        calls that changed something. An exception from a call ends the round there."""
        return self._calls(planner, time, self.tasks.heads().items())

    def _calls(self, planner: Planner, time: float, heads: Iterable[tuple[int, Task]]) -> Iterator[CallOutcome]:
        # Rounds only for a RoundPlanner that does or may answer them (an attribute of another kind that
        # happens to be called ``rounds`` leaves a planner called one call at a time).
        rounds = getattr(planner, "rounds", False)
        if (rounds is True or rounds is None) and callable(getattr(planner, "plan_round", None)):
            return self._rounds(cast("RoundPlanner", planner), time, list(heads))
        return self._one_by_one(planner, time, heads)

    def _one_by_one(self, planner: Planner, time: float, heads: Iterable[tuple[int, Task]]) -> Iterator[CallOutcome]:
        # One planning round makes a call per busy vehicle, 10^4 a simulated minute in a large fleet, so
        # what every call needs is looked up once and the calls are made from this one frame.
        is_routed, invoke, layout = self.tasks.is_routed, self._invoke, self.layout
        plan_routes, fix_legs = planner.plan_routes, planner.fix_legs
        quiet: Callable[[int, FleetSnapshot], Quiet | None] | None = getattr(planner, "quiet", None)
        resting = self.resting if callable(quiet) else None
        changed_marks: Callable[[], Iterable[Hashable]] | None = None
        write_again: Callable[[int], object] | None = None
        if resting is not None:
            changed_marks, write_again = _optional(planner, "changed_marks"), _optional(planner, "write_again")
            resting.wake_due(time)
            resting.wake_standing(self._states)
            resting.planner_changed(planner, changed_marks)
        for vehicle_id, task in heads:
            if resting is not None and vehicle_id in resting.resting:
                # Its planner said asking again would change nothing until now, but for what the call
                # wrote, if that changed since: written again now, when the call would have been made.
                if vehicle_id in resting.to_write:
                    assert write_again is not None
                    resting.to_write.discard(vehicle_id)
                    write_again(vehicle_id)
                    resting.planner_changed(planner, changed_marks)
                continue
            method: Method
            if is_routed(task.id):
                method, call = "fix_legs", fix_legs
            else:
                method, call = "plan_routes", plan_routes
            try:
                # The snapshot is not kept in a local between calls: held here, it could not be brought up
                # to date in place for the next call (see LiveCopy).
                response: object = invoke(method, call, vehicle_id, task, self.snapshot(time), layout)
            except RouteError as error:  # the whole request cannot be routed
                response = error
            if resting is not None:  # the planner's own state may have changed
                resting.planner_changed(planner, changed_marks)
            if type(response) is list and not response:
                if resting is not None:
                    assert quiet is not None
                    hint = quiet(vehicle_id, self.snapshot(time))
                    if hint is not None:
                        if hint.writes and write_again is None:  # it cannot write them again: asked then
                            hint = replace(hint, marks=hint.marks | hint.writes, writes=frozenset())
                        resting.rest(vehicle_id, hint, self._states)
                continue  # nothing to change: the most common answer, so tested first
            outcome = self._answered(vehicle_id, method, task, response, time)
            if outcome is not None:
                if resting is not None and outcome.rejections:
                    resting.wake_all()  # the planner may have counted a plan that is not in force
                yield outcome

    def _rounds(self, planner: RoundPlanner, time: float, heads: list[tuple[int, Task]]) -> Iterator[CallOutcome]:
        """The calls of ``heads`` asked in rounds: each round holds the next ``ROUND_CALLS`` calls left, made
        as they would be now (a change can route another vehicle's task, turning its plan_routes into
        fix_legs)."""
        is_routed, invoke_round, layout = self.tasks.is_routed, self._invoke_round, self.layout
        done = 0
        while done < len(heads):
            if planner.rounds is False:  # it turned out to answer one call at a time
                yield from self._one_by_one(planner, time, heads[done:])
                return
            calls: list[RoundCall] = [
                ("fix_legs" if is_routed(task.id) else "plan_routes", vehicle_id, task)
                for vehicle_id, task in heads[done : done + ROUND_CALLS]
            ]
            answers = invoke_round(planner.plan_round, calls, self.snapshot(time), layout)  # (no local: see above)
            if not 0 < len(answers) <= len(calls):
                msg = f"plan_round() answered {len(answers)} of a round's {len(calls)} calls; it must answer 1 to {len(calls)}"
                raise PlannerError(msg, vehicle_id=calls[0][1])
            done += len(answers)
            for (name, vehicle_id, task), response in zip(calls, answers, strict=False):
                if type(response) is list and not response:
                    continue  # nothing to change
                method: Method = "fix_legs" if name == "fix_legs" else "plan_routes"
                outcome = self._answered(vehicle_id, method, task, response, time)
                if outcome is not None:
                    yield outcome

    def _answered(
        self, vehicle_id: int, method: Method, task: Task, response: object, time: float
    ) -> CallOutcome | None:
        """What an answer other than an empty list does: a whole-request ``RouteError`` is reported; a
        response is checked and applied, unless it is empty or hands the plan in force back unchanged."""
        plans = self._plans
        if isinstance(response, RouteError):
            return CallOutcome(vehicle_id, method, task, plans[vehicle_id], (), (), (response,), ())
        items = validate_response(response, method, vehicle_id)
        if not items or hands_back(items, plans):
            return None
        return self._apply(vehicle_id, method, task, items, time)

    def _context(self) -> CheckContext:
        return CheckContext(
            self.layout, self._types, self._plans, self.tasks.queues(), self.tasks.routed_now, self._drives
        )

    def _apply(
        self, vehicle_id: int, method: Method, task: Task, items: tuple[FleetPlan | RouteError, ...], time: float
    ) -> CallOutcome:
        plans = [item for item in items if isinstance(item, FleetPlan)]
        errors = tuple(item for item in items if isinstance(item, RouteError))
        previous = self._plans[vehicle_id]
        accepted: list[FleetPlan] = []
        rejections: list[Rejection] = []
        completed: list[int] = []
        for result in check_plans(plans, self._context()):
            if isinstance(result, Rejection):
                rejections.append(result)
                continue
            self._put_plan(result)
            self._alerts = None
            self.tasks.mark_routed(result)
            goal = result.legs[0].goal_for_task
            if goal is not None and not self.tasks.is_completed(goal):
                self.tasks.complete(goal, time)  # already on the goal leg
                completed.append(goal)
            accepted.append(result)
        return CallOutcome(
            vehicle_id, method, task, previous, tuple(accepted), tuple(rejections), errors, tuple(completed)
        )

    def requeue(self, vehicle_id: int, withdraw: Sequence[int], append: Sequence[Task]) -> None:
        """A dispatcher's assignment: the vehicle's tasks ``withdraw`` leave its queue (and their goal
        markers its plan), then ``append`` join it."""
        self.tasks.withdraw(vehicle_id, withdraw)
        self._unmark(vehicle_id, set(withdraw))
        self.tasks.append(append)
        self._stale = True
        if self.resting is not None:
            self.resting.queue_changed(sorted({vehicle_id, *(task.vehicle_id for task in append)}), self._plans)

    def _unmark(self, vehicle_id: int, task_ids: set[int]) -> None:
        """The vehicle's plan without goal markers for ``task_ids``."""
        plan = self._plans[vehicle_id]
        if task_ids and any(leg.goal_for_task in task_ids for leg in plan.legs):
            legs = tuple(
                replace(leg, goal_for_task=None) if leg.goal_for_task in task_ids else leg for leg in plan.legs
            )
            self._put_plan(FleetPlan(vehicle_id, legs))
            self._alerts = None

    def bookkeeping(self) -> tuple[Task, ...]:
        """Step 1: completed tasks leave their queues and their goal markers leave the plans."""
        dropped = self.tasks.drop_completed()
        if dropped:
            self._stale = True
            if self.resting is not None:
                self.resting.queue_changed(sorted({task.vehicle_id for task in dropped}), self._plans)
        for task in dropped:
            self._unmark(task.vehicle_id, {task.id})
        return dropped

    def planning_round(self, planner: Planner, time: float) -> tuple[CallOutcome, ...]:
        """Steps 1–2: bookkeeping, then consult the planner for each busy vehicle by id."""
        self.bookkeeping()
        return tuple(self.consult_all(planner, time))
