"""The domain vocabulary of SPEC §2 as string enums (their values are the words used in files)."""

from __future__ import annotations

from enum import Enum

__all__ = [
    "ConflictModel",
    "Direction",
    "Disturbed",
    "JointKind",
    "Progress",
    "Shape",
    "Traverse",
    "TurnCapability",
]


class Traverse(str, Enum):
    """The way a vehicle drives along a segment's waypoints (a leg's ``traverse``).

    Attributes:
        FORWARD: ``"forward"``: from the first waypoint to the last.
        BACKWARD: ``"backward"``: from the last waypoint to the first.
    """

    __hash__ = str.__hash__  # hash like the equal string, so "forward" finds Traverse.FORWARD in a dict

    FORWARD = "forward"
    BACKWARD = "backward"

    @property
    def reversed(self) -> Traverse:
        """The other traverse: the way back along the same waypoints."""
        return Traverse.BACKWARD if self is Traverse.FORWARD else Traverse.FORWARD

    def __str__(self) -> str:
        return self.value


class Progress(str, Enum):
    """How a vehicle moves relative to its own nose: nose first, or backing (a leg's ``progress``).

    Whatever the traverse: a vehicle driving a segment ``BACKWARD`` nose first has ``FORWARD`` progress.

    Attributes:
        FORWARD: ``"forward"``: nose first; the heading is the travel direction.
        REVERSE: ``"reverse"``: backing; the heading is the travel direction plus π.
    """

    __hash__ = str.__hash__

    FORWARD = "forward"
    REVERSE = "reverse"

    @property
    def flipped(self) -> Progress:
        """The other progress direction (what a cusp, ``JointKind.OPPOSITE``, does to a curve vehicle's)."""
        return Progress.REVERSE if self is Progress.FORWARD else Progress.FORWARD

    def __str__(self) -> str:
        return self.value


class Direction(str, Enum):
    """The traverses a segment allows (its ``direction`` property in the map).

    Attributes:
        BOTH: ``"both"``: two-way, either traverse.
        FORWARD: ``"forward"``: one-way, ``Traverse.FORWARD`` only (first waypoint to last).
        BACKWARD: ``"backward"``: one-way, ``Traverse.BACKWARD`` only (last waypoint to first).
    """

    __hash__ = str.__hash__

    BOTH = "both"
    FORWARD = "forward"
    BACKWARD = "backward"

    def allows(self, traverse: Traverse) -> bool:
        """Whether a leg may drive the segment with ``traverse`` (else check code ``wrong-way``)."""
        return self is Direction.BOTH or self.value == traverse.value

    def __str__(self) -> str:
        return self.value


class Shape(str, Enum):
    """The drawing template a segment came from (the Tiled object's class). Informative only: what a
    vehicle may do at a segment's ends is told by the joints, not the shape.

    Attributes:
        STRAIGHT: ``"straight"``: a straight line.
        CURVE: ``"curve"``: an arc (the shipped template: a 90° turn).
        S_CURVE: ``"s_curve"``: an S-bend, ending parallel to where it starts (a lane change).
        PATH: ``"path"``: a free-form polyline (drawn freely, or imported: LIF edges, RMF lanes).
    """

    __hash__ = str.__hash__

    STRAIGHT = "straight"
    CURVE = "curve"
    S_CURVE = "s_curve"
    PATH = "path"

    def __str__(self) -> str:
        return self.value


class JointKind(str, Enum):
    """How two connected segments meet (the thesis's "NextProgressDirection"), from the angle between
    them at the joint and the layout's ``joint_angle_tolerance``.

    Attributes:
        SAME: ``"same"``: a smooth continuation; a ``CURVE`` vehicle keeps its progress.
        OPPOSITE: ``"opposite"``: a cusp (the next segment doubles back, as at a U-turn onto the same
            segment); a ``CURVE`` vehicle must flip its progress (``Progress.flipped``).
        TURN_IN_PLACE: ``"turn_in_place"``: a corner; only an ``IN_PLACE`` vehicle can take it, stopping
            to turn on the spot.
    """

    __hash__ = str.__hash__

    SAME = "same"
    OPPOSITE = "opposite"
    TURN_IN_PLACE = "turn_in_place"

    def __str__(self) -> str:
        return self.value


class TurnCapability(str, Enum):
    """Whether a vehicle type can only follow curves or can also turn on the spot (``turn_capability``).

    Attributes:
        CURVE: ``"curve"``: follows curves only: keeps its progress at ``SAME`` joints, flips it at
            ``OPPOSITE`` joints (cusps) and cannot take ``TURN_IN_PLACE`` joints (check code
            ``illegal-progress-change``).
        IN_PLACE: ``"in_place"``: may take any joint with either progress; it stops and turns on the spot
            (at ``VehicleType.turn_rate``) wherever its heading changes by more than the joint tolerance.
    """

    __hash__ = str.__hash__

    CURVE = "curve"
    IN_PLACE = "in_place"

    def __str__(self) -> str:
        return self.value


class ConflictModel(str, Enum):
    """How conflicting segments are found: swept circles (default) or the thesis's bounding boxes.

    Attributes:
        SWEPT: ``"swept"``: two segments conflict when their polylines come closer than twice the vehicle
            radius plus the safety margin (metres): the circles of two vehicles on them could touch.
        BBOX: ``"bbox"``: the thesis's model: their bounding boxes, grown by the vehicle radius plus half
            the safety margin on each side, overlap (false positives on curves).
    """

    __hash__ = str.__hash__

    SWEPT = "swept"
    BBOX = "bbox"

    def __str__(self) -> str:
        return self.value


class Disturbed(str, Enum):
    """What a disturbance does to a vehicle now, as a fleet manager would see it (not for how long):
    ``VehicleState.disturbed``.

    Attributes:
        STOPPED: ``"stopped"``: it stands still, wherever its plan goes.
        SLOWED: ``"slowed"``: it drives below its type's ``max_speed``.
    """

    __hash__ = str.__hash__

    STOPPED = "stopped"
    SLOWED = "slowed"

    def __str__(self) -> str:
        return self.value
