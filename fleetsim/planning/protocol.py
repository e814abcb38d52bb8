"""The planner protocol (SPEC §6): the two methods a planner has, what each receives and may return.

A planner is any object with ``plan_routes(task, fleet, layout)`` and ``fix_legs(task, fleet, layout)``;
what they return is in ``fleetsim.planning.plans``. A planner may also answer a planning round's calls
in one go (:class:`RoundPlanner`: a planner process whose client speaks protocol 1.2's rounds), and be
told of every step before its planning (:class:`SteppedPlanner`: fleetsim's VDA 5050 vehicles).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol, runtime_checkable

if TYPE_CHECKING:
    from fleetsim.layout.layout import Layout
    from fleetsim.planning.checks import Rejection
    from fleetsim.planning.plans import Response, RouteError
    from fleetsim.planning.quiet import Quiet
    from fleetsim.planning.snapshot import FleetSnapshot
    from fleetsim.scenario import Task

__all__ = ["Planner", "QuietPlanner", "RoundCall", "RoundPlanner", "SteppedPlanner"]

# A call of a planning round: (method name, vehicle id, task).
RoundCall = tuple[str, int, "Task"]


@runtime_checkable
class Planner(Protocol):
    """A fleet route planner (the thesis's ``RoutePlannerInterface``). A fresh instance serves one run.

    Any object with these two methods will do; no base class is needed. On each planning round the
    harness asks about each vehicle with tasks left, in ascending id: ``plan_routes`` while the head of its
    queue is not routed (no accepted plan marks its goal), else ``fix_legs``. Each response is checked and
    applied before the next call, so a later call's ``fleet`` holds what an earlier one changed.

    A response is a sequence of [`FleetPlan`][fleetsim.planning.plans.FleetPlan]s and
    [`RouteError`][fleetsim.planning.plans.RouteError]s, at most one plan per vehicle (check code
    ``duplicate-plan``). A plan replaces its vehicle's plan unless a check rejects it
    ([`Rejection`][fleetsim.planning.checks.Rejection]), in which case the vehicle keeps its old one. An
    empty list changes nothing.
    """

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        """The vehicle's head task has not been routed yet: return a plan marking its goal leg.

        Args:
            task: The head of the vehicle's task queue; ``task.vehicle_id`` is the vehicle asked about.
            fleet: The whole fleet now, read-only: the vehicle's plan in force is
                ``fleet.plans[task.vehicle_id]``, and a new plan must start with its ``fixed_legs``.
            layout: The map: segments, their connections with joint kinds, and conflicts.

        Returns:
            The vehicle's new plan, with ``goal_for_task=task.id`` on the leg that reaches
                ``task.goal_segment`` (later tasks of its queue may be marked after it, in queue order);
                plans for other vehicles may come with it. A ``RouteError`` for the vehicle when no route
                exists; an empty list to change nothing (the harness asks again next round).

        Raises:
            RouteError: The request cannot be answered at all: nothing of it is applied.
        """
        ...

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        """The task is routed: return the vehicle's plan with more legs fixed (or unchanged).

        The vehicle drives only its fixed legs, so it waits at the end of them until this fixes more.

        Args:
            task: The head of the vehicle's task queue (routed: its goal leg is in the plan in force).
            fleet: The whole fleet now, read-only.
            layout: The map.

        Returns:
            The vehicle's plan with a longer fixed prefix (or a new route, keeping the fixed legs and
                the goal marker), plans for other vehicles, or an empty list to change nothing.

        Raises:
            RouteError: The request cannot be answered at all: nothing of it is applied.
        """
        ...


class RoundPlanner(Planner, Protocol):
    """A planner that can answer the calls of a planning round in one go (the harness's side of a planner
    process speaking protocol 1.2's rounds); the run and its trace are the same as with one call at a time.

    ``rounds`` says whether it does: ``None`` until it knows (a planner process knows once started),
    ``False`` for one call at a time, which the harness then makes through ``plan_routes`` and ``fix_legs``.
    """

    rounds: bool | None

    def plan_round(
        self, calls: Sequence[RoundCall], fleet: FleetSnapshot, layout: Layout
    ) -> Sequence[tuple[Response | RouteError, float | None]]:
        """The answers to the first of ``calls`` (at least one), made in order against ``fleet``: each call's
        response (a ``RouteError`` object: the whole request raised it) with the call's own duration in
        seconds (``None``: unknown). Every answer but the last changes nothing; the harness applies them,
        then asks again about the calls left."""
        ...


@runtime_checkable
class SteppedPlanner(Planner, Protocol):
    """A planner told of every step before its planning (SPEC §9, between steps 1 and 2): fleetsim's VDA 5050
    vehicles, which pace the run on a wall clock, take in what their master control sent and tell it where
    the fleet is. Planners without ``begin_step`` are never asked, and their runs are as before.
    """

    def begin_step(self, fleet: FleetSnapshot, layout: Layout) -> Sequence[Rejection]:
        """The step at ``fleet.time`` begins (every vehicle's state up to date); return the messages refused
        since the last step, as rejections made by hand (code ``order-invalid``, no plan), which the run
        records and judges as any rejection. Raising fails the run as a ``planner-error``: a
        :class:`~fleetsim.errors.PlannerError` (a fault the planner expects, such as a VDA 5050 master
        control that exited) with its message alone, anything else as ``begin_step raised ...`` with its
        traceback.

        A stepped planner may also have ``paused() -> set of vehicle ids``, asked right after: the vehicles
        held still from this step on (a VDA 5050 ``startPause``), each braking to rest within the distance
        its fixed legs leave it and staying until it is no longer named. And ``awaiting_plan() -> set of
        vehicle ids``, asked then too: the vehicles that stand still, with no event (nothing disturbs them),
        until a plan of this planner's is accepted for them (a VDA 5050 vehicle without an order moves only
        along released base, not along the start leg every plan begins fixed with); the accepted plan lets
        one drive at once, in that step. And ``explain_wait(vehicle_id, now) -> str``, asked when a run ends
        stuck (deadlock or time limit) for each vehicle with a pending task: a sentence the stuck-fleet
        diagnosis adds to that vehicle's finding (empty: nothing to add)."""
        ...


@runtime_checkable
class QuietPlanner(Planner, Protocol):
    """A planner that may say when asking about a vehicle again would change nothing (an optional hint: a
    planner without ``quiet`` is asked about every vehicle with tasks on every planning round, as always).

    Most calls of a run answer an empty list: a vehicle cruising along legs it has fixed far enough ahead
    has nothing to change. Right after a call for a vehicle answers an empty list, the harness asks
    ``quiet(vehicle_id, fleet)`` (``fleet``: the snapshot that call saw). A
    [`Quiet`][fleetsim.planning.quiet.Quiet] answer promises that asking again would answer an empty list
    and change nothing of the planner's own, until the vehicle's plan or task queue changes, another
    vehicle's fixed legs change on a segment conflicting with one of ``Quiet.watch`` (or such a vehicle's
    queue changes), one of ``Quiet.vehicles`` changes its plan or queue or comes to rest or starts to
    move, another vehicle's route comes onto or leaves a segment conflicting with one of
    ``Quiet.routes``, the planning time reaches ``Quiet.until``, a round finds it at rest with
    ``Quiet.until_standing``, a plan of any call is rejected, the planner names one of ``Quiet.marks``
    among the marks of its own state that changed (its optional ``changed_marks()`` method, asked after
    every call and at every round: each mark once, then forgotten), or the
    planner's ``quiet_epoch`` attribute (if any; read after every call and at every round) changes. Until
    then the vehicle is not asked. ``None`` promises nothing. ``Quiet.writes`` names marks the call wrote
    without reading them: when one changes, the vehicle rests on and the planner's optional
    ``write_again(vehicle_id)`` is called at its turn in the round instead, and must write them again as
    the call did (without that method, the vehicle is asked again).

    The promise must hold exactly: a run must be the same, hash for hash, with the hint honoured or
    ignored. ``ReservingPlanner`` gives it for cruising vehicles (half its calls on a busy warehouse) and
    for vehicles standing blocked (most of a congested shift's); a
    planner in another process is asked about every vehicle, as before.
    """

    def quiet(self, vehicle_id: int, fleet: FleetSnapshot) -> Quiet | None:
        """After a call for ``vehicle_id`` answered an empty list: a promise that asking again changes
        nothing until what it names changes, or ``None``."""
        ...
