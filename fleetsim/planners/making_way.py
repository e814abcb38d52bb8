"""Where a vehicle can go to get out of another's way: the nearest places off a route, and the drive there.

A *way out* is a drive from the vehicle's state to a segment outside the area to keep clear, on segments
no other vehicle holds — except vehicles that may themselves be moved (``movable``): crossing their
holdings costs extra and names them, so the planner can move them first. The place at the end is free of
every other vehicle's fixed legs. Ways out are ordered: those that move nobody else first, then places
few routes come near (where the vehicle will not be in the way again soon), then the shortest drive.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable
from collections.abc import Set as AbstractSet
from dataclasses import dataclass, field
from typing import ClassVar

from fleetsim.enums import JointKind, TurnCapability
from fleetsim.layout.layout import Layout
from fleetsim.layout.reachability import State, state_key
from fleetsim.planners.fleet_index import FleetIndex
from fleetsim.planners.routing import Recent, StepTable, rebuild_path

__all__ = ["Reads", "WayOut", "WaysOutMemo", "ways_out"]

_CROSSING_PENALTY = 30.0  # metres added for driving where a movable vehicle stands


@dataclass(frozen=True, slots=True)
class WayOut:
    """A drive to a waiting place: the states to drive (the last is the place) and who must move first."""

    path: tuple[State, ...]
    crossing: tuple[int, ...]  # movable vehicles whose fixed legs the drive comes near, by id
    routes_near: int  # how many other vehicles' routes come near the place
    cost: float


def ways_out(
    vehicle: int,
    start: State,
    capability: TurnCapability,
    avoid: AbstractSet[int],
    layout: Layout,
    index: FleetIndex,
    lengths: dict[int, float],
    movable: Callable[[int], bool],
    *,
    turnaround: float,
    limit: int,
    wanted: int = 6,
    table: StepTable | None = None,
) -> list[WayOut]:
    """Up to ``wanted`` ways out for ``vehicle`` from ``start`` to a segment outside ``avoid``, best first.

    ``table``: the layout's steps for ``capability``, kept between searches (else worked out for this one).
    Nothing changes during a search, so each segment's holders and each vehicle's ``movable`` are asked
    once per search.
    """
    steps = table if table is not None else StepTable(layout, capability)
    return _search(vehicle, start, avoid, index, lengths, movable, turnaround, limit, wanted, steps).ways


@dataclass(slots=True)
class _Found:
    """A search's ways out and everything it read, as it was at the index's ``tick``: each segment's holders
    and each place's count of routes near, and the vehicles it asked whether they may be moved, with the
    answers in the order asked."""

    ways: list[WayOut]
    tick: int
    held: tuple[tuple[int, list[int]], ...]
    routes: tuple[tuple[int, int], ...]
    asked: tuple[tuple[int, bool], ...]

    def holds(self, vehicle: int, index: FleetIndex, movable: Callable[[int], bool]) -> bool:
        """Whether the search would read the same now (and so find the same ways). A segment stamped later
        than the search may hold what it held then (a plan counted and taken back, say): it is read again."""
        if index.tick != self.tick:
            stamps, tick = index.stamps, self.tick
            for segment, holders in self.held:
                if stamps.get(segment, 0) > tick and index.holders(vehicle, segment) != holders:
                    return False
            for segment, count in self.routes:
                if index.route_stamp(segment) > tick and index.routes_near(vehicle, segment) != count:
                    return False
        for other, answer in self.asked:
            if movable(other) != answer:
                return False
        self.tick = index.tick  # read again: as it is now
        return True


def _search(
    vehicle: int,
    start: State,
    avoid: AbstractSet[int],
    index: FleetIndex,
    lengths: dict[int, float],
    movable: Callable[[int], bool],
    turnaround: float,
    limit: int,
    wanted: int,
    table: StepTable,
) -> _Found:
    steps = table.steps
    held: dict[int, list[int]] = {}  # segment -> its holders (other than the vehicle)
    # segment -> what crossing it adds (for the movable vehicles holding it), None: held by one that is not
    crossing_cost: dict[int, float | None] = {}
    asked: dict[int, bool] = {}  # vehicle -> whether it may be moved
    routes: list[tuple[int, int]] = []  # the places found, and how many routes come near each

    def holders(segment: int) -> list[int]:
        found = held.get(segment)
        if found is None:
            found = held[segment] = index.holders(vehicle, segment)
        return found

    def may_move(other: int) -> bool:
        answer = asked.get(other)
        if answer is None:
            answer = asked[other] = movable(other)
        return answer

    def extra(segment: int) -> float | None:
        others = holders(segment)
        cost = crossing_cost[segment] = (
            _CROSSING_PENALTY * len(others) if all(may_move(other) for other in others) else None
        )
        return cost

    best: dict[State, float] = {start: 0.0}
    came_from: dict[State, State] = {}
    heap: list[tuple[float, tuple[int, int, int], State]] = [(0.0, state_key(start), start)]
    found: list[WayOut] = []
    looked = 0
    while heap and looked < limit and len(found) < wanted:
        spent, _, state = heapq.heappop(heap)
        if spent > best.get(state, math.inf):
            continue
        looked += 1
        if state != start and state[0] not in avoid and not holders(state[0]):
            path = rebuild_path(came_from, state)
            crossing = sorted({other for s, _, _ in path for other in holders(s)})
            near = index.routes_near(vehicle, state[0])
            routes.append((state[0], near))
            found.append(WayOut(tuple(path), tuple(crossing), near, spent))
            continue  # a place to wait: no need to drive on through it
        for following, joint, key in steps(state):
            segment = following[0]
            added = crossing_cost[segment] if segment in crossing_cost else extra(segment)
            if added is None:
                continue  # held by a vehicle that will not make way
            total = spent + lengths[segment] + (turnaround if joint is JointKind.OPPOSITE else 0.0)
            total += added
            if total < best.get(following, math.inf):
                best[following] = total
                came_from[following] = state
                heapq.heappush(heap, (total, key, following))
    ways = sorted(found, key=lambda way: (bool(way.crossing), way.routes_near, way.cost, state_key(way.path[-1])))
    return _Found(ways, index.tick, tuple(held.items()), tuple(routes), tuple(asked.items()))


@dataclass(slots=True)
class Reads:
    """What several searches for ways out read, gathered (for a planner's quiet hint, which names what to
    wait for): the searches themselves, whose segments' holders were read and whose vehicles were asked
    whether they may be moved (:meth:`segments`, :meth:`vehicles`: gathered only when a hint is given),
    the places whose count of routes near ordered the ways found (:meth:`routes`), other vehicles read
    (``others``), and where the attempts sent vehicles to wait (``sent``: vehicle -> the segment last
    noted for it; made again, they would note the same again)."""

    others: set[int]
    found: list[_Found] = field(default_factory=list)
    sent: dict[int, int | None] = field(default_factory=dict)

    def add(self, found: _Found) -> None:
        self.found.append(found)

    def segments(self) -> set[int]:
        return {segment for found in self.found for segment, _ in found.held}

    def routes(self) -> set[int]:
        """The places whose count of routes near ordered two or more ways found (one way needs no order)."""
        return {segment for found in self.found if len(found.ways) > 1 for segment, _ in found.routes}

    def vehicles(self) -> set[int]:
        return self.others.union(*({vehicle for vehicle, _ in found.asked} for found in self.found))


class WaysOutMemo:
    """Ways out found, given again while nothing the search read has changed.

    A vehicle that stands blocked is asked about on every planning round, and looks for the same ways out
    for itself and its blockers each time, in a fleet that has mostly not changed where the search looked
    (in a congested shift nearly every search repeats one of the step before). A search reads the holders
    of the segments it reached and the routes near the places it found (the fleet index stamps each
    segment when those change) and asks some vehicles whether they may be moved. A search with the same
    arguments whose segments are unchanged and whose vehicles answer the same again (asked again, in the
    same order, as the search would) would find the same ways: those are given, and the search is not
    made. The answers are exactly the searches'.

    The last ``variants`` searches with the same arguments are kept: a blocked vehicle's helpers are
    searched for with and without the plans of those moved before them, in turn, on every round.
    """

    # Searches kept at most; when full, all are forgotten (a shift makes a few thousand distinct ones a
    # minute, nearly all of them repeated minutes on end). 0: none kept (every search made).
    capacity: ClassVar[int] = 50_000
    # Searches kept per arguments, the latest first.
    variants: ClassVar[int] = 2

    def __init__(self) -> None:
        self._found: Recent[_Found] = Recent(self.capacity, self.variants)
        # (id of the area, id of the way) -> (the area, the way, the area with the segments near the way)
        self._regions: dict[tuple[int, int], tuple[AbstractSet[int], WayOut, frozenset[int]]] = {}
        self.asked = 0  # ways out asked for
        self.searched = 0  # searches made for them

    def ways_out(
        self,
        vehicle: int,
        start: State,
        avoid: AbstractSet[int],
        index: FleetIndex,
        lengths: dict[int, float],
        movable: Callable[[int], bool],
        *,
        turnaround: float,
        limit: int,
        table: StepTable,
        wanted: int = 6,
        reads: Reads | None = None,
    ) -> list[WayOut]:
        """As :func:`ways_out`, the layout's steps (``table``, for the vehicle's turn capability) given;
        what the search read (remembered or made) is added to ``reads``."""
        self.asked += 1
        key = (vehicle, start, frozenset(avoid), table.capability, turnaround, limit, wanted)
        for found in self._found.get(key):
            if found.holds(vehicle, index, movable):
                if reads is not None:
                    reads.add(found)
                return found.ways
        self.searched += 1
        found = _search(vehicle, start, avoid, index, lengths, movable, turnaround, limit, wanted, table)
        self._found.keep(key, found)
        if reads is not None:
            reads.add(found)
        return found.ways

    def widened(self, avoid: AbstractSet[int], start: State, way: WayOut, layout: Layout) -> frozenset[int]:
        """``avoid`` and the segments near ``start`` and ``way``'s drive (the way out of a search from
        ``start``): where those the way crosses must go out of. Kept for an ``avoid`` that cannot change (a
        frozenset), so that the same area is the same object, whose hash is worked out once."""
        key = (id(avoid), id(way))
        kept = self._regions.get(key)
        if kept is not None and kept[0] is avoid and kept[1] is way:
            return kept[2]
        region = frozenset(avoid).union(
            near for segment, _, _ in (start, *way.path) for near in layout.conflicts(segment)
        )
        if self.capacity and isinstance(avoid, frozenset):
            if len(self._regions) >= self.capacity:
                self._regions.clear()
            self._regions[key] = (avoid, way, region)
        return region
