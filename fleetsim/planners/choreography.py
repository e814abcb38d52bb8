"""The last resort for a few vehicles stuck in each other's way: a joint search, one leg at a time.

When vehicles block each other where no one can simply get out of the way (a small loop, a corridor
with its only passing place taken), the planner searches their joint positions: in each move one vehicle
drives on one leg, onto a segment that conflicts with no other vehicle of the group and with nothing the
rest of the fleet holds. Best first, the search finds moves after which the vehicle that asked reaches
its goal. The moves are then danced in order: a vehicle fixes its next move only when
every move before it is done, so the group never meets a situation the search did not foresee.
"""

from __future__ import annotations

import heapq
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from fleetsim.enums import Progress, TurnCapability
from fleetsim.layout.layout import Layout
from fleetsim.layout.reachability import State, next_states
from fleetsim.planners.routing import StepTable

__all__ = ["Dance", "choreograph"]

Positions = tuple[State, ...]


def choreograph(
    layout: Layout,
    vehicles: Sequence[int],
    starts: Mapping[int, State],
    capabilities: Mapping[int, TurnCapability],
    blocked: set[int] | frozenset[int],
    goal: tuple[int, int, Progress | None],
    limit: int,
    table: StepTable | None = None,
) -> list[tuple[int, State]] | None:
    """Single-leg moves of ``vehicles`` after which ``goal``'s vehicle stands on its goal segment (with
    its progress, when one is asked of a vehicle that cannot turn in place); None if the search finds
    none within ``limit`` joint positions. ``blocked`` are segments others hold. ``table``: the layout's
    steps for the goal's vehicle's turn capability, kept between searches (else worked out for this one).

    Best first: fewest moves plus twice the legs the goal's vehicle still has to drive (alone), so the
    search heads for the goal and spends its effort on the moves that clear the way.
    """
    who, segment_goal, progress = goal
    mover = vehicles.index(who)
    must_match = progress is not None and capabilities[who] is TurnCapability.CURVE
    if table is None or table.layout is not layout or table.capability is not capabilities[who]:
        table = StepTable(layout, capabilities[who])
    to_go = _legs_to_goal(table, segment_goal, progress if must_match else None, blocked)
    start: Positions = tuple(starts[v] for v in vehicles)
    if start[mover] not in to_go:
        return None
    came_from: dict[Positions, tuple[Positions, int]] = {}
    spent = {start: 0}
    heap: list[tuple[int, int, Positions]] = [(2 * to_go[start[mover]], 0, start)]
    order = 0
    while heap and len(spent) < limit:
        _, _, here = heapq.heappop(heap)
        cost = spent[here] + 1
        for index, vehicle in enumerate(vehicles):
            others = {here[k][0] for k in range(len(vehicles)) if k != index}
            for following in next_states(layout, capabilities[vehicle], here[index]):
                segment = following[0]
                if segment in blocked or layout.conflicts(segment) & others:
                    continue
                there = (*here[:index], following, *here[index + 1 :])
                if there in spent:
                    continue
                spent[there] = cost
                came_from[there] = (here, index)
                if index == mover and segment == segment_goal and (not must_match or following[2] is progress):
                    return _moves(came_from, there, vehicles)
                remaining = to_go.get(there[mover])
                if remaining is not None:
                    order += 1
                    heapq.heappush(heap, (cost + 2 * remaining, order, there))
    return None


def _legs_to_goal(
    table: StepTable, goal: int, progress: Progress | None, blocked: set[int] | frozenset[int]
) -> dict[State, int]:
    """For each state, the fewest legs to the goal segment, alone (breadth first, backwards)."""
    before = table.predecessors()
    ends = [state for state in before if state[0] == goal and (progress is None or state[2] is progress)]
    distance = dict.fromkeys(ends, 0)
    frontier = deque(ends)
    while frontier:
        state = frontier.popleft()
        for earlier in before.get(state, ()):
            if earlier not in distance and earlier[0] not in blocked:
                distance[earlier] = distance[state] + 1
                frontier.append(earlier)
    return distance


def _moves(
    came_from: Mapping[Positions, tuple[Positions, int]], end: Positions, vehicles: Sequence[int]
) -> list[tuple[int, State]]:
    moves: list[tuple[int, State]] = []
    here = end
    while here in came_from:
        before, index = came_from[here]
        moves.append((vehicles[index], here[index]))
        here = before
    moves.reverse()
    return moves


@dataclass
class Dance:
    """Moves being danced: who drives which leg, in order; how many are done."""

    moves: list[tuple[int, State]]
    started: float
    done: int = 0
    progressed: float = field(default=0.0)

    @property
    def vehicles(self) -> frozenset[int]:
        return frozenset(vehicle for vehicle, _ in self.moves)

    def advance(self, current: Mapping[int, State], time: float) -> None:
        """Count the moves done: a move is done once its vehicle is on the leg it moved to."""
        while self.done < len(self.moves):
            vehicle, state = self.moves[self.done]
            if current.get(vehicle) != state:
                break
            self.done += 1
            self.progressed = time

    @property
    def finished(self) -> bool:
        return self.done >= len(self.moves)
