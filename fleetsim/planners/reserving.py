"""The reference conflict-free planner: shortest routes, fixed to a safe place, with priorities and yielding.

Routing is A* by length over (segment, traverse, progress) states, honouring the goal direction, with
penalties for turning back at a cusp, for driving against another vehicle's plan (head-on) and for going
near vehicles that have no tasks left. Safety comes from fixing: a leg is fixed only when its segment's
conflict set holds no other vehicle's fixed leg, so the reservation check never alerts.

Progress comes from priorities. A vehicle with a task ranks by how long it has worked on its current
task (the longest first; ties by id, so at the start the order is the vehicles' ids); a vehicle with no
tasks left ranks last. The rules, in the order a blocked vehicle tries them:

- *Hold only what you need.* A vehicle fixes its way up to the first place past its braking distance
  and ``fix_ahead`` metres where it may stop, not as far as the way is free.
- *Stop only where you do not block.* Legs fixed in one go end at the goal or on a leg that no
  higher-ranked vehicle's next legs come near, and never next to the exit of a vehicle that stands
  further along the route (it would be shut in). A lower-ranked vehicle's plans are no reason to stop.
- *Make way.* A vehicle that stands blocked by lower-ranked vehicles standing still moves them away:
  the planner returns plans for them too, whose fixed legs take them to the nearest place off its route
  (moving the vehicles in their way first, two deep), and then on to their goals. Idle vehicles near a
  route are moved before anyone arrives. When the blockers cannot move (a dead end behind them), the
  vehicle steps aside itself and waits off their way until they have moved (moving those with no
  tasks left off its way once it is out of theirs).
- *Move on.* A vehicle whose way is free but that has nowhere to stop moves on anyway after 5 s.
- *Look for a way round* after 3 s, then at doubling intervals (up to 16 s), off every segment others
  hold; taken only when at most 1.1 times (+2 m) the way it replaces (the search stops there).
- *Dance.* When a few vehicles stay stuck in each other's way, a joint search finds single-leg moves
  that bring one of them to its goal, and they drive them in order (:mod:`fleetsim.planners.choreography`).

The highest-ranked vehicle therefore always moves, makes others move, or finds a way round; when it
reaches its goal it drops in rank and the next one is highest. Searches are deterministic (ties broken
by state, never by hashing).
"""

from __future__ import annotations

import math
from collections.abc import Hashable
from collections.abc import Set as AbstractSet
from dataclasses import replace
from typing import ClassVar

from mypy_extensions import mypyc_attr

from fleetsim.enums import JointKind, Traverse, TurnCapability
from fleetsim.layout.layout import Layout
from fleetsim.layout.reachability import State, next_states
from fleetsim.planners.choreography import Dance, choreograph
from fleetsim.planners.fleet_index import FleetIndex
from fleetsim.planners.making_way import Reads, WayOut, WaysOutMemo
from fleetsim.planners.routing import (
    RouteFound,
    RouteRead,
    RoutesMemo,
    StepTable,
    legs_along,
    mark_goal_on_fixed,
    shortest_route,
    straight_line_estimate,
)
from fleetsim.planning.plans import FleetLeg, FleetPlan, Response, RouteError
from fleetsim.planning.quiet import STANDING, Quiet
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Task

__all__ = ["ReservingPlanner"]

Rank = tuple[float, int]
_OPPOSITE = {Traverse.FORWARD: Traverse.BACKWARD, Traverse.BACKWARD: Traverse.FORWARD}
# Seconds: a vehicle resting until a moment is asked again this much before it (the planner compares
# times with a tolerance of 1e-9 s; asking early changes nothing, asking late would).
_EARLY = 1e-6


# Users subclass the reference planners; the compiled build (fleetsim/compiled.py) must let them.
@mypyc_attr(allow_interpreted_subclasses=True)
class ReservingPlanner:
    """Shortest routes, fixed to a place where waiting blocks no higher-ranked vehicle; blockers make way."""

    # Tunables: class variables, so that a subclass may change them (in the compiled build too).

    # Metres added for a cusp: stopping to reverse or turn round takes time.
    turnaround_penalty: ClassVar[float] = 10.0
    # Metres added for driving a segment that another plan drives the other way.
    oncoming_penalty: ClassVar[float] = 50.0
    # Metres added near a vehicle with no tasks left.
    parked_penalty: ClassVar[float] = 1_000.0
    # How many of a vehicle's next legs others keep clear of when they stop.
    ahead_legs: ClassVar[int] = 6
    # Seconds a vehicle stands blocked before it moves a lower-ranked blocker away.
    push_after: ClassVar[float] = 1.0
    # Seconds a vehicle with a free way but nowhere to stop waits before it moves on anyway.
    stall_after: ClassVar[float] = 5.0
    # Seconds before a vehicle that was moved away is moved again.
    push_cooldown: ClassVar[float] = 5.0
    # Seconds a vehicle that stepped aside keeps off the way of those it stepped aside for.
    aside_for: ClassVar[float] = 30.0
    # Seconds a blocked, standing vehicle first waits before looking for another route.
    replan_interval: ClassVar[float] = 3.0
    # The longest wait between looks.
    max_replan_interval: ClassVar[float] = 16.0
    # States a search for a place to make way in looks at, at most.
    search_limit: ClassVar[int] = 4_000
    # Seconds a vehicle stands blocked before a few stuck vehicles are moved leg by leg.
    dance_after: ClassVar[float] = 6.0
    # Vehicles moved together at most.
    dance_group: ClassVar[int] = 4
    # Joint positions the search for their moves looks at, at most.
    dance_limit: ClassVar[int] = 20_000
    # Seconds before a vehicle whose dance could not be found looks for one again.
    dance_retry: ClassVar[float] = 30.0
    # States a search for a way round looks at, at most.
    detour_limit: ClassVar[int] = 4_000
    # A way round at most this much longer (x) is taken ...
    detour_stretch: ClassVar[float] = 1.1
    # ... and at most this much longer (+ m).
    detour_slack: ClassVar[float] = 2.0
    # Metres beyond its braking distance a vehicle fixes its way, at most.
    fix_ahead: ClassVar[float] = 4.0
    # Seconds without a move done before a dance is given up.
    dance_patience: ClassVar[float] = 20.0

    def __init__(self) -> None:
        self._index: FleetIndex | None = None
        self._layout: Layout | None = None
        self._lengths: dict[int, float] = {}
        self._tables: dict[TurnCapability, StepTable] = {}  # the layout's steps, per turn capability
        # Searches for ways out, and routes on from waiting places: made again only when what they read changed.
        self._ways_out = WaysOutMemo()
        self._routes = RoutesMemo()
        self._near_cache: dict[int, tuple[FleetPlan, frozenset[int]]] = {}  # vehicle -> (plan, its _near)
        self._since: dict[int, tuple[int, float]] = {}  # vehicle -> (head task, when it became the head)
        self._blocked: dict[int, float] = {}  # vehicle -> since when it stands unable to fix a leg
        self._pushed: dict[int, float] = {}  # vehicle -> when it was last moved out of the way
        self._next_look: dict[int, tuple[float, float]] = {}  # vehicle -> (next look, current wait)
        self._haven: dict[int, int] = {}  # vehicle -> the segment it was sent to wait on
        self._dance: Dance | None = None  # a few stuck vehicles being moved leg by leg, in order
        self._group: frozenset[int] = frozenset()  # the dance's vehicles (also those that keep still)
        self._dance_time = -1.0  # when the dance last took a step
        self._no_dance: dict[int, float] = {}  # vehicle -> when it may look for a dance again
        # vehicle -> (until when, where not to stop, (whom, on which segment), near its way) while it steps
        # aside for others
        self._aside: dict[int, tuple[float, frozenset[int], tuple[tuple[int, int], ...], frozenset[int]]] = {}
        # vehicle -> whom it last stepped aside for, where they stood: it does not step aside for them again
        # while they stand there (it came back and they had not moved: the dance is left to try)
        self._stepped_for: dict[int, tuple[tuple[int, int], ...]] = {}
        # The quiet hint (fleetsim.planning.quiet): the vehicle of the last call when that call found it
        # cruising along legs fixed far enough ahead with no vehicle without tasks near its next legs, and
        # the segments of those legs; the epoch changes when a dance starts (every vehicle is asked then).
        self._calm: tuple[int, Quiet] | None = None
        # What a blocked vehicle's attempts to move others out of its way read, while it makes them: when
        # they all fail, its hint names what to wait for (_calm_standing).
        self._reads: Reads | None = None
        self._calm_after_clearing = False
        # What the last call's failed attempts to move vehicles without tasks from ahead of it read (None:
        # there were none to move): a hint given after them waits for these too.
        self._clearing: Reads | None = None
        self._idle_of: tuple[object, frozenset[int]] = (None, frozenset())  # (fleet.tasks, its idle vehicles)
        self.quiet_epoch = 0
        # The marks of this planner's own state changed since changed_marks() was last asked (in order, each
        # once): ("haven", vehicle) when where a vehicle was sent to wait changed.
        self._changed_marks: dict[Hashable, None] = {}
        self._own_marks: dict[int, frozenset[Hashable]] = {}  # vehicle -> {("haven", vehicle)}, made once
        # vehicle -> where its last call that gave a hint sent others to wait (the hint's writes, which
        # write_again() notes again)
        self._sent_by: dict[int, dict[int, int | None]] = {}
        # The hint holds for this class's answers: a subclass that answers otherwise gets none (unless it
        # gives its own quiet()).
        cls = type(self)
        self._own_calls = cls.fix_legs is ReservingPlanner.fix_legs and cls.plan_routes is ReservingPlanner.plan_routes

    def _conflicts_of(self, segment: int) -> frozenset[int]:
        assert self._layout is not None
        return self._layout.conflicts(segment)

    def _refresh(self, fleet: FleetSnapshot, layout: Layout) -> FleetIndex:
        if self._index is None:
            self._layout = layout
            self._index = FleetIndex(layout, self.ahead_legs)
            self._lengths = {sid: segment.length for sid, segment in layout.segments.items()}
        self._index.refresh(fleet)
        return self._index

    # -- the protocol --------------------------------------------------------------------------------

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self._calm = None
        index = self._refresh(fleet, layout)
        vehicle_id = task.vehicle_id
        danced = self._dance_step(fleet, index)
        if vehicle_id in self._group:
            return danced  # it keeps to the dance's moves until the dance is over
        fixed = fleet.plans[vehicle_id].fixed_legs
        marked = mark_goal_on_fixed(fixed, task, check_progress=True)
        if marked is not None:
            return [*danced, FleetPlan(vehicle_id, marked)]
        route = self._route(task, fixed[-1], fleet, layout)
        if route is None:
            last = fixed[-1]
            arrive = f" arriving {task.goal_progress.value}" if task.goal_progress is not None else ""
            msg = f"no route from segment {last.segment} ({last.traverse.value}) to segment {task.goal_segment}{arrive}"
            return [*danced, RouteError(vehicle_id, msg)]
        return [*danced, FleetPlan(vehicle_id, (*fixed, *route))]

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self._calm = None
        index = self._refresh(fleet, layout)
        vehicle_id = task.vehicle_id
        danced = self._dance_step(fleet, index)
        if vehicle_id in self._group:
            return danced
        plan = fleet.plans[vehicle_id]
        if self._haven.get(vehicle_id) == plan.legs[0].segment:
            self._send_to_wait(vehicle_id, None)  # it has arrived where it was sent to wait
        fixed_count = len(plan.fixed_legs)
        cleared = self._clear_idle_ahead(vehicle_id, plan, fleet, layout, index)
        response: list[FleetPlan] = [*danced, *cleared]
        committed = fixed_count == len(plan.legs)  # everything up to the goal
        if committed or self._fixed_ahead(plan) >= self._horizon(vehicle_id, fleet):
            # Committed, or enough to drive on at speed: until its plan or what stands near its next legs
            # changes, asking again changes nothing.
            if not response and self._calm_after_clearing:
                self._hint(vehicle_id, self._next_segments(plan), fleet)
            if not committed:
                # (_fix would fix nothing; moving, it is not standing, so _unblock would only forget its looks.)
                (self._blocked if cleared else self._next_look).pop(vehicle_id, None)
            return response
        following = plan.legs[fixed_count].segment
        if (
            not response
            and self._calm_after_clearing
            and index.others_fixed_near(vehicle_id, following)
            and not self._standing(vehicle_id, fleet)
        ):
            # Still moving towards the end of its fixed legs, the next one held by another: _fix would fix
            # nothing (its rank noted, as there) and _unblock only forget its looks. Until it stands, its
            # plan changes or what stands near its next legs does, asking again changes nothing.
            self._rank(vehicle_id, fleet)
            self._next_look.pop(vehicle_id, None)
            self._hint(vehicle_id, self._next_segments(plan) | {following}, fleet, until_standing=True)
            return response
        extended = self._fix(plan, fleet, index)
        if extended is not plan:
            self._blocked.pop(vehicle_id, None)
            return [*response, extended]
        if cleared:
            # Its way is being cleared: it waits for that rather than stepping aside or turning to another
            # route (where the vehicles just moved may stand, so that it would move them back, and so on).
            self._blocked.pop(vehicle_id, None)
            return response
        return response + self._unblock(task, plan, fleet, layout, index)

    def quiet(self, vehicle_id: int, fleet: FleetSnapshot) -> Quiet | None:
        """The quiet hint (fleetsim.planning.quiet), given when no dance goes on and no vehicle without tasks
        stands near this one's next legs (or none that could be moved), for a vehicle cruising along legs
        fixed far enough ahead, for one still moving whose next leg another holds (until it stands), and
        for one standing blocked (until it may push, dance or look round; behind lower-ranked vehicles that
        could not be moved, until what those attempts read changes): asked again, it would answer the
        same empty list, and touch nothing of this planner's, until its plan changes or other vehicles'
        fixed legs or queues near its next legs do. A subclass that overrides ``fix_legs`` or
        ``plan_routes`` gets none (its answers may depend on more), unless it overrides this too."""
        calm = self._calm
        if calm is None or calm[0] != vehicle_id or self._dance is not None or vehicle_id in self._aside:
            return None
        return calm[1] if self._own_calls else None

    def _next_segments(self, plan: FleetPlan) -> frozenset[int]:
        return frozenset(leg.segment for leg in plan.legs[1 : self.ahead_legs])

    # -- ranks ---------------------------------------------------------------------------------------

    def _rank(self, vehicle_id: int, fleet: FleetSnapshot) -> Rank:
        """Lower is higher: (when its current task became its head task, id); no tasks: last."""
        queue = fleet.tasks.get(vehicle_id, ())
        if not queue:
            return (math.inf, vehicle_id)
        head = queue[0].id
        since = self._since.get(vehicle_id)
        if since is None or since[0] != head:
            since = self._since[vehicle_id] = (head, fleet.time)
        return (since[1], vehicle_id)

    def _standing(self, vehicle_id: int, fleet: FleetSnapshot) -> bool:
        """At rest at the end of what it may drive (only the leg it is on is fixed)."""
        # (A vehicle that braked to a stop may keep a speed of a few 1e-15 m/s from rounding.)
        return fleet.vehicles[vehicle_id].speed < STANDING and len(fleet.plans[vehicle_id].fixed_legs) == 1

    # -- fixing --------------------------------------------------------------------------------------

    def _fix(self, plan: FleetPlan, fleet: FleetSnapshot, index: FleetIndex, *, anywhere: bool = False) -> FleetPlan:
        """Fix the free planned legs up to the first place past the horizon where waiting blocks no
        higher-ranked vehicle's next legs, else the longest free run that ends at the goal or at such a
        place (``anywhere``: wherever the free run ends)."""
        vehicle_id = plan.vehicle_id
        legs = plan.legs
        first = len(plan.fixed_legs)
        lengths = self._lengths
        ahead = self._fixed_ahead(plan)
        horizon = self._horizon(vehicle_id, fleet)
        if ahead >= horizon:
            return plan  # it has enough fixed before it to drive on at speed
        end = first
        while end < len(legs) and not index.others_fixed_near(vehicle_id, legs[end].segment):
            end += 1
        take = end
        if not anywhere:
            mine = self._rank(vehicle_id, fleet)

            def may_stop(after: int) -> bool:
                exits = self._exits(vehicle_id, legs[after : after + self.ahead_legs], fleet, index)
                segment = legs[after - 1].segment
                return segment not in exits and self._may_wait(vehicle_id, mine, segment, fleet, index)

            for k in range(first, end):
                ahead += lengths[legs[k].segment]
                if ahead >= horizon and k + 1 < end and may_stop(k + 1):
                    take = k + 1
                    break
            else:
                if take < len(legs):
                    while take > first and not may_stop(take):
                        take -= 1
        if take == first:
            return plan
        committed = tuple(replace(leg, fixed=True) for leg in legs[first:take])
        return FleetPlan(vehicle_id, (*legs[:first], *committed, *legs[take:]))

    def _fixed_ahead(self, plan: FleetPlan) -> float:
        """Metres of fixed legs before the vehicle, past the leg it is on."""
        lengths = self._lengths
        return sum(lengths[leg.segment] for leg in plan.legs[1 : len(plan.fixed_legs)])

    def _horizon(self, vehicle_id: int, fleet: FleetSnapshot) -> float:
        """How far ahead a vehicle fixes its way: its braking distance from full speed and a margin."""
        kind = fleet.vehicles[vehicle_id].type
        return kind.max_speed**2 / (2.0 * kind.acceleration) + self.fix_ahead

    def _exits(
        self, vehicle_id: int, beyond: tuple[FleetLeg, ...], fleet: FleetSnapshot, index: FleetIndex
    ) -> set[int]:
        """Segments near the next legs of vehicles that stand (or will stand) in the way further along:
        stopping there would shut them in, and they have to move before this vehicle can pass."""
        exits: set[int] = set()
        seen: set[int] = set()
        for leg in beyond:
            for other in index.holders(vehicle_id, leg.segment):
                if other in seen:
                    continue
                seen.add(other)
                their = fleet.plans[other]
                if len(their.legs) > 1 and len(their.fixed_legs) == 1:  # it stands, or soon will, at its leg's end
                    exits |= self._conflicts_of(their.legs[1].segment)
        return exits

    def _may_wait(self, vehicle_id: int, mine: Rank, segment: int, fleet: FleetSnapshot, index: FleetIndex) -> bool:
        """No higher-ranked vehicle's next legs come near ``segment`` (one stepping aside does not count),
        or it is the place this vehicle was sent to wait."""
        if self._haven.get(vehicle_id) == segment:
            return True
        if segment in self._keep_clear(vehicle_id, fleet):
            return False  # it stepped aside for others: it waits off their way until they have moved
        return not any(
            other != vehicle_id and self._rank(other, fleet) < mine and not self._keep_clear(other, fleet)
            for other in index.ahead(segment)
        )

    def _keep_clear(self, vehicle_id: int, fleet: FleetSnapshot) -> frozenset[int]:
        """Where a vehicle that stepped aside must not stop: until those it made way for have moved."""
        aside = self._aside.get(vehicle_id)
        if aside is None:
            return frozenset()
        until, region, where, _ = aside
        if fleet.time >= until or all(fleet.vehicles[other].segment != segment for other, segment in where):
            del self._aside[vehicle_id]
            return frozenset()
        return region

    # -- when nothing can be fixed -------------------------------------------------------------------

    def _unblock(
        self, task: Task, plan: FleetPlan, fleet: FleetSnapshot, layout: Layout, index: FleetIndex
    ) -> list[FleetPlan]:
        """Move lower-ranked standing blockers away, step aside for them, or look for another route."""
        vehicle_id = task.vehicle_id
        if not self._standing(vehicle_id, fleet):
            self._next_look.pop(vehicle_id, None)
            return []
        since = self._blocked.setdefault(vehicle_id, fleet.time)
        following = plan.legs[len(plan.fixed_legs)]
        if fleet.time - since >= self.stall_after - 1e-9 and not index.holders(vehicle_id, following.segment):
            # Its way is free, but every place to stop is in someone's way, and they wait too (for it,
            # say): better to move on into their way, where they can move it, than to wait for ever.
            moved_on = self._fix(plan, fleet, index, anywhere=True)
            if moved_on is not plan:
                self._blocked.pop(vehicle_id, None)
                return [moved_on]
        pushing = fleet.time - since >= self.push_after - 1e-9
        lower: list[int] = []
        reads: Reads | None = None
        if pushing:
            mine = self._rank(vehicle_id, fleet)
            holders = index.holders(vehicle_id, following.segment)
            lower = [other for other in holders if self._rank(other, fleet) > mine]
            if lower and self._calm_after_clearing:  # (else no hint is given: nothing to gather)
                reads = self._reads = Reads({vehicle_id, *holders})
            try:
                pushed = self._push(vehicle_id, plan, lower, mine, fleet, layout, index)
            finally:
                self._reads = None
            if pushed:
                return pushed
        if (
            fleet.time - since >= self.dance_after - 1e-9
            and self._dance is None
            and fleet.time >= self._no_dance.get(vehicle_id, -math.inf)
        ):
            dance = self._start_dance(task, plan, fleet, layout, index)
            if dance:
                return dance
            self._no_dance[vehicle_id] = fleet.time + self.dance_retry
        if (
            vehicle_id not in self._haven
            and not self._keep_clear(vehicle_id, fleet)
            and self._should_look_around(vehicle_id, fleet)
        ):
            # (Not while it makes way for others: a way round would undo its move.)
            detour = self._route(task, plan.fixed_legs[-1], fleet, layout, within=self._worth(plan))
            if detour is not None and detour != plan.legs[len(plan.fixed_legs) :]:
                rerouted = FleetPlan(vehicle_id, (*plan.fixed_legs, *detour))
                return [self._fix(rerouted, fleet, index)]
        if self._calm_after_clearing and index.others_fixed_near(vehicle_id, following.segment):
            # (With lower-ranked blockers that could not be moved, until what those attempts read changes.)
            self._calm_standing(vehicle_id, plan, since, pushing, following.segment, fleet, reads)
        return []

    def _push(
        self,
        vehicle_id: int,
        plan: FleetPlan,
        lower: list[int],
        mine: Rank,
        fleet: FleetSnapshot,
        layout: Layout,
        index: FleetIndex,
    ) -> list[FleetPlan]:
        """Plans that move the lower-ranked blockers ``lower`` out of the way of standing, blocked
        ``vehicle_id``, or that take it out of theirs; none when neither can be done."""
        moved: list[FleetPlan] = []
        taken = {vehicle_id}
        for other in lower:
            plans = self._evacuate(other, self._near(plan, layout), mine, fleet, layout, index, taken, depth=2)
            if plans:
                moved += self._assumed(plans, index)
                taken |= {p.vehicle_id for p in plans}
        if moved:
            return self._committed(moved, fleet)
        standing = [other for other in lower if self._standing(other, fleet)]
        where = tuple((other, fleet.vehicles[other].segment) for other in standing)
        if standing and self._stepped_for.get(vehicle_id) != where:
            # They cannot get out of its way (a dead end behind them, say): it gets out of theirs,
            # off their routes and off the way they would take out of its way if it were not there.
            keep_clear = set().union(*(self._near(fleet.plans[other], layout) for other in standing))
            for other in standing:
                keep_clear |= self._way_out_past(other, vehicle_id, self._near(plan, layout), fleet, layout, index)
            plans = self._evacuate(vehicle_id, keep_clear, mine, fleet, layout, index, set(standing), depth=2)
            if plans:
                self._assumed(plans, index)
                self._stepped_for[vehicle_id] = where
                way = frozenset(self._near(plan, layout))
                self._aside[vehicle_id] = (fleet.time + self.aside_for, frozenset(keep_clear), where, way)
                return self._committed(plans, fleet)
        return []

    def _calm_standing(
        self,
        vehicle_id: int,
        plan: FleetPlan,
        since: float,
        pushing: bool,
        following: int,
        fleet: FleetSnapshot,
        reads: Reads | None = None,
    ) -> None:
        """The quiet hint for a vehicle that stands blocked right ahead, with none without tasks near its
        next legs, by vehicles that all rank above it (none to move away), or (``reads``) by lower-ranked ones
        that could not be moved, nor it out of their way: what those attempts read. Until one of the
        vehicles ahead or its own plan changes (or what the attempts read: the holders of the segments their
        searches reached, the vehicles they asked about, whether those are moved lately), what it does
        changes only with time, when it may move blockers (``push_after``), start a dance or look for a way
        round; it is asked again a little before the first of these."""
        moments = [] if pushing else [since + self.push_after]
        if self._dance is None:
            moments.append(max(since + self.dance_after, self._no_dance.get(vehicle_id, -math.inf)))
        if vehicle_id not in self._haven and vehicle_id in self._next_look:
            moments.append(self._next_look[vehicle_id][0])
        until = min(moments) - _EARLY if moments else math.inf  # (none: a dance goes on, no hint is given)
        self._hint(vehicle_id, self._next_segments(plan) | {following}, fleet, until=until, reads=reads)

    def _hint(
        self,
        vehicle_id: int,
        watch: frozenset[int],
        fleet: FleetSnapshot,
        *,
        until: float = math.inf,
        until_standing: bool = False,
        reads: Reads | None = None,
    ) -> None:
        """Give the quiet hint for this call (``quiet()`` hands it out): rest, watching ``watch``, until
        ``until`` or (``until_standing``) the vehicle stands; and until anything the call's failed attempts
        to move others read changes (``reads``, and those of moving vehicles without tasks from ahead of
        it): the holders of the segments their searches reached, the vehicles they asked about, the routes
        near the places that ordered the ways found, and the end of the cooldown of any of those vehicles
        moved lately (it may be moved again then)."""
        vehicles: set[int] = set()
        routes: set[int] = set()
        sent: dict[int, int | None] = {}
        for gathered in (self._clearing, reads):
            if gathered is not None:
                watch |= gathered.segments()
                vehicles |= gathered.vehicles()
                routes |= gathered.routes()
                sent.update(gathered.sent)  # (in the order noted first, as noted last)
        marks = self._own_marks.get(vehicle_id)  # where it was sent to wait: every call reads that
        if marks is None:
            marks = self._own_marks[vehicle_id] = frozenset({("haven", vehicle_id)})
        writes: frozenset[Hashable] = frozenset()
        if sent:
            # Where others were sent to wait: only this vehicle's own calls read that, so a call that noted
            # it would, made again, note it again and do nothing else (``Quiet.writes``, write_again()).
            sent.pop(vehicle_id, None)  # (its own is read: a mark)
            self._sent_by[vehicle_id] = sent
            writes = frozenset(("haven", other) for other in sent)
        else:
            self._sent_by.pop(vehicle_id, None)
        moments = [
            self._pushed[other] + self.push_cooldown - 1e-9 - _EARLY
            for other in sorted(vehicles)
            if self._recently_moved(other, fleet)
        ]
        until = min(until, *moments) if moments else until
        self._calm = (
            vehicle_id,
            Quiet(
                watch,
                until,
                until_standing,
                vehicles=frozenset(vehicles),
                routes=frozenset(routes),
                marks=marks,
                writes=writes,
            ),
        )

    @staticmethod
    def _assumed(plans: list[FleetPlan], index: FleetIndex) -> list[FleetPlan]:
        """Count ``plans`` in the index now, so that the rest of this response does not contradict them."""
        for plan in plans:
            index.assume(plan.vehicle_id, plan)
        return plans

    def _worth(self, plan: FleetPlan) -> float:
        """What a way round may cost at most: not much more than the way it replaces."""
        lengths = self._lengths
        now = sum(lengths[leg.segment] for leg in plan.legs[len(plan.fixed_legs) :])
        return self.detour_stretch * now + self.detour_slack

    def _committed(self, plans: list[FleetPlan], fleet: FleetSnapshot) -> list[FleetPlan]:
        for plan in plans:
            self._pushed[plan.vehicle_id] = fleet.time
            self._next_look.pop(plan.vehicle_id, None)
            self._blocked.pop(plan.vehicle_id, None)
        return plans

    def _near(self, plan: FleetPlan, layout: Layout) -> frozenset[int]:
        """The segments near a plan's legs (worked out once per plan: a long route's take a while)."""
        cached = self._near_cache.get(plan.vehicle_id)
        if cached is not None and cached[0] is plan:
            return cached[1]
        near = frozenset(near for leg in plan.legs for near in layout.conflicts(leg.segment))
        self._near_cache[plan.vehicle_id] = (plan, near)
        return near

    def _clear_idle_ahead(
        self, vehicle_id: int, plan: FleetPlan, fleet: FleetSnapshot, layout: Layout, index: FleetIndex
    ) -> list[FleetPlan]:
        """Vehicles with no tasks left standing near this vehicle's next legs are moved away early, and
        those it stepped aside for (they do not move by themselves once it is out of their way)."""
        moved: list[FleetPlan] = []
        taken: set[int] = {vehicle_id}
        idle = self._idle(fleet)
        next_legs = plan.legs[1 : self.ahead_legs]
        ahead: list[int] = []
        if idle:
            fixed_near = index.fixed_near
            for leg in next_legs:  # (a loop: asked on every call, and seldom true)
                holding = fixed_near.get(leg.segment)
                if holding and not idle.isdisjoint(holding):
                    ahead = [
                        other
                        for near in next_legs
                        for other in index.holders(vehicle_id, near.segment)
                        if other in idle
                    ]
                    break
        near = self._near(plan, layout) if ahead else frozenset()
        to_move: list[tuple[int, AbstractSet[int]]] = [(other, near) for other in ahead]
        aside = self._aside.get(vehicle_id)
        if aside is not None:
            to_move += [(other, set(aside[3])) for other, _ in aside[2] if other in idle]
        # Nobody to move, or nobody that could be moved (what those attempts read is gathered), and no standing
        # aside: nothing here changes until near vehicles do, or what the attempts read (the quiet hint).
        self._clearing = self._reads = Reads(set()) if to_move and aside is None else None
        try:
            for other, avoid in to_move:
                if other in taken:
                    continue
                plans = self._evacuate(other, avoid, (math.inf, -1), fleet, layout, index, taken, depth=0)
                if plans:
                    moved += self._assumed(plans, index)
                    taken |= {p.vehicle_id for p in plans}
        finally:
            self._reads = None
        self._calm_after_clearing = aside is None and not moved
        return self._committed(moved, fleet) if moved else moved

    def _idle(self, fleet: FleetSnapshot) -> frozenset[int]:
        """The vehicles with no tasks left (worked out once per task queues shown)."""
        tasks = fleet.tasks
        if self._idle_of[0] is not tasks:
            self._idle_of = (tasks, frozenset(vehicle for vehicle, queue in tasks.items() if not queue))
        return self._idle_of[1]

    def _evacuate(
        self,
        vehicle_id: int,
        avoid: AbstractSet[int],
        above: Rank,
        fleet: FleetSnapshot,
        layout: Layout,
        index: FleetIndex,
        taken: set[int],
        *,
        depth: int,
    ) -> list[FleetPlan] | None:
        """Plans that take standing ``vehicle_id`` out of ``avoid`` (and on to its goal), moving standing
        vehicles ranked below ``above`` out of its way first (up to ``depth`` deep); None if it cannot."""
        reads = self._reads
        if reads is not None:
            reads.others.add(vehicle_id)
        if (
            vehicle_id in taken
            or vehicle_id in self._group
            or not self._standing(vehicle_id, fleet)
            or self._recently_moved(vehicle_id, fleet)
        ):
            return None
        taken = {*taken, vehicle_id}

        def movable(other: int) -> bool:
            return (
                depth > 0
                and other not in taken
                and other not in self._group
                and self._standing(other, fleet)
                and self._rank(other, fleet) > above
                and not self._recently_moved(other, fleet)
            )

        current = fleet.plans[vehicle_id].legs[0]
        start: State = (current.segment, current.traverse, current.progress)
        capability = fleet.vehicles[vehicle_id].type.turn_capability
        lengths, turnaround, limit = self._lengths, self.turnaround_penalty, self.search_limit
        table = self._table(layout, capability)
        for way in self._ways_out.ways_out(
            vehicle_id, start, avoid, index, lengths, movable, turnaround=turnaround, limit=limit, table=table,
            reads=reads,
        ):  # fmt: skip
            others: list[FleetPlan] = []
            replaced: list[tuple[int, FleetPlan | None]] = []  # what the index counted before, to undo
            last: list[tuple[int, FleetPlan | None]] = []  # ... of the last vehicle moved, its drives alone
            # (No one to move out of it when it crosses no one.)
            region = self._ways_out.widened(avoid, start, way, layout) if way.crossing else avoid
            for place, other in enumerate(way.crossing, start=1):
                plans = self._evacuate(other, region, above, fleet, layout, index, taken, depth=depth - 1)
                if plans is None:
                    break
                others += plans
                if place < len(way.crossing):  # the next one's search reads them whole
                    replaced += [(p.vehicle_id, index.assume(p.vehicle_id, p)) for p in plans]
                else:  # the way on from the waiting place reads only the drives (_away_plan, _route)
                    last = [(p.vehicle_id, index.assume_drives(p.vehicle_id, p)) for p in plans]
                taken |= {p.vehicle_id for p in plans}
            else:
                plan = self._away_plan(vehicle_id, current, way, fleet, layout)
                self._undo(index, replaced, last)
                if plan is not None:
                    return [plan, *others]  # the caller counts the whole set at once
                continue
            self._undo(index, replaced, last)
        return None

    @staticmethod
    def _undo(
        index: FleetIndex, replaced: list[tuple[int, FleetPlan | None]], last: list[tuple[int, FleetPlan | None]]
    ) -> None:
        """Count again what the index counted before the plans of vehicles moved were assumed."""
        for other, old in reversed(last):
            index.restore_drives(other, old)
        for other, old in reversed(replaced):
            index.restore(other, old)

    def _way_out_past(
        self,
        vehicle_id: int,
        past: int,
        avoid: AbstractSet[int],
        fleet: FleetSnapshot,
        layout: Layout,
        index: FleetIndex,
    ) -> set[int]:
        """The segments near the way ``vehicle_id`` would take out of ``avoid`` if ``past`` were not there."""
        current = fleet.plans[vehicle_id].legs[0]
        start: State = (current.segment, current.traverse, current.progress)
        capability = fleet.vehicles[vehicle_id].type.turn_capability
        ways = self._ways_out.ways_out(
            vehicle_id, start, avoid, index, self._lengths, lambda other: other == past,
            turnaround=self.turnaround_penalty, limit=self.search_limit, wanted=1, table=self._table(layout, capability),
            reads=self._reads,
        )  # fmt: skip
        return {near for segment, _, _ in ways[0].path for near in layout.conflicts(segment)} if ways else set()

    def _away_plan(
        self, vehicle_id: int, current: FleetLeg, way: WayOut, fleet: FleetSnapshot, layout: Layout
    ) -> FleetPlan | None:
        """The drive to the waiting place (fixed, unless others must move first), then on to the goal."""
        free = not way.crossing
        away = tuple(FleetLeg(segment, traverse, progress, fixed=free) for segment, traverse, progress in way.path)
        onward: tuple[FleetLeg, ...] = ()
        queue = self._open_tasks(vehicle_id, current, fleet)
        if queue:
            route = self._route(queue[0], away[-1], fleet, layout, remember=True)
            if route is None:
                return None  # never strand a vehicle where its task cannot be reached
            onward = route
        if not free:
            self._send_to_wait(vehicle_id, way.path[-1][0])  # it may wait there, whoever's way it is in
        return FleetPlan(vehicle_id, (current, *away, *onward))

    def _send_to_wait(self, vehicle_id: int, segment: int | None) -> None:
        """Note where a vehicle is sent to wait (None: nowhere now). A blocked vehicle's attempt to move
        others may note it and still fail, and the same attempt, made again, notes it again: a vehicle resting
        on a hint after such an attempt would not. So the attempts' reads take what they noted (``sent``),
        which the hint names as its writes: when the place changes, the vehicle whose call noted it notes
        it again at its turn (write_again()), and the vehicle sent, whose every call reads it, is asked
        again (its hints watch the mark ("haven", vehicle)); a change that no attempt being recorded makes
        asks every resting vehicle again (``quiet_epoch``)."""
        reads = self._reads
        if reads is not None:
            reads.sent[vehicle_id] = segment
        self._note_haven(vehicle_id, segment, marked=reads is not None)

    def _note_haven(self, vehicle_id: int, segment: int | None, *, marked: bool) -> None:
        """Where a vehicle was sent to wait is now ``segment``; a change is told by its mark (``marked``)
        or by a new ``quiet_epoch``."""
        if self._haven.get(vehicle_id) != segment:
            if segment is None:
                del self._haven[vehicle_id]
            else:
                self._haven[vehicle_id] = segment
            if marked:
                self._changed_marks[("haven", vehicle_id)] = None
            else:
                self.quiet_epoch += 1

    def write_again(self, vehicle_id: int) -> None:
        """What the quiet hint's ``writes`` promise: where the vehicle's last call sent others to wait, noted
        again as that call noted it (the harness calls this at the vehicle's turn, while it rests, when one
        of those places changed since)."""
        for other, segment in self._sent_by.get(vehicle_id, {}).items():
            self._note_haven(other, segment, marked=True)

    def changed_marks(self) -> list[Hashable]:
        """The marks of this planner's own state that changed since last asked (the quiet hint's
        ``marks``), each once, in the order they first changed."""
        if not self._changed_marks:
            return []
        marks = list(self._changed_marks)
        self._changed_marks.clear()
        return marks

    @staticmethod
    def _open_tasks(vehicle_id: int, current: FleetLeg, fleet: FleetSnapshot) -> tuple[Task, ...]:
        """Its queue without a task whose goal it stands on already (done, though not yet counted)."""
        return tuple(task for task in fleet.tasks.get(vehicle_id, ()) if task.id != current.goal_for_task)

    def _recently_moved(self, vehicle_id: int, fleet: FleetSnapshot) -> bool:
        return fleet.time - self._pushed.get(vehicle_id, -math.inf) < self.push_cooldown - 1e-9

    # -- the last resort: a few vehicles moved leg by leg ----------------------------------------------

    def _start_dance(
        self, task: Task, plan: FleetPlan, fleet: FleetSnapshot, layout: Layout, index: FleetIndex
    ) -> list[FleetPlan]:
        """Search joint moves that bring this vehicle to its goal, moving the standing vehicles that
        block it (and theirs); the plans that start the dance, or nothing when no such moves are found."""
        vehicle_id = task.vehicle_id
        group = [vehicle_id]
        for member in group:  # those in its way, then those in the way of any move of theirs
            member_plan = fleet.plans[member]
            current = member_plan.legs[0]
            capability = fleet.vehicles[member].type.turn_capability
            reach = [leg.segment for leg in member_plan.legs[len(member_plan.fixed_legs) :][:1]]
            near = list(next_states(layout, capability, (current.segment, current.traverse, current.progress)))
            near += [after for state in near for after in next_states(layout, capability, state)]  # two moves on
            reach += [state[0] for state in near]
            for segment in reach:
                for other in index.holders(member, segment):
                    if other not in group and len(group) < self.dance_group:
                        group.append(other)
        if len(group) < 2 or not all(self._standing(member, fleet) for member in group):
            return []
        members = sorted(group)
        blocked = {
            near
            for other, other_plan in fleet.plans.items()
            if other not in group
            for leg in other_plan.fixed_legs
            for near in layout.conflicts(leg.segment)
        }
        starts = {
            member: (leg.segment, leg.traverse, leg.progress)
            for member in members
            for leg in fleet.plans[member].legs[:1]
        }
        capabilities = {member: fleet.vehicles[member].type.turn_capability for member in members}
        moves = choreograph(
            layout,
            members,
            starts,
            capabilities,
            blocked,
            (vehicle_id, task.goal_segment, task.goal_progress),
            self.dance_limit,
            self._table(layout, capabilities[vehicle_id]),
        )
        if not moves:
            return []
        plans: list[FleetPlan] = []
        for member in members:
            states = [state for who, state in moves if who == member]
            if not states:
                continue
            legs = [FleetLeg(segment, traverse, progress, fixed=False) for segment, traverse, progress in states]
            current = fleet.plans[member].legs[0]
            queue = self._open_tasks(member, current, fleet)
            if member == vehicle_id:
                legs[-1] = replace(legs[-1], goal_for_task=task.id, progress=task.goal_progress or legs[-1].progress)
                last = max(k for k, (who, _) in enumerate(moves) if who == member)
                moves[last] = (member, (legs[-1].segment, legs[-1].traverse, legs[-1].progress))
                plans.append(FleetPlan(member, (current, *legs)))
                continue
            onward: tuple[FleetLeg, ...] = ()
            if queue:
                route = self._route(queue[0], legs[-1], fleet, layout)
                if route is None:
                    return []
                onward = route
            plans.append(FleetPlan(member, (current, *legs, *onward)))
        self._dance = Dance(moves, fleet.time, progressed=fleet.time)
        self.quiet_epoch += 1  # every vehicle is asked while it goes on
        self._group = frozenset(members)
        self._dance_time = fleet.time
        return self._committed(self._assumed(plans, index), fleet)

    def _dance_step(self, fleet: FleetSnapshot, index: FleetIndex) -> list[FleetPlan]:
        """Once per moment: fix the next move of the dance when every move before it is done."""
        dance = self._dance
        if dance is None or self._dance_time == fleet.time:
            return []
        self._dance_time = fleet.time
        current = {
            member: (leg.segment, leg.traverse, leg.progress)
            for member in self._group
            for leg in fleet.plans[member].legs[:1]
        }
        dance.advance(current, fleet.time)
        if dance.finished or fleet.time - dance.progressed > self.dance_patience:
            self._end_dance()
            return []
        member, state = dance.moves[dance.done]
        plan = fleet.plans[member]
        first = len(plan.fixed_legs)
        if first >= len(plan.legs):
            return []  # still driving its previous move
        leg = plan.legs[first]
        if (leg.segment, leg.traverse, leg.progress) != state:
            self._end_dance()  # its plan is no longer the dance's
            return []
        if first > 1 or index.others_fixed_near(member, leg.segment):
            return []  # it has not reached its last move yet, or someone else is in the way
        fixed = FleetPlan(member, (*plan.legs[:first], replace(leg, fixed=True), *plan.legs[first + 1 :]))
        index.assume(member, fixed)
        return [fixed]

    def _end_dance(self) -> None:
        self._dance, self._group = None, frozenset()
        self.quiet_epoch += 1  # a vehicle that stands blocked may start one now: every vehicle is asked

    # -- routing -------------------------------------------------------------------------------------

    def _route(
        self,
        task: Task,
        last: FleetLeg,
        fleet: FleetSnapshot,
        layout: Layout,
        *,
        within: float | None = None,
        remember: bool = False,
    ) -> tuple[FleetLeg, ...] | None:
        """The cheapest route to the task's goal; ``within`` a cost, as a way round (off every segment
        near legs others have fixed), else by any segment. ``remember``: a question likely asked again (the
        route on from a place a vehicle is sent to wait at), kept in the routes memo; other routes (to a new
        task, say) are seldom asked twice, and recording what their searches read would cost more than it
        saves."""
        vehicle_id = task.vehicle_id
        index = self._refresh(fleet, layout)
        parked: set[int] = set()
        for other, queue in fleet.tasks.items():
            if other != vehicle_id and not queue:
                parked |= layout.conflicts(fleet.vehicles[other].segment)
        capability = fleet.vehicles[vehicle_id].type.turn_capability
        start = (last.segment, last.traverse, last.progress)
        avoid_held = within is not None
        # A route to the goal by any segment is remembered (RoutesMemo): the same question asked again while
        # what the search read is unchanged has the same answer.
        remember = remember and not avoid_held
        key = (vehicle_id, task.id, task.goal_segment, task.goal_progress, start, capability) if remember else ()
        if remember:
            remembered = self._routes.get(key, vehicle_id, index, parked)
            if remembered is not None:
                return remembered.legs
        lengths = self._lengths
        turnaround, oncoming, near_parked = self.turnaround_penalty, self.oncoming_penalty, self.parked_penalty
        # (FleetIndex.others_drive and others_fixed_near, read in place: a search asks them at every step.)
        drives, fixed_near = index.drives.get, index.fixed_near.get
        read: dict[tuple[int, Traverse], RouteRead] = {}

        def cost(segment: int, traverse: Traverse, joint: JointKind) -> float:
            total = lengths[segment]
            if joint is JointKind.OPPOSITE:
                total += turnaround
            other_way = _OPPOSITE[traverse]
            counts = drives((segment, other_way))
            head_on = counts is not None and (len(counts) > 1 or vehicle_id not in counts)
            if head_on:
                total += oncoming
            near = segment in parked
            if near:
                total += near_parked
            if avoid_held:
                counts = fixed_near(segment)
                if counts is not None and (len(counts) > 1 or vehicle_id not in counts):
                    return math.inf
            elif remember:
                read[segment, traverse] = (segment, traverse, other_way, head_on, near)
            return total

        table = self._table(layout, capability)
        estimate = straight_line_estimate(layout, task.goal_segment, table)
        limit = self.detour_limit if avoid_held else None
        path = shortest_route(
            layout, capability, start, task.goal_segment, task.goal_progress, cost, estimate, limit, within, table
        )
        legs = None if path is None else legs_along(path, task, task.goal_progress)
        if remember:
            looked = tuple(read.values())
            near_parked_read = frozenset(segment for segment, _, _, _, near in looked if near)
            others = frozenset(segment for segment, _, _, _, near in looked if not near)
            self._routes.keep(key, RouteFound(legs, index.tick, looked, near_parked_read, others))
        return legs

    def _table(self, layout: Layout, capability: TurnCapability) -> StepTable:
        """The layout's steps for ``capability``, shared by every search of this planner's."""
        table = self._tables.get(capability)
        if table is None:
            table = self._tables[capability] = StepTable(layout, capability)
        return table

    def _should_look_around(self, vehicle_id: int, fleet: FleetSnapshot) -> bool:
        """Only a vehicle standing at the end of what it may drive, and less often the longer it waits.

        The wait between looks doubles (up to ``max_replan_interval``) while looking finds nothing
        better: a vehicle queued behind others should not search the map every few seconds.
        """
        due, interval = self._next_look.get(vehicle_id, (fleet.time + self.replan_interval, self.replan_interval))
        if vehicle_id not in self._next_look:
            self._next_look[vehicle_id] = (due, interval)
        if fleet.time < due - 1e-9:
            return False
        interval = min(2.0 * interval, self.max_replan_interval)
        self._next_look[vehicle_id] = (fleet.time + interval, interval)
        return True
