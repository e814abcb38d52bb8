"""Route search over (segment, traverse, progress) states, shared by the reference planners.

A vehicle's next states (:func:`~fleetsim.layout.reachability.next_steps`, re-exported here) follow the
layout's connections and the progress rules of SPEC §4; the scenario loader's task check uses the same
rules, so a goal it accepts is one these searches can find. Equal-cost ties are broken by
:func:`~fleetsim.layout.reachability.state_key`, never by hashing or insertion order.
"""

from __future__ import annotations

import heapq
import math
from collections import deque
from collections.abc import Callable, Sequence
from collections.abc import Set as AbstractSet
from dataclasses import dataclass, replace
from typing import ClassVar, Generic, TypeVar

from fleetsim.enums import JointKind, Progress, Traverse, TurnCapability
from fleetsim.layout.layout import Layout
from fleetsim.layout.reachability import State, next_states, next_steps, state_key
from fleetsim.planners.fleet_index import FleetIndex
from fleetsim.planning.plans import FleetLeg
from fleetsim.scenario import Task

__all__ = [
    "Recent",
    "RouteFound",
    "RoutesMemo",
    "State",
    "StepTable",
    "breadth_first_route",
    "legs_along",
    "mark_goal_on_fixed",
    "next_states",
    "next_steps",
    "rebuild_path",
    "shortest_route",
    "straight_line_estimate",
]

Cost = Callable[[int, Traverse, JointKind], float]  # (segment entered, its traverse, joint crossed)
Estimate = Callable[[int, Traverse], float]  # a lower bound of the cost from a state to the goal


def rebuild_path(came_from: dict[State, State], end: State) -> list[State]:
    """The states from the search's start (excluded) to ``end``, following ``came_from`` back."""
    path = [end]
    while path[-1] in came_from:
        path.append(came_from[path[-1]])
    path.reverse()
    return path[1:]  # without the start state


def breadth_first_route(layout: Layout, capability: TurnCapability, start: State, goal: int) -> list[State] | None:
    """Fewest legs from ``start`` to any state on segment ``goal`` (``start`` itself excluded)."""
    came_from: dict[State, State] = {}
    frontier = deque([start])
    seen = {start}
    while frontier:
        state = frontier.popleft()
        for following in next_states(layout, capability, state):
            if following in seen:
                continue
            seen.add(following)
            came_from[following] = state
            if following[0] == goal:
                return rebuild_path(came_from, following)
            frontier.append(following)
    return None


Step = tuple[State, JointKind, tuple[int, int, int]]  # a next state, the joint crossed, its state_key


class StepTable:
    """One layout's :func:`next_steps` for one turn capability, each state's worked out once (with each
    next state's :func:`state_key`), and each state's exit point: what every route search asks again and
    again, looked up instead of worked out."""

    def __init__(self, layout: Layout, capability: TurnCapability) -> None:
        self.layout, self.capability = layout, capability
        self._steps: dict[State, tuple[Step, ...]] = {}
        self._exits: dict[tuple[int, Traverse], tuple[float, float]] = {}
        self._before: dict[State, list[State]] | None = None  # predecessors()
        # Per goal segment: the straight-line estimate of each (segment, traverse) asked so far.
        self.estimates: dict[int, dict[tuple[int, Traverse], float]] = {}

    def steps(self, state: State) -> tuple[Step, ...]:
        steps = self._steps.get(state)
        if steps is None:
            found = next_steps(self.layout, self.capability, state)
            steps = self._steps[state] = tuple((following, joint, state_key(following)) for following, joint in found)
        return steps

    def predecessors(self) -> dict[State, list[State]]:
        """Per state, the states from which a vehicle drives on to it (the layout's every state, worked out
        at the first call; read only)."""
        if self._before is None:
            before: dict[State, list[State]] = {}
            layout, capability = self.layout, self.capability
            for segment, item in layout.segments.items():
                for traverse in (Traverse.FORWARD, Traverse.BACKWARD):
                    if not item.allows(traverse):
                        continue
                    for progress in Progress:
                        state = (segment, traverse, progress)
                        for following in next_states(layout, capability, state):
                            before.setdefault(following, []).append(state)
            self._before = before
        return self._before

    def exit(self, segment: int, traverse: Traverse) -> tuple[float, float]:
        point = self._exits.get((segment, traverse))
        if point is None:
            point = self._exits[segment, traverse] = self.layout.segments[segment].exit(traverse)
        return point


def straight_line_estimate(layout: Layout, goal: int, table: StepTable | None = None) -> Estimate:
    """An A* estimate that never overestimates a route's length to ``goal``.

    From the exit of a state, the vehicle must still reach an end of the goal segment (at least the
    straight-line distance) and then drive the whole goal segment. ``table``: where exits are looked up,
    and where the estimates for ``goal`` are kept once worked out (searches to one goal share them).
    """
    target = layout.segments[goal]
    (ax, ay), (bx, by) = target.first, target.last
    length = target.length
    segments = layout.segments
    hypot = math.hypot
    exit_of = table.exit if table is not None else (lambda segment, traverse: segments[segment].exit(traverse))

    def estimate(segment: int, traverse: Traverse) -> float:
        if segment == goal:
            return 0.0
        x, y = exit_of(segment, traverse)
        return min(hypot(x - ax, y - ay), hypot(x - bx, y - by)) + length

    if table is None:
        return estimate
    known = table.estimates.setdefault(goal, {})

    def remembered(segment: int, traverse: Traverse) -> float:
        value = known.get((segment, traverse))
        if value is None:
            value = known[segment, traverse] = estimate(segment, traverse)
        return value

    return remembered


def shortest_route(
    layout: Layout,
    capability: TurnCapability,
    start: State,
    goal: int,
    arrive: Progress | None,
    cost: Cost,
    estimate: Estimate | None = None,
    limit: int | None = None,
    bound: float | None = None,
    table: StepTable | None = None,
) -> list[State] | None:
    """Least total ``cost`` from ``start`` to segment ``goal`` (``start`` itself excluded).

    ``cost(segment, traverse, joint)`` is what driving on to a segment costs (at least its length);
    ``estimate(segment, traverse)``, if given, a consistent lower bound of the cost still to come (A*;
    see :func:`straight_line_estimate`), else 0 (Dijkstra). ``arrive`` is the required progress on the
    goal segment; a vehicle that turns in place can always meet it on the last leg, so only a curve-only
    vehicle's progress is constrained. A segment whose cost is infinite is never driven. The search
    gives up (``None``) after looking at ``limit`` states, or once every route left would cost more than
    ``bound``. ``table``: the layout's steps for ``capability``, kept between searches (else worked out
    for this one).
    """
    steps = (table if table is not None else StepTable(layout, capability)).steps
    must_match = arrive is not None and capability is TurnCapability.CURVE
    best: dict[State, float] = {start: 0.0}
    came_from: dict[State, State] = {}
    heap: list[tuple[float, tuple[int, int, int], float, State]] = [(0.0, state_key(start), 0.0, start)]
    infinity = math.inf
    budget = infinity if limit is None else limit
    ceiling = infinity if bound is None else bound
    while heap:
        least, _, spent, state = heapq.heappop(heap)
        if least > ceiling:
            return None
        if spent > best.get(state, infinity):
            continue
        budget -= 1
        if budget < 0:
            return None
        if state != start and state[0] == goal and (not must_match or state[2] is arrive):
            return rebuild_path(came_from, state)
        for following, joint, key in steps(state):
            total = spent + cost(following[0], following[1], joint)
            if total < best.get(following, infinity):
                best[following] = total
                came_from[following] = state
                bound = total + (estimate(following[0], following[1]) if estimate is not None else 0.0)
                heapq.heappush(heap, (bound, key, total, following))
    return None


def legs_along(path: Sequence[State], task: Task, arrive: Progress | None) -> tuple[FleetLeg, ...]:
    """Planned legs for a route, the last one marked as the task's goal (with ``arrive`` if required)."""
    legs = [FleetLeg(segment, traverse, progress, fixed=False) for segment, traverse, progress in path]
    last = legs[-1]
    legs[-1] = replace(last, goal_for_task=task.id, progress=arrive if arrive is not None else last.progress)
    return tuple(legs)


def mark_goal_on_fixed(fixed: Sequence[FleetLeg], task: Task, *, check_progress: bool) -> tuple[FleetLeg, ...] | None:
    """The fixed legs with the task's goal marked on the first that reaches it, or ``None`` if none does.

    A vehicle completes a task on a leg it is committed to when the plan marks that leg as the goal.
    """
    for index, leg in enumerate(fixed):
        matches_progress = not check_progress or task.goal_progress in (None, leg.progress)
        if leg.segment == task.goal_segment and leg.goal_for_task is None and matches_progress:
            marked = list(fixed)
            marked[index] = replace(leg, goal_for_task=task.id)
            return tuple(marked)
    return None


Answer = TypeVar("Answer")

# What a route search read of one (segment, traverse) it looked at driving on to: whether another plan
# drives the segment the other way (the other way's traverse given), and whether the segment is near a
# vehicle without tasks.
RouteRead = tuple[int, Traverse, Traverse, bool, bool]


@dataclass(slots=True)
class RouteFound:
    """A route search's answer (legs, or ``None``: no route) and what it read, as it was at the fleet
    index's ``tick``: each (segment, traverse) it looked at, whether another plan drove that segment the
    other way, and whether it was near a vehicle without tasks (``parked``, ``unparked``: the segments read
    that were and were not)."""

    legs: tuple[FleetLeg, ...] | None
    tick: int
    read: tuple[RouteRead, ...]
    parked: frozenset[int]
    unparked: frozenset[int]

    def holds(self, vehicle: int, index: FleetIndex, parked: AbstractSet[int]) -> bool:
        """Whether the search would read the same now (and so find the same route)."""
        if not self.parked <= parked or not parked.isdisjoint(self.unparked):
            return False
        if index.tick != self.tick:
            stamps, tick = index.drive_stamps, self.tick
            for segment, _, other_way, oncoming, _ in self.read:
                if stamps.get(segment, 0) > tick and index.others_drive(vehicle, segment, other_way) != oncoming:
                    return False
        self.tick = index.tick  # read again: as it is now
        return True


class Recent(Generic[Answer]):
    """Answers kept per question, the latest ``variants`` first; when ``capacity`` questions are kept, all
    are forgotten at once (0: nothing is kept). The answers of a memo whose caller checks which still hold."""

    def __init__(self, capacity: int, variants: int) -> None:
        self.capacity, self.variants = capacity, variants
        self._kept: dict[tuple[object, ...], list[Answer]] = {}

    def get(self, key: tuple[object, ...]) -> Sequence[Answer]:
        return self._kept.get(key, ())

    def keep(self, key: tuple[object, ...], answer: Answer) -> None:
        if not self.capacity:
            return
        if len(self._kept) >= self.capacity:
            self._kept.clear()
        kept = self._kept.get(key)
        if kept is None:
            self._kept[key] = [answer]
        else:
            kept.insert(0, answer)
            del kept[self.variants :]


class RoutesMemo:
    """Routes found, given again while nothing the search read has changed.

    A route's cost reads, besides the layout, whether other plans drive a segment the other way and which
    segments are near vehicles without tasks. A vehicle making way for another is given a route on to its
    goal from the place it waits at, and in a congested shift the same is worked out on every planning
    round. A search with the same arguments whose reads are the same now would find the same route: that
    is given, and the search is not made. The fleet index stamps a segment when a plan driving it changes,
    so only stamped segments are read again. The last ``variants`` searches per question are kept.
    """

    # Searches kept at most; when full, all are forgotten. 0: none kept (every search made).
    capacity: ClassVar[int] = 20_000
    # Searches kept per question, the latest first.
    variants: ClassVar[int] = 2

    def __init__(self) -> None:
        self._found: Recent[RouteFound] = Recent(self.capacity, self.variants)
        self.asked = 0  # routes asked for
        self.searched = 0  # searches made for them

    def get(
        self, key: tuple[object, ...], vehicle: int, index: FleetIndex, parked: AbstractSet[int]
    ) -> RouteFound | None:
        """The remembered answer to the question ``key`` that holds now, if any."""
        self.asked += 1
        for found in self._found.get(key):
            if found.holds(vehicle, index, parked):
                return found
        self.searched += 1
        return None

    def keep(self, key: tuple[object, ...], found: RouteFound) -> None:
        self._found.keep(key, found)
