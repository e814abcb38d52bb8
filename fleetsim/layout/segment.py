"""A segment: one piece of the driving map (SPEC §2)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from fleetsim.enums import Direction, Shape, Traverse

__all__ = ["Point", "Segment", "polyline_length"]

Point = tuple[float, float]


def polyline_length(waypoints: tuple[Point, ...]) -> float:
    """Sum of the straight pieces between consecutive waypoints, in metres."""
    return math.fsum(math.dist(a, b) for a, b in zip(waypoints, waypoints[1:]))


@dataclass(frozen=True, slots=True)
class Segment:
    """An immutable segment: Tiled object id, world waypoints in metres, shape and allowed direction."""

    id: int
    shape: Shape
    direction: Direction
    waypoints: tuple[Point, ...]
    length: float = field(init=False, compare=False)

    def __post_init__(self) -> None:
        if len(self.waypoints) < 2:
            msg = f"segment {self.id} needs at least 2 waypoints, got {len(self.waypoints)}"
            raise ValueError(msg)
        object.__setattr__(self, "length", polyline_length(self.waypoints))

    @property
    def first(self) -> Point:
        return self.waypoints[0]

    @property
    def last(self) -> Point:
        return self.waypoints[-1]

    def entry(self, traverse: Traverse) -> Point:
        """Where a vehicle driving ``traverse`` enters this segment."""
        return self.first if traverse is Traverse.FORWARD else self.last

    def exit(self, traverse: Traverse) -> Point:
        """Where a vehicle driving ``traverse`` leaves this segment."""
        return self.last if traverse is Traverse.FORWARD else self.first

    def allows(self, traverse: Traverse) -> bool:
        return self.direction.allows(traverse)
