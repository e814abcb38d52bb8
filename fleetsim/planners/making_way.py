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
from dataclasses import dataclass

from fleetsim.enums import JointKind, TurnCapability
from fleetsim.layout.layout import Layout
from fleetsim.layout.reachability import State, state_key
from fleetsim.planners.fleet_index import FleetIndex
from fleetsim.planners.routing import StepTable, rebuild_path

__all__ = ["WayOut", "ways_out"]

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
    steps = (table if table is not None else StepTable(layout, capability)).steps
    held: dict[int, list[int]] = {}  # segment -> its holders (other than the vehicle)
    # segment -> what crossing it adds (for the movable vehicles holding it), None: held by one that is not
    crossing_cost: dict[int, float | None] = {}

    def holders(segment: int) -> list[int]:
        found = held.get(segment)
        if found is None:
            found = held[segment] = index.holders(vehicle, segment)
        return found

    def extra(segment: int) -> float | None:
        others = holders(segment)
        cost = crossing_cost[segment] = (
            _CROSSING_PENALTY * len(others) if all(movable(other) for other in others) else None
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
            found.append(WayOut(tuple(path), tuple(crossing), index.routes_near(vehicle, state[0]), spent))
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
    return sorted(found, key=lambda way: (bool(way.crossing), way.routes_near, way.cost, state_key(way.path[-1])))
