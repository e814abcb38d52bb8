"""Checks on every plan a planner returns (SPEC §7), each its own small function with a stable code.

A plan goes through the response checks (``unknown-vehicle``, ``duplicate-plan``), then the task checks
(goal markers), then the sanity checks; the first failing check rejects it and the vehicle keeps its old
plan. Every rejection names the vehicle, the leg index and segment where there is one, and says what to
change.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from collections.abc import Set as AbstractSet
from dataclasses import dataclass, field, replace
from enum import Enum
from itertools import islice, pairwise

from fleetsim.enums import JointKind, Progress, Traverse, TurnCapability
from fleetsim.layout.continuations import progresses_after
from fleetsim.layout.layout import Layout
from fleetsim.layout.segment_ids import not_in_map, segment_ids
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.scenario import Task, VehicleType

__all__ = [
    "CheckContext",
    "Rejection",
    "RejectionCode",
    "check_plan",
    "check_plans",
]


class RejectionCode(str, Enum):
    """Why a plan was rejected: a stable code that suites name in ``expect.rejections``.

    The checks run in the order below, and the first that fails rejects the plan: the response checks,
    the task checks (goal markers), then the sanity checks. The documentation's page "Errors and check
    codes" shows a plan that triggers each.

    Attributes:
        UNKNOWN_VEHICLE: ``"unknown-vehicle"``: the plan is for a vehicle not in the scenario.
        DUPLICATE_PLAN: ``"duplicate-plan"``: the response holds two or more plans for one vehicle (all
            are rejected).
        GOAL_NOT_ASSIGNED: ``"goal-not-assigned"``: a ``goal_for_task`` names a task that is not in the
            vehicle's queue.
        GOAL_ORDER: ``"goal-order"``: the goal markers do not follow the queue from its head, or drop the
            marker of a routed task.
        GOAL_SEGMENT_MISMATCH: ``"goal-segment-mismatch"``: a goal marker is on a leg whose segment is not
            the task's ``goal_segment``.
        GOAL_DIRECTION: ``"goal-direction"``: the goal leg's progress is not the task's ``goal_progress``.
        EMPTY_PLAN: ``"empty-plan"``: the plan has no legs.
        UNKNOWN_SEGMENT: ``"unknown-segment"``: a leg names a segment not in the layout.
        FIXED_LEGS_CHANGED: ``"fixed-legs-changed"``: the plan does not start with all of the vehicle's
            fixed legs, unchanged and still fixed (a goal marker may be added to one).
        FIXED_NOT_CONTIGUOUS: ``"fixed-not-contiguous"``: a fixed leg follows a planned one.
        WRONG_WAY: ``"wrong-way"``: a leg drives a one-way segment against its ``direction``.
        NOT_CONNECTED: ``"not-connected"``: a leg does not lead to the next (no connection between them
            for their traverses).
        ILLEGAL_PROGRESS_CHANGE: ``"illegal-progress-change"``: a ``CURVE`` vehicle changes progress at a
            ``SAME`` joint, keeps it at an ``OPPOSITE`` one, or meets a ``TURN_IN_PLACE`` joint.
        ORDER_INVALID: ``"order-invalid"``: a VDA 5050 master control's message breaks a rule of the
            standard that no plan can show (malformed JSON, a schema violation, sequence ids out of step, a
            base after the horizon, an outdated order update). Not a check of plans: the VDA 5050 vehicles
            (`fleetsim.vda5050`) refuse such a message, and the run records it with this code.
        ASSIGNMENT_UNKNOWN_VEHICLE: ``"assignment-unknown-vehicle"``: a dispatcher's assignment names a
            vehicle not in the scenario. This and the codes below are the dispatcher's rules
            (``fleetsim.dispatch.checks``): an answer with any of them is refused whole.
        ASSIGNMENT_TWICE: ``"assignment-twice"``: two assignments for one vehicle in one answer.
        ORDER_UNKNOWN: ``"order-unknown"``: an assignment names an order the scenario does not have.
        ORDER_UNRELEASED: ``"order-unreleased"``: an assignment names an order not yet released.
        ORDER_COMPLETED: ``"order-completed"``: an assignment names an order already completed.
        ORDER_TWICE: ``"order-twice"``: an order in two assignments of one answer, or twice in one.
        ORDER_STARTED: ``"order-started"``: an order whose vehicle has reached its first stop is given to
            another vehicle (it may be taken back until then, never after).
        ORDER_VEHICLE_TYPE: ``"order-vehicle-type"``: an order given to a vehicle of a type it excludes.
    """

    __hash__ = str.__hash__

    UNKNOWN_VEHICLE = "unknown-vehicle"
    DUPLICATE_PLAN = "duplicate-plan"
    EMPTY_PLAN = "empty-plan"
    UNKNOWN_SEGMENT = "unknown-segment"
    FIXED_LEGS_CHANGED = "fixed-legs-changed"
    FIXED_NOT_CONTIGUOUS = "fixed-not-contiguous"
    NOT_CONNECTED = "not-connected"
    WRONG_WAY = "wrong-way"
    ILLEGAL_PROGRESS_CHANGE = "illegal-progress-change"
    GOAL_NOT_ASSIGNED = "goal-not-assigned"
    GOAL_ORDER = "goal-order"
    GOAL_SEGMENT_MISMATCH = "goal-segment-mismatch"
    GOAL_DIRECTION = "goal-direction"
    ORDER_INVALID = "order-invalid"
    ASSIGNMENT_UNKNOWN_VEHICLE = "assignment-unknown-vehicle"
    ASSIGNMENT_TWICE = "assignment-twice"
    ORDER_UNKNOWN = "order-unknown"
    ORDER_UNRELEASED = "order-unreleased"
    ORDER_COMPLETED = "order-completed"
    ORDER_TWICE = "order-twice"
    ORDER_STARTED = "order-started"
    ORDER_VEHICLE_TYPE = "order-vehicle-type"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True, slots=True)
class Rejection:
    """A plan the checks refused: which check, for which vehicle, where in the plan, and why.

    The vehicle keeps the plan it had. ``str(rejection)`` reads ``code: vehicle V, leg I (segment S):
    message``, as in a run's report.

    Attributes:
        code: The check that failed.
        vehicle_id: The plan's vehicle.
        leg_index: The index in ``plan.legs`` (0-based) of the leg that failed the check, or ``None``
            when the check is about the plan as a whole.
        segment: That leg's segment id, or ``None``.
        message: What is wrong, in words, naming the values concerned.
        plan: The plan refused (``None`` only in rejections made by hand).
    """

    code: RejectionCode
    vehicle_id: int
    leg_index: int | None
    segment: int | None
    message: str
    plan: FleetPlan | None = field(default=None, compare=False, repr=False)

    def __str__(self) -> str:
        where = f"vehicle {self.vehicle_id}"
        if self.leg_index is not None:
            where += f", leg {self.leg_index}"
        if self.segment is not None:
            where += f" (segment {self.segment})"
        return f"{self.code.value}: {where}: {self.message}"


@dataclass(frozen=True, slots=True)
class CheckContext:
    """What the checks compare a plan with: the layout and each vehicle's type, plan and task queue."""

    layout: Layout
    vehicle_types: Mapping[int, VehicleType]  # by vehicle id
    plans: Mapping[int, FleetPlan]  # the plans in force now
    queues: Mapping[int, tuple[Task, ...]]  # head first
    routed: AbstractSet[int] = frozenset()  # queued tasks an accepted plan already marks
    drives: DriveMemo | None = None  # drives already found legal, kept between checks (one layout)


Check = Callable[[FleetPlan, CheckContext], "Rejection | None"]


class DriveMemo:
    """The drives and pairs of consecutive drives that passed the wrong-way, not-connected and
    illegal-progress-change checks, on one layout: those checks judge each leg and each pair of legs
    alone, so a plan made only of drives and pairs passed before passes them again, and is not walked
    through again (a planner that fixes one more leg of a long route sends the same route again and
    again). A plan with anything new is checked in full, as ever, and what passes is remembered.

    The last plan of each vehicle that passed is kept too: a plan whose drives are the end of its drives
    (the same route, legs fixed or driven past since) passes without its keys being made at all."""

    __slots__ = ("_last", "_legs", "_pairs")

    def __init__(self) -> None:
        self._legs: set[tuple[int, Traverse]] = set()
        self._pairs: set[tuple[TurnCapability, int, Traverse, Progress, int, Traverse, Progress]] = set()
        self._last: dict[tuple[int, TurnCapability], tuple[FleetLeg, ...]] = {}

    def _keys(
        self, plan: FleetPlan, capability: TurnCapability
    ) -> tuple[
        list[tuple[int, Traverse]], list[tuple[TurnCapability, int, Traverse, Progress, int, Traverse, Progress]]
    ]:
        legs = plan.legs
        drives = [(leg.segment, leg.traverse) for leg in legs]
        pairs = [
            (capability, a.segment, a.traverse, a.progress, b.segment, b.traverse, b.progress)
            for a, b in pairwise(legs)
        ]
        return drives, pairs

    def passed(self, plan: FleetPlan, capability: TurnCapability) -> bool:
        key = (plan.vehicle_id, capability)
        last = self._last.get(key)
        if last is not None and _ends(last, plan.legs):
            return True  # its drives and pairs are among those of a plan that passed
        drives, pairs = self._keys(plan, capability)
        if self._legs.issuperset(drives) and self._pairs.issuperset(pairs):
            self._last[key] = plan.legs
            return True
        return False

    def learn(self, plan: FleetPlan, capability: TurnCapability) -> None:
        drives, pairs = self._keys(plan, capability)
        self._legs.update(drives)
        self._pairs.update(pairs)
        self._last[(plan.vehicle_id, capability)] = plan.legs


def _ends(before: Sequence[FleetLeg], legs: Sequence[FleetLeg]) -> bool:
    """``legs`` drive as the end of ``before`` does, leg by leg (segment, traverse, progress): their drives
    and pairs of consecutive drives are among ``before``'s. Legs unchanged are mostly the same objects."""
    skip = len(before) - len(legs)
    if skip < 0:
        return False
    for a, b in zip(islice(before, skip, None), legs, strict=True):
        if a is not b and (a.segment != b.segment or a.traverse != b.traverse or a.progress != b.progress):
            return False
    return True


def _reject(code: RejectionCode, plan: FleetPlan, index: int | None, message: str) -> Rejection:
    segment = plan.legs[index].segment if index is not None else None
    return Rejection(code, plan.vehicle_id, index, segment, message, plan)


def _segment(layout: Layout, segment: int) -> str:
    """``segment 7``; a segment the map lacks says so (``segment 999, which is not in the map (...)``)."""
    return f"segment {segment}" if segment in layout.segments else not_in_map(segment, layout.segments)


def _naming_missing_segments(rejection: Rejection, plan: FleetPlan, layout: Layout) -> Rejection:
    """``rejection``, its message ending with the legs that name segments the map does not have.

    The first failing check sets the code (a goal marker on segment 999 is ``goal-segment-mismatch``),
    but a segment that does not exist is what the planner's author must hear about, whichever check
    came first.
    """
    missing = [(index, leg.segment) for index, leg in enumerate(plan.legs) if leg.segment not in layout.segments]
    if not missing:
        return rejection
    if len(missing) == 1:
        index, segment = missing[0]
        news = f"leg {index} names {not_in_map(segment, layout.segments)}"
    else:
        legs = ", ".join(str(index) for index, _ in missing)
        named = ", ".join(str(segment) for segment in dict.fromkeys(segment for _, segment in missing))
        news = f"legs {legs} name segments {named}, which are not in the map ({segment_ids(layout.segments)})"
    return replace(rejection, message=f"{rejection.message}; besides, {news}")


def _goal_legs(plan: FleetPlan) -> list[tuple[int, FleetLeg]]:
    return [(index, leg) for index, leg in enumerate(plan.legs) if leg.goal_for_task is not None]


# -- task checks ------------------------------------------------------------------------------------


def goal_not_assigned(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    queued = {task.id for task in ctx.queues.get(plan.vehicle_id, ())}
    for index, leg in _goal_legs(plan):
        if leg.goal_for_task not in queued:
            listing = ", ".join(str(task_id) for task_id in sorted(queued)) or "none"
            msg = (
                f"marks the goal of task {leg.goal_for_task}, which is not in this vehicle's queue (queued: {listing})"
            )
            return _reject(RejectionCode.GOAL_NOT_ASSIGNED, plan, index, msg)
    return None


def goal_order(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    """Goal markers must follow the queue from its head, without gaps or repeats, and keep routed tasks.

    The marked tasks are always the first tasks of the queue, in queue order: a vehicle completes its
    tasks one after the other, so a plan cannot reach task 3's goal before task 2's. A task that an
    accepted plan routed stays marked until it is completed.
    """
    queue = ctx.queues.get(plan.vehicle_id, ())
    goals = _goal_legs(plan)
    routed = [task for task in queue if task.id in ctx.routed]
    if len(goals) < len(routed):
        dropped = routed[len(goals)]
        msg = f"drops the goal marker of task {dropped.id}, which is routed; it must stay marked until completed"
        return _reject(RejectionCode.GOAL_ORDER, plan, None, msg)
    for position, (index, leg) in enumerate(goals):
        expected = queue[position].id if position < len(queue) else None
        if leg.goal_for_task != expected:
            wanted = f"task {expected}" if expected is not None else "no further goal"
            msg = (
                f"marks task {leg.goal_for_task} as goal number {position + 1}, but the queue's order "
                f"requires {wanted} there (queue: {', '.join(str(t.id) for t in queue)})"
            )
            return _reject(RejectionCode.GOAL_ORDER, plan, index, msg)
    return None


def goal_segment_mismatch(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    tasks = {task.id: task for task in ctx.queues.get(plan.vehicle_id, ())}
    for index, leg in _goal_legs(plan):
        task = tasks[leg.goal_for_task]  # type: ignore[index]  # goal_not_assigned ran first
        if leg.segment != task.goal_segment:
            goal = _segment(ctx.layout, task.goal_segment)
            msg = f"marks the goal of task {task.id} on segment {leg.segment}, but its goal is {goal}"
            return _reject(RejectionCode.GOAL_SEGMENT_MISMATCH, plan, index, msg)
    return None


def goal_direction(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    tasks = {task.id: task for task in ctx.queues.get(plan.vehicle_id, ())}
    for index, leg in _goal_legs(plan):
        task = tasks[leg.goal_for_task]  # type: ignore[index]
        if task.goal_progress is not None and leg.progress is not task.goal_progress:
            msg = (
                f"reaches the goal of task {task.id} with progress {leg.progress.value}, "
                f"but the task requires arriving {task.goal_progress.value}"
            )
            return _reject(RejectionCode.GOAL_DIRECTION, plan, index, msg)
    return None


# -- sanity checks ----------------------------------------------------------------------------------


def empty_plan(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    if not plan.legs:
        return _reject(
            RejectionCode.EMPTY_PLAN,
            plan,
            None,
            "the plan has no legs; it must at least hold the leg the vehicle is on",
        )
    return None


def unknown_segment(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    for index, leg in enumerate(plan.legs):
        if leg.segment not in ctx.layout.segments:
            msg = f"segment {leg.segment} is not in the map ({segment_ids(ctx.layout.segments)})"
            return _reject(RejectionCode.UNKNOWN_SEGMENT, plan, index, msg)
    return None


def fixed_legs_changed(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    """The plan must start with every current fixed leg, same drive, still fixed, goal marker kept.

    A goal marker may be added to a fixed leg that had none: that is how a planner completes a task on
    the segment the vehicle is already committed to.
    """
    current = ctx.plans[plan.vehicle_id].fixed_legs
    for index, old in enumerate(current):
        if index >= len(plan.legs):
            msg = f"the plan has {len(plan.legs)} legs but the vehicle has {len(current)} fixed legs, which cannot be dropped"
            return _reject(RejectionCode.FIXED_LEGS_CHANGED, plan, None, msg)
        new = plan.legs[index]
        marker_kept = old.goal_for_task is None or new.goal_for_task == old.goal_for_task
        if not (new.same_drive(old) and new.fixed and marker_kept):
            msg = f"fixed leg {index} was ({old}) and may not change; the plan has ({new})"
            return _reject(RejectionCode.FIXED_LEGS_CHANGED, plan, index, msg)
    return None


def fixed_not_contiguous(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    seen_planned = False
    for index, leg in enumerate(plan.legs):
        if leg.fixed and seen_planned:
            msg = "a fixed leg follows a planned one; fixed legs must form the plan's first legs"
            return _reject(RejectionCode.FIXED_NOT_CONTIGUOUS, plan, index, msg)
        seen_planned = seen_planned or not leg.fixed
    return None


def wrong_way(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    for index, leg in enumerate(plan.legs):
        segment = ctx.layout.segments[leg.segment]
        if not segment.allows(leg.traverse):
            msg = f"segment {segment.id} is one-way {segment.direction.value}; the leg drives it {leg.traverse.value}"
            return _reject(RejectionCode.WRONG_WAY, plan, index, msg)
    return None


def _joint(layout: Layout, before: FleetLeg, after: FleetLeg) -> JointKind | None:
    return layout.joint(before.segment, before.traverse, after.segment, after.traverse)


def not_connected(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    for index, (before, after) in enumerate(pairwise(plan.legs), start=1):
        if _joint(ctx.layout, before, after) is None:
            msg = (
                f"segment {before.segment} driven {before.traverse.value} does not lead to segment "
                f"{after.segment} driven {after.traverse.value}"
            )
            return _reject(RejectionCode.NOT_CONNECTED, plan, index, msg)
    return None


def illegal_progress_change(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    """Each leg's progress must be one :func:`~fleetsim.layout.continuations.progresses_after` allows
    after the leg before: the rule ``Layout.continuations`` offers planners. Curve-only vehicles keep
    progress at smooth joints, flip it at cusps and cannot take corners."""
    vehicle_type = ctx.vehicle_types[plan.vehicle_id]
    capability = vehicle_type.turn_capability
    for index, (before, after) in enumerate(pairwise(plan.legs), start=1):
        joint = _joint(ctx.layout, before, after)
        if joint is None or after.progress in progresses_after(capability, joint, before.progress):
            continue
        if joint is JointKind.TURN_IN_PLACE:
            msg = f"the joint from segment {before.segment} is a corner, and a {vehicle_type.name!r} vehicle cannot turn in place"
        elif joint is JointKind.SAME:
            msg = f"progress changes from {before.progress.value} to {after.progress.value} at a smooth joint"
        else:
            msg = f"the joint from segment {before.segment} is a cusp: progress must flip from {before.progress.value}"
        return _reject(RejectionCode.ILLEGAL_PROGRESS_CHANGE, plan, index, msg)
    return None


# Task checks first, then sanity checks (SPEC §7). Within the sanity checks, wrong-way runs before
# not-connected: a one-way segment driven backwards also has no connection, and "wrong way" says why.
TASK_CHECKS: tuple[Check, ...] = (goal_not_assigned, goal_order, goal_segment_mismatch, goal_direction)
SANITY_CHECKS: tuple[Check, ...] = (
    empty_plan,
    unknown_segment,
    fixed_legs_changed,
    fixed_not_contiguous,
    wrong_way,
    not_connected,
    illegal_progress_change,
)


def check_plan(plan: FleetPlan, ctx: CheckContext) -> Rejection | None:
    """The first failed check of a plan for a known vehicle, or ``None`` when it passes them all.

    The first failed check gives the code; when a leg names a segment the map does not have, the message
    says so too, whichever check that was (``...; besides, leg 2 names segment 999, which is not in the
    map (segments 1–8)``).
    """
    memo = ctx.drives
    capability = ctx.vehicle_types[plan.vehicle_id].turn_capability if memo is not None else None
    for check in (*TASK_CHECKS, *SANITY_CHECKS):
        if check is wrong_way and memo is not None and capability is not None and memo.passed(plan, capability):
            return None  # the rest (wrong way, connections, progress) passed for these very drives before
        rejection = check(plan, ctx)
        if rejection is not None:
            if rejection.code is RejectionCode.UNKNOWN_SEGMENT:
                return rejection
            return _naming_missing_segments(rejection, plan, ctx.layout)
    if memo is not None and capability is not None:
        memo.learn(plan, capability)
    return None


def check_plans(plans: Sequence[FleetPlan], ctx: CheckContext) -> list[FleetPlan | Rejection]:
    """Each plan of one response, or the rejection it earned, in response order.

    Plans for vehicles not in the scenario are rejected, and so are all plans of a vehicle that appears
    twice (which of them the planner meant cannot be known; the vehicle keeps its current plan).
    """
    counts: dict[int, int] = {}
    for plan in plans:
        counts[plan.vehicle_id] = counts.get(plan.vehicle_id, 0) + 1
    results: list[FleetPlan | Rejection] = []
    for plan in plans:
        if plan.vehicle_id not in ctx.plans:
            known = ", ".join(str(v) for v in sorted(ctx.plans))
            msg = f"vehicle {plan.vehicle_id} is not in the scenario (vehicles: {known})"
            results.append(Rejection(RejectionCode.UNKNOWN_VEHICLE, plan.vehicle_id, None, None, msg, plan))
        elif counts[plan.vehicle_id] > 1:
            msg = f"the response holds {counts[plan.vehicle_id]} plans for this vehicle; all are rejected"
            results.append(Rejection(RejectionCode.DUPLICATE_PLAN, plan.vehicle_id, None, None, msg, plan))
        else:
            results.append(check_plan(plan, ctx) or plan)
    return results
