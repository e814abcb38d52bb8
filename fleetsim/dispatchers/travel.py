"""How long a vehicle needs to reach a stop: the reference dispatchers' measure of distance.

Travel time is the least time over the layout's directed ``(segment, traverse)`` graph from where the
vehicle is committed to be (the rest of the leg it is on, then its further fixed legs) to entering the
stop's segment, by the progress rules of its turn capability (:data:`~fleetsim.layout.continuations.RULES`;
a curve-only vehicle takes no corner and must arrive with the stop's progress if it names one, a vehicle
that turns in place may arrive either way). Each segment costs its length over the type's ``max_speed``;
a vehicle that turns in place also spends ``|Δheading| / turn_rate`` where the travel heading turns by more
than the layout's joint angle tolerance between two segments (it keeps its progress there, as the
reference planners' routes do). Acceleration and braking are left out: the measure ranks vehicles, it does
not predict arrival times.

One reverse Dijkstra from the stop's segment gives every state's time to go; it is kept per stop segment,
arrival progress and kind of vehicle (turn capability, speed, turn rate), all fixed for a run's layout,
so a dispatcher asking about many vehicles and many orders searches the map once per stop segment.
"""

from __future__ import annotations

import heapq
import math
from typing import NamedTuple

from fleetsim.enums import Progress, Traverse, TurnCapability
from fleetsim.layout.continuations import RULES
from fleetsim.layout.layout import Layout
from fleetsim.layout.reachability import State, state_key
from fleetsim.orders import Stop
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.snapshot import VehicleState
from fleetsim.scenario import VehicleType

__all__ = ["Start", "TravelTimes"]


class _Kind(NamedTuple):
    """What a travel time depends on of a vehicle's type."""

    capability: TurnCapability
    speed: float  # m/s
    turn_rate: float  # rad/s


class _Search(NamedTuple):
    """One reverse search's results: per state, the time from entering it to entering the stop (``to_go``),
    and, filled as asked, from leaving it (``after``)."""

    to_go: dict[State, float]
    after: dict[State, float]


class Start(NamedTuple):
    """Where a vehicle is committed to drive, for travel times from it (:meth:`TravelTimes.start`)."""

    kind: _Kind
    legs: tuple[tuple[int, Progress, float], ...]  # per leg: segment, progress, seconds until it is entered
    leaving: float  # seconds until it leaves the last
    last: State  # the last leg's state (an in-place turner's with progress FORWARD)


class TravelTimes:
    """Travel times to stops for a run's vehicles, with the searches kept (see the module's description).

    Attributes:
        searches: How many reverse searches of the map were made (one per stop segment, arrival progress
            and kind of vehicle); a new layout starts afresh.
    """

    def __init__(self) -> None:
        self._layout: Layout | None = None
        self._searches: dict[tuple[int, Progress | None, _Kind], _Search] = {}
        self._ends: dict[tuple[int, Traverse], tuple[float, float]] = {}
        self._kinds: dict[VehicleType, _Kind] = {}
        self._tolerance = 0.0
        self.searches = 0

    def time(self, layout: Layout, vehicle: VehicleState, plan: FleetPlan, stop: Stop) -> float:
        """Seconds for ``vehicle`` (following ``plan``'s fixed legs first) to reach ``stop``'s segment;
        0 when it is on it (with the stop's progress, if it names one), ``math.inf`` when it cannot."""
        return self.time_from(layout, self.start(layout, vehicle, plan), stop)

    def start(self, layout: Layout, vehicle: VehicleState, plan: FleetPlan) -> Start:
        """Where ``vehicle`` is committed to drive (the rest of its leg, then ``plan``'s further fixed
        legs): worked out once, then asked about many stops with :meth:`time_from`."""
        self._use(layout)
        kind = self._kinds.get(vehicle.type)
        if kind is None:
            kind = _Kind(vehicle.type.turn_capability, vehicle.type.max_speed, math.radians(vehicle.type.turn_rate))
            self._kinds[vehicle.type] = kind
        fixed = plan.fixed_legs or (FleetLeg(vehicle.segment, vehicle.traverse, vehicle.progress, fixed=True),)
        elapsed = 0.0
        before: FleetLeg | None = None
        legs: list[tuple[int, Progress, float]] = []
        for leg in fixed:
            length = layout.segments[leg.segment].length
            if before is None:
                length = max(length - vehicle.distance, 0.0)
            else:
                elapsed += self._turn(kind, before.segment, before.traverse, leg.segment, leg.traverse)
            legs.append((leg.segment, leg.progress, elapsed))
            elapsed += length / kind.speed
            before = leg
        assert before is not None
        progress = Progress.FORWARD if kind.capability is TurnCapability.IN_PLACE else before.progress
        return Start(kind, tuple(legs), elapsed, (before.segment, before.traverse, progress))

    def time_from(self, layout: Layout, start: Start, stop: Stop) -> float:
        """Seconds from ``start`` to reaching ``stop``'s segment (``math.inf``: it cannot)."""
        for segment, progress, at in start.legs:
            if segment == stop.segment and stop.progress in (None, progress):
                return at
        self._use(layout)
        return start.leaving + self._after(layout, start.kind, stop, start.last)

    def _use(self, layout: Layout) -> None:
        if layout is not self._layout:
            self._layout = layout
            self._searches.clear()
            self._ends.clear()
            self._tolerance = math.radians(layout.joint_angle_tolerance)

    def _heading_ends(self, segment: int, traverse: Traverse) -> tuple[float, float]:
        """The travel heading where a segment driven ``traverse`` starts and where it ends."""
        key = (segment, traverse)
        found = self._ends.get(key)
        if found is None:
            assert self._layout is not None
            seg = self._layout.segments[segment]
            found = self._ends[key] = (seg.pose_at(0.0, traverse)[2], seg.pose_at(seg.length, traverse)[2])
        return found

    def _turn(self, kind: _Kind, segment: int, traverse: Traverse, following: int, next_traverse: Traverse) -> float:
        """Seconds turning in place between the two (0 for a curve-only vehicle, or within the tolerance)."""
        if kind.capability is not TurnCapability.IN_PLACE:
            return 0.0
        turn = abs(
            math.remainder(
                self._heading_ends(following, next_traverse)[0] - self._heading_ends(segment, traverse)[1], math.tau
            )
        )
        return turn / kind.turn_rate if turn > self._tolerance else 0.0

    def _search(self, layout: Layout, kind: _Kind, stop: Stop) -> _Search:
        # An in-place turner chooses its progress on every leg: its states are kept with FORWARD alone.
        free = kind.capability is TurnCapability.IN_PLACE
        arrive = None if free else stop.progress
        key = (stop.segment, arrive, kind)
        found = self._searches.get(key)
        if found is not None:
            return found
        self.searches += 1
        progresses = (Progress.FORWARD,) if free else tuple(Progress)
        rule = RULES[kind.capability]
        segments = layout.segments
        to_go: dict[State, float] = {}
        heap: list[tuple[float, tuple[int, int, int], State]] = []
        goal = segments[stop.segment]
        for traverse in Traverse:
            if goal.allows(traverse):
                for progress in progresses:
                    if arrive in (None, progress):
                        state = (stop.segment, traverse, progress)
                        to_go[state] = 0.0
                        heap.append((0.0, state_key(state), state))
        heapq.heapify(heap)
        while heap:
            cost, _, state = heapq.heappop(heap)
            if cost > to_go[state]:
                continue
            segment, traverse, progress = state
            for previous, previous_traverse, joint in layout.predecessors(segment, traverse):
                step = segments[previous].length / kind.speed + self._turn(
                    kind, previous, previous_traverse, segment, traverse
                )
                for previous_progress in progresses:
                    if not free and progress not in rule[joint][previous_progress]:
                        continue
                    before = (previous, previous_traverse, previous_progress)
                    total = cost + step
                    if total < to_go.get(before, math.inf):
                        to_go[before] = total
                        heapq.heappush(heap, (total, state_key(before), before))
        found = self._searches[key] = _Search(to_go, {})
        return found

    def _after(self, layout: Layout, kind: _Kind, stop: Stop, state: State) -> float:
        """Seconds from leaving ``state`` (at its end; an in-place turner's with progress FORWARD) to
        entering the stop's segment."""
        search = self._search(layout, kind, stop)
        free = kind.capability is TurnCapability.IN_PLACE
        found = search.after.get(state)
        if found is None:
            segment, traverse, progress = state
            rule = RULES[kind.capability]
            found = math.inf
            for following, next_traverse, joint in layout.successors(segment, traverse):
                options = (Progress.FORWARD,) if free else rule[joint][progress]
                for next_progress in options:
                    to_go = search.to_go.get((following, next_traverse, next_progress))
                    if to_go is not None:
                        turn = self._turn(kind, segment, traverse, following, next_traverse)
                        found = min(found, turn + to_go)
            search.after[state] = found
        return found
