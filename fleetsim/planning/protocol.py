"""The planner protocol (SPEC §6): what a planner receives and what it may return.

A planner is any object with ``plan_routes(task, fleet, layout)`` and ``fix_legs(task, fleet, layout)``.
Both return a sequence whose items are each a :class:`FleetPlan` or a :class:`RouteError` for one
vehicle; raising a :class:`RouteError` fails the whole request. Plans and legs are immutable.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, runtime_checkable

from fleetsim.enums import Progress, Traverse
from fleetsim.errors import FleetsimError

if TYPE_CHECKING:
    from fleetsim.layout.layout import Layout
    from fleetsim.planning.snapshot import FleetSnapshot
    from fleetsim.scenario import Task

__all__ = ["FleetLeg", "FleetPlan", "Planner", "Response", "ResponseItem", "RouteError"]


def _enum_value(enum: type[Traverse] | type[Progress], value: object, name: str) -> Traverse | Progress:
    try:
        return enum(value)
    except ValueError:
        choices = " or ".join(repr(member.value) for member in enum)
        msg = f"{name}={value!r} must be {choices}"
        raise ValueError(msg) from None


def _whole_number(value: object, name: str) -> int:
    # bool is an int subclass, but True is never a meaningful segment or vehicle id.
    if isinstance(value, bool) or not isinstance(value, int):
        msg = f"{name}={value!r} must be an int"
        raise TypeError(msg)
    return value


@dataclass(frozen=True, slots=True)
class FleetLeg:
    """An instruction to drive one segment: which way, nose first or backing, committed or not.

    The strings ``"forward"``, ``"backward"`` and ``"reverse"`` are accepted for the enums.

    Attributes:
        segment: The segment's id.
        traverse: ``FORWARD`` along the segment's waypoints (first to last), ``BACKWARD`` against them;
            one-way segments allow one of the two (check code ``wrong-way``).
        progress: ``FORWARD`` nose first, ``REVERSE`` backing; it changes only where the joint allows
            (a cusp, ``JointKind.OPPOSITE``, or an in-place turn; check code ``illegal-progress-change``).
        fixed: Committed (VDA 5050 "base"): the vehicle may drive it, the harness reserves its segment's
            conflict set, and it can never change (check code ``fixed-legs-changed``). Planned legs (VDA 5050
            "horizon") may still change; fixed legs come first in a plan.
        goal_for_task: The id of the task this leg completes (the vehicle's head task, on its goal
            segment), or ``None``.
    """

    segment: int
    traverse: Traverse
    progress: Progress
    fixed: bool
    goal_for_task: int | None = None

    def __post_init__(self) -> None:
        # Legs are made by the thousand every simulated second: the common case (an int and the enum
        # members themselves) is checked by type alone, anything else converted or refused with a message.
        if type(self.segment) is not int:
            _whole_number(self.segment, "segment")
        if type(self.traverse) is not Traverse:
            object.__setattr__(self, "traverse", _enum_value(Traverse, self.traverse, "traverse"))
        if type(self.progress) is not Progress:
            object.__setattr__(self, "progress", _enum_value(Progress, self.progress, "progress"))
        if self.fixed is not True and self.fixed is not False:
            msg = f"fixed={self.fixed!r} must be True or False"
            raise TypeError(msg)
        if self.goal_for_task is not None and type(self.goal_for_task) is not int:
            _whole_number(self.goal_for_task, "goal_for_task")

    def same_drive(self, other: FleetLeg) -> bool:
        """Whether both legs drive the same segment the same way (fixed flag and goal marker aside)."""
        return (self.segment, self.traverse, self.progress) == (other.segment, other.traverse, other.progress)

    def __str__(self) -> str:
        text = f"{self.segment} {self.traverse.value} {self.progress.value} {'fixed' if self.fixed else 'planned'}"
        return text + (f" goal of task {self.goal_for_task}" if self.goal_for_task is not None else "")


@dataclass(frozen=True, slots=True)
class FleetPlan:
    """A vehicle's route plan: its legs in driving order, the first being the one it is on now.

    A list of legs is accepted and frozen into a tuple.

    Attributes:
        vehicle_id: Whose plan it is (a response may carry plans for other vehicles than the one asked
            about, to move them out of the way, say).
        legs: The [`FleetLeg`][fleetsim.planning.protocol.FleetLeg]s in driving order, the one the
            vehicle is on first; the fixed ones come first (``fixed_legs``), then the planned ones. Never
            empty in a plan the harness accepts (check code ``empty-plan``).
    """

    vehicle_id: int
    legs: tuple[FleetLeg, ...]
    # How many legs the committed prefix holds (derived; asked for on every step of every vehicle).
    _fixed_count: int = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        _whole_number(self.vehicle_id, "vehicle_id")
        if isinstance(self.legs, (str, bytes)) or not isinstance(self.legs, Sequence):
            msg = f"legs={self.legs!r} must be a sequence of FleetLeg"
            raise TypeError(msg)
        legs = tuple(self.legs)
        count = 0
        for index, leg in enumerate(legs):
            if not isinstance(leg, FleetLeg):
                msg = f"legs[{index}]={leg!r} must be a FleetLeg"
                raise TypeError(msg)
            if leg.fixed and count == index:
                count += 1
        object.__setattr__(self, "legs", legs)
        object.__setattr__(self, "_fixed_count", count)

    @property
    def fixed_legs(self) -> tuple[FleetLeg, ...]:
        """The legs before the first planned one: the committed prefix the vehicle may drive.

        For a well-formed plan these are all its fixed legs (check code ``fixed-not-contiguous``). A
        planner's new plan for a vehicle must start with the vehicle's current ``fixed_legs`` unchanged
        (check code ``fixed-legs-changed``).
        """
        return self.legs[: self._fixed_count]

    def __str__(self) -> str:
        return f"vehicle {self.vehicle_id}: " + ", ".join(map(str, self.legs))


class RouteError(FleetsimError):
    """A planner cannot route: returned as a response item for one vehicle, or raised for the request.

    Attributes:
        vehicle_id: The vehicle it is about, or ``None`` for the whole request (when raised).
        message: What went wrong, in words (shown in the run's report and the summary's route errors).
    """

    vehicle_id: int | None
    message: str

    def __init__(self, vehicle_id: int | None, message: str) -> None:
        self.vehicle_id = vehicle_id
        self.message = message
        who = f"vehicle {vehicle_id}" if vehicle_id is not None else "request"
        super().__init__(f"route error ({who}): {message}")

    def __repr__(self) -> str:
        return f"RouteError(vehicle_id={self.vehicle_id!r}, message={self.message!r})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, RouteError):
            return NotImplemented
        return (self.vehicle_id, self.message) == (other.vehicle_id, other.message)

    def __hash__(self) -> int:
        return hash((self.vehicle_id, self.message))


ResponseItem = FleetPlan | RouteError
Response = Sequence[ResponseItem]


@runtime_checkable
class Planner(Protocol):
    """A fleet route planner (the thesis's ``RoutePlannerInterface``). A fresh instance serves one run.

    Any object with these two methods will do; no base class is needed. On each planning round the
    harness asks about each vehicle with tasks left, in ascending id: ``plan_routes`` while the head of its
    queue is not routed (no accepted plan marks its goal), else ``fix_legs``. Each response is checked and
    applied before the next call, so a later call's ``fleet`` holds what an earlier one changed.

    A response is a sequence of [`FleetPlan`][fleetsim.planning.protocol.FleetPlan]s and
    [`RouteError`][fleetsim.planning.protocol.RouteError]s, at most one plan per vehicle (check code
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
