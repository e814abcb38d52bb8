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
    """The way a vehicle drives along a segment's waypoints."""

    __hash__ = str.__hash__  # hash like the equal string, so "forward" finds Traverse.FORWARD in a dict

    FORWARD = "forward"
    BACKWARD = "backward"

    @property
    def reversed(self) -> Traverse:
        return Traverse.BACKWARD if self is Traverse.FORWARD else Traverse.FORWARD

    def __str__(self) -> str:
        return self.value


class Progress(str, Enum):
    """How a vehicle moves relative to its own nose: nose first, or backing."""

    __hash__ = str.__hash__

    FORWARD = "forward"
    REVERSE = "reverse"

    @property
    def flipped(self) -> Progress:
        return Progress.REVERSE if self is Progress.FORWARD else Progress.FORWARD

    def __str__(self) -> str:
        return self.value


class Direction(str, Enum):
    """The driving direction a segment allows."""

    __hash__ = str.__hash__

    BOTH = "both"
    FORWARD = "forward"
    BACKWARD = "backward"

    def allows(self, traverse: Traverse) -> bool:
        return self is Direction.BOTH or self.value == traverse.value

    def __str__(self) -> str:
        return self.value


class Shape(str, Enum):
    """The drawing template a segment came from."""

    __hash__ = str.__hash__

    STRAIGHT = "straight"
    CURVE = "curve"
    S_CURVE = "s_curve"
    PATH = "path"  # a free-form polyline: drawn freely, or imported (LIF edges, RMF lanes)

    def __str__(self) -> str:
        return self.value


class JointKind(str, Enum):
    """How two connected segments meet (the thesis's "NextProgressDirection")."""

    __hash__ = str.__hash__

    SAME = "same"  # smooth continuation: progress direction unchanged
    OPPOSITE = "opposite"  # a cusp: the vehicle must reverse its progress direction
    TURN_IN_PLACE = "turn_in_place"  # a corner only an in-place turner can take

    def __str__(self) -> str:
        return self.value


class TurnCapability(str, Enum):
    """Whether a vehicle type can only follow curves or can also turn on the spot."""

    __hash__ = str.__hash__

    CURVE = "curve"
    IN_PLACE = "in_place"

    def __str__(self) -> str:
        return self.value


class ConflictModel(str, Enum):
    """How conflicting segments are found: swept circles (default) or the thesis's bounding boxes."""

    __hash__ = str.__hash__

    SWEPT = "swept"
    BBOX = "bbox"

    def __str__(self) -> str:
        return self.value


class Disturbed(str, Enum):
    """What a disturbance does to a vehicle now, as a fleet manager would see it (not for how long)."""

    __hash__ = str.__hash__

    STOPPED = "stopped"
    SLOWED = "slowed"

    def __str__(self) -> str:
        return self.value
