"""Which legs may follow which: the progress rules of SPEC §4, in one place.

A leg is a segment driven one way (``traverse``) with the vehicle nose first or backing (``progress``).
Where one leg's segment leads to another's, the layout knows the joint between them (``JointKind``); the
vehicle's turn capability and the joint decide the progress it may have on the next leg:

- a vehicle that turns in place (``IN_PLACE``) may take any joint with either progress: it stops and
  turns on the spot wherever its heading or progress changes;
- a vehicle that only follows curves (``CURVE``) keeps its progress at a smooth joint (``SAME``), must
  flip it at a cusp (``OPPOSITE``: the next segment doubles back) and cannot take a corner
  (``TURN_IN_PLACE``).

:func:`progresses_after` is the rule itself. The plan check ``illegal-progress-change`` judges plans by
it, the reference planners' route searches and the scenario loader's reachability check generate
states by it, and planners ask :meth:`Layout.continuations <fleetsim.layout.layout.Layout.continuations>`
for the legal next legs, so what a planner is offered is what the check accepts.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

from fleetsim.enums import JointKind, Progress, Traverse, TurnCapability

__all__ = ["RULES", "Continuation", "Turning", "capability_of", "progresses_after"]


class Turning(Protocol):
    """Anything with a turn capability: a [`VehicleType`][fleetsim.scenario.VehicleType]."""

    @property
    def turn_capability(self) -> TurnCapability: ...


class Continuation(NamedTuple):
    """A legal next leg: drive ``segment`` with ``traverse`` and ``progress``, over a joint of kind ``joint``.

    Attributes:
        segment: The next leg's segment id.
        traverse: Which way along that segment's waypoints the next leg drives.
        progress: The progress the vehicle has on the next leg (``FORWARD`` nose first, ``REVERSE``
            backing).
        joint: The joint crossed from the leg before (``SAME``, ``OPPOSITE`` or ``TURN_IN_PLACE``).
    """

    segment: int
    traverse: Traverse
    progress: Progress
    joint: JointKind


_KEEP_OR_FLIP = {
    Progress.FORWARD: (Progress.FORWARD, Progress.REVERSE),
    Progress.REVERSE: (Progress.REVERSE, Progress.FORWARD),
}
_KEEP = {Progress.FORWARD: (Progress.FORWARD,), Progress.REVERSE: (Progress.REVERSE,)}
_FLIP = {Progress.FORWARD: (Progress.REVERSE,), Progress.REVERSE: (Progress.FORWARD,)}


def progresses_after(capability: TurnCapability, joint: JointKind, progress: Progress) -> tuple[Progress, ...]:
    """The progresses a vehicle of ``capability`` may have on the next leg, after a joint of kind ``joint``
    crossed with ``progress``; the progress it has first (kept where it may be kept), empty when the joint
    cannot be taken."""
    if capability is TurnCapability.IN_PLACE:
        return _KEEP_OR_FLIP[progress]
    if joint is JointKind.SAME:
        return _KEEP[progress]
    if joint is JointKind.OPPOSITE:
        return _FLIP[progress]
    return ()


# The rule as a table, for route searches that ask it per connection: RULES[capability][joint][progress]
# is progresses_after(capability, joint, progress), without a call.
RULES: dict[TurnCapability, dict[JointKind, dict[Progress, tuple[Progress, ...]]]] = {
    capability: {
        joint: {progress: progresses_after(capability, joint, progress) for progress in Progress} for joint in JointKind
    }
    for capability in TurnCapability
}


def capability_of(vehicle: TurnCapability | Turning) -> TurnCapability:
    """The turn capability itself, or a vehicle type's."""
    return vehicle if isinstance(vehicle, TurnCapability) else vehicle.turn_capability
