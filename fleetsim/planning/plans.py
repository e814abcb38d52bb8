"""What a planner answers (SPEC §6): plans of legs, and route errors. Plans and legs are immutable.

A response is a sequence whose items are each a ``FleetPlan`` or a ``RouteError`` for one vehicle;
raising a ``RouteError`` fails the whole request. The planner itself is ``fleetsim.planning.protocol``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from fleetsim.enums import Progress, Traverse
from fleetsim.errors import FleetsimError

__all__ = ["FleetLeg", "FleetPlan", "Response", "ResponseItem", "RouteError", "hands_back"]


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
        legs: The [`FleetLeg`][fleetsim.planning.plans.FleetLeg]s in driving order, the one the
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


def hands_back(items: Sequence[object], plans: Mapping[int, FleetPlan]) -> bool:
    """``items`` is one plan, its vehicle's plan in force (of ``plans``): accepting it changes nothing, as
    an empty response does not."""
    if len(items) != 1:
        return False
    item = items[0]
    return isinstance(item, FleetPlan) and item == plans.get(item.vehicle_id)
