"""Room for vehicles: how many starts a layout has that keep every pair of vehicles apart.

Two starts are apart when their conflict sets share no segment (the rule the scenarios strategy has
always kept). Drawn one after another at random, starts block each other: in a one-junction warehouse
the first vehicle on a crossing straight leaves no room for a second. So the strategy keeps a *spare
set*: starts that are pairwise apart, each usable by every vehicle type, at least as many as vehicles
still to place; a start is drawn only where enough of the spare set survives it.

The spare set is a greedy choice (fewest clashes first, ties by segment id): a lower bound on a
layout's room that depends on nothing but the layout. It is computed with the largest conflict radius
any of the spec's types gives, so it stays apart for any mix of types drawn (a smaller radius only
shrinks conflict sets).
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable, Sequence

from fleetsim.enums import Progress, Traverse, TurnCapability
from fleetsim.layout.layout import Layout
from fleetsim.planners.routing import next_states

__all__ = ["NoRoomError", "Room", "clashes", "spare_starts"]


class NoRoomError(ValueError):
    """No layout the spec allows has room for its largest number of vehicles.

    ``kind`` and ``size`` are the spec's, ``vehicles`` its vehicle range, ``room`` the most vehicles
    any allowed layout has room for, ``radius`` the conflict radius that was assumed (metres).
    """

    def __init__(self, kind: str, size: tuple[int, int], vehicles: tuple[int, int], room: int, radius: float) -> None:
        self.kind = kind
        self.size = size
        self.vehicles = vehicles
        self.room = room
        self.radius = radius
        super().__init__(self.describe(f"vehicles={vehicles!r}", f"size={size!r}", "larger layouts"))

    def describe(self, vehicles: str, size: str, remedy: str) -> str:
        """The message, with the spec's fields spelled as the reader wrote them."""
        kinds = "layouts of any kind" if self.kind == "any" else f"{self.kind} layouts"
        return (
            f"{vehicles} needs room for {self.vehicles[1]} vehicles with non-conflicting starts, but {kinds} of "
            f"{size} have room for {self.room} (vehicle radius {self.radius:.2f} m); allow {remedy} or fewer vehicles"
        )


def clashes(layout: Layout, segment: int) -> frozenset[int]:
    """Segments a vehicle may not start on while another starts on ``segment``: their conflict sets meet."""
    return frozenset().union(*(layout.conflicts(other) for other in layout.conflicts(segment)))


def _startable(layout: Layout, segment: int, capabilities: Collection[TurnCapability]) -> bool:
    """Every capability has a state on ``segment`` to start in with somewhere to go."""
    allowed = [t for t in Traverse if layout.segments[segment].allows(t)]
    return all(
        any(any(True for _ in next_states(layout, capability, (segment, t, p))) for t in allowed for p in Progress)
        for capability in capabilities
    )


def spare_starts(
    layout: Layout, capabilities: Collection[TurnCapability], among: Iterable[int] | None = None
) -> frozenset[int]:
    """Start segments pairwise apart and usable by every capability: greedily, fewest clashes first.

    With ``among``, only those segments are candidates.
    """
    candidates = layout.segments if among is None else among
    free = {sid for sid in candidates if _startable(layout, sid, capabilities)}
    clash = {sid: clashes(layout, sid) & free for sid in free}
    chosen: set[int] = set()
    while free:
        pick = min(sorted(free), key=lambda sid: len(clash[sid] & free))
        chosen.add(pick)
        free -= clash[pick]
    return frozenset(chosen)


class Room:
    """How many vehicles the plainest layout of each kind and size has room for (memoised).

    ``plainest(kind, size)`` builds that layout as a :class:`Layout` with the spec's largest radius;
    options a drawn layout adds (passing bays, lane shifts) are checked on the layout itself.
    """

    def __init__(self, plainest: Callable[[str, int], Layout], capabilities: Collection[TurnCapability]) -> None:
        self._plainest = plainest
        self.capabilities = frozenset(capabilities)
        self._spare: dict[tuple[str, int], frozenset[int]] = {}

    def layout(self, kind: str, size: int) -> Layout:
        return self._plainest(kind, size)

    def spare(self, kind: str, size: int) -> frozenset[int]:
        if (kind, size) not in self._spare:
            self._spare[kind, size] = spare_starts(self._plainest(kind, size), self.capabilities)
        return self._spare[kind, size]

    def smallest(self, kind: str, sizes: Sequence[int], count: int) -> int | None:
        """The smallest of ``sizes`` whose plainest layout has room for ``count`` vehicles, if any."""
        return next((size for size in sizes if len(self.spare(kind, size)) >= count), None)

    def most(self, kinds: Iterable[str], sizes: Sequence[int]) -> int:
        """The most vehicles any plainest layout of ``kinds`` and ``sizes`` has room for."""
        return max(len(self.spare(kind, size)) for kind in kinds for size in sizes)
