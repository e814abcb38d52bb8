"""A planner's optional hint that asking about a vehicle again would change nothing (the protocol's
:class:`~fleetsim.planning.protocol.QuietPlanner`), and the resting vehicles the controller skips until
something their planner depends on changes.

Most planner calls answer "nothing to change" (a vehicle cruising along legs it has fixed far enough
ahead), yet every busy vehicle is asked on every planning round. A planner may say, right after such an
answer, that the same call would keep answering an empty list, with no effect on the planner either,
until something named happens: it gives its ``quiet(vehicle_id, fleet)`` method, which the controller
asks after each call for a vehicle that answered an empty list, and which returns a :class:`Quiet` or
``None`` (no promise). The vehicle then *rests*: it is not asked again until one of these happens:

- its own plan or task queue changes (any accepted plan for it, a leg driven past, a task completed,
  assigned or taken back);
- another vehicle's fixed legs change on a segment that conflicts with one of ``Quiet.watch`` (a leg
  fixed or driven past there), or such a vehicle's task queue changes;
- one of ``Quiet.vehicles`` changes: its plan or task queue changes, or it comes to rest or starts to
  move (its speed crosses 1e-9 m/s), wherever it is;
- another vehicle's route (any of its legs, fixed or not) comes onto or leaves a segment that conflicts
  with one of ``Quiet.routes``;
- the planning time reaches ``Quiet.until``;
- with ``Quiet.until_standing``, a planning round finds the vehicle at rest (below 1e-9 m/s);
- any plan of any call is rejected (the planner may have counted it already);
- the planner names one of ``Quiet.marks`` among the marks of its own state that changed (its
  ``changed_marks()`` method, asked after every call: a part of its own state that the answer read,
  or that the call would write again, such as where another vehicle was sent to wait);
- the planner names one of ``Quiet.writes`` among those that changed and has no ``write_again``
  method. ``writes`` are marks the call wrote without reading them: asked again, it would write them
  again as it did, and do nothing else. With ``write_again(vehicle_id)``, the vehicle rests on: at its
  turn in the round (when it would have been asked), that method is called instead, and must write them
  again as the call did;
- the planner's ``quiet_epoch`` attribute changes (read after every call: the planner's own state
  changed in a way it cannot express by segments or marks, so every resting vehicle is asked again).

The promise must be exact: a run is the same, call for call and hash for hash, with the hint honoured
or ignored (``FleetController(..., quiet=False)``); the tests compare both. A planner without ``quiet``
is asked as before.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable, Hashable, Iterable, Mapping
from dataclasses import dataclass
from typing import TypeVar

from fleetsim.planning.plans import FleetPlan
from fleetsim.planning.reservations import fixed_segments
from fleetsim.planning.snapshot import VehicleState

__all__ = ["STANDING", "Quiet", "Resting"]

_Key = TypeVar("_Key")


@dataclass(frozen=True, slots=True)
class Quiet:
    """A planner's promise about one vehicle: asked again, it would answer an empty list and change
    nothing of its own, until the vehicle's plan or queue changes, or one of these happens.

    Attributes:
        watch: Segments: another vehicle's fixed legs changing on a segment that conflicts with one of
            these (or such a vehicle's task queue changing) ends the rest.
        until: The planning time from which the vehicle is asked again (``inf``: no time).
        until_standing: The vehicle is asked again at the first planning round that finds it at rest
            (its speed below 1e-9 m/s: a vehicle that braked to a stop may keep a few 1e-15 m/s).
        vehicles: Other vehicles: any change of their plans or task queues ends the rest, and so does one
            of them coming to rest or starting to move (its speed crossing 1e-9 m/s) — for a vehicle that
            read whether they stand or may be moved, wherever they are.
        routes: Segments: another vehicle's route (any leg, fixed or not) coming onto or leaving a segment
            that conflicts with one of these ends the rest (for a vehicle that read how many routes come
            near them).
        marks: Marks of the planner's own state (anything hashable, named by the planner): the planner
            naming one of these among those that changed (``changed_marks()``, asked after every call)
            ends the rest. Finer than ``quiet_epoch``, which ends every rest.
        writes: Marks the call wrote and did not read: asked again, it would write them again as it did
            and do nothing else. When the planner names one among those that changed, the vehicle rests on
            and the planner's ``write_again(vehicle_id)`` is called at its turn in the round instead of
            the call (a planner without ``write_again``: the rest ends, as for ``marks``).
    """

    watch: frozenset[int] = frozenset()
    until: float = math.inf
    until_standing: bool = False
    vehicles: frozenset[int] = frozenset()
    routes: frozenset[int] = frozenset()
    marks: frozenset[Hashable] = frozenset()
    writes: frozenset[Hashable] = frozenset()


# m/s: below this speed a vehicle is at rest (one that braked to a stop may keep a few 1e-15 m/s); a
# planner whose hint rests until_standing judges standing by the same figure.
STANDING = 1e-9


def _fixed_segments(plan: FleetPlan | None) -> frozenset[int]:
    return frozenset(fixed_segments(plan)) if plan is not None else frozenset()


def _route_changes(before: FleetPlan | None, after: FleetPlan) -> set[int]:
    """The segments a vehicle's route (all its legs) came onto or left."""
    if before is None:
        return {leg.segment for leg in after.legs}
    old, new = before.legs, after.legs
    if len(new) == len(old) - 1 and all(a is b for a, b in zip(old[1:], new, strict=True)):
        left = old[0].segment  # the first leg driven past: the commonest change
        return set() if any(leg.segment == left for leg in new) else {left}
    if len(new) == len(old) and all(a is b or a.segment == b.segment for a, b in zip(old, new, strict=True)):
        return set()  # the same segments in the same order: legs fixed, the next commonest change
    return {leg.segment for leg in old} ^ {leg.segment for leg in new}


def _enlist(table: dict[_Key, set[int]], keys: Iterable[_Key], vehicle: int) -> None:
    """``vehicle`` watches each of ``keys`` in ``table`` (key -> the resting vehicles watching it)."""
    for key in keys:
        watchers = table.get(key)
        if watchers is None:
            table[key] = {vehicle}
        else:
            watchers.add(vehicle)


def _discharge(table: dict[_Key, set[int]], keys: Iterable[_Key], vehicle: int) -> None:
    """``vehicle`` no longer watches ``keys`` (:func:`_enlist`)."""
    for key in keys:
        watchers = table[key]
        watchers.discard(vehicle)
        if not watchers:
            del table[key]


class Resting:
    """The resting vehicles of one run and what wakes each (the controller keeps it up to date)."""

    def __init__(self, conflicts: Callable[[int], frozenset[int]]) -> None:
        self._conflicts = conflicts
        self.resting: dict[int, frozenset[int]] = {}  # vehicle -> its watched segments
        self._watchers: dict[int, set[int]] = {}  # watched segment -> the resting vehicles watching it
        self._due: list[tuple[float, int]] = []  # (until, vehicle), a heap; stale entries skipped
        self._until: dict[int, float] = {}
        self._epoch: object = None  # the planner's quiet_epoch when last read
        self._until_standing: set[int] = set()  # resting vehicles asked again once at rest
        # (watched vehicle, whether it stood when their rest began) -> the resting vehicles watching it
        self._followers: dict[tuple[int, bool], set[int]] = {}
        # resting vehicle -> the vehicles it watches, each with whether it stood when the rest began
        self._stood: dict[int, tuple[tuple[int, bool], ...]] = {}
        self._routes: dict[int, frozenset[int]] = {}  # resting vehicle -> the segments whose routes near it watches
        self._route_watchers: dict[int, set[int]] = {}  # such a segment -> the resting vehicles watching it
        self._marks: dict[int, frozenset[Hashable]] = {}  # resting vehicle -> the planner's marks it watches
        self._mark_watchers: dict[Hashable, set[int]] = {}  # such a mark -> the resting vehicles watching it
        self._writes: dict[int, frozenset[Hashable]] = {}  # resting vehicle -> the marks its call writes
        self._writers: dict[Hashable, set[int]] = {}  # such a mark -> the resting vehicles that write it
        # Resting vehicles whose writes changed since: at their turn, the planner writes them again.
        self.to_write: set[int] = set()

    def epoch(self, epoch: object) -> None:
        """The planner's ``quiet_epoch`` now: when it changed, every resting vehicle wakes."""
        if epoch != self._epoch:
            self._epoch = epoch
            self.wake_all()

    def rest(self, vehicle: int, quiet: Quiet, states: Mapping[int, VehicleState] | None = None) -> None:
        """``vehicle`` rests on ``quiet``; ``states``: the states its planner saw (needed when the hint
        watches vehicles, to tell when one comes to rest or starts to move)."""
        self.wake(vehicle)
        if quiet.vehicles:
            assert states is not None, "a hint that watches vehicles needs the states it was given on"
            stood = self._stood[vehicle] = tuple(
                (other, states[other].speed < STANDING) for other in sorted(quiet.vehicles)
            )
            _enlist(self._followers, stood, vehicle)
        self.resting[vehicle] = quiet.watch
        _enlist(self._watchers, quiet.watch, vehicle)
        if quiet.routes:
            self._routes[vehicle] = quiet.routes
            _enlist(self._route_watchers, quiet.routes, vehicle)
        if quiet.marks:
            self._marks[vehicle] = quiet.marks
            _enlist(self._mark_watchers, quiet.marks, vehicle)
        if quiet.writes:
            self._writes[vehicle] = quiet.writes
            _enlist(self._writers, quiet.writes, vehicle)
        if quiet.until != math.inf:
            self._until[vehicle] = quiet.until
            heapq.heappush(self._due, (quiet.until, vehicle))
        if quiet.until_standing:
            self._until_standing.add(vehicle)

    def wake(self, vehicle: int) -> None:
        watch = self.resting.pop(vehicle, None)
        if watch is None:
            return
        _discharge(self._watchers, watch, vehicle)
        self._until.pop(vehicle, None)
        self._until_standing.discard(vehicle)
        _discharge(self._route_watchers, self._routes.pop(vehicle, ()), vehicle)
        _discharge(self._followers, self._stood.pop(vehicle, ()), vehicle)
        _discharge(self._mark_watchers, self._marks.pop(vehicle, ()), vehicle)
        if self._writes:
            _discharge(self._writers, self._writes.pop(vehicle, ()), vehicle)
            self.to_write.discard(vehicle)

    def wake_all(self) -> None:
        self.resting.clear()
        self._watchers.clear()
        self._due.clear()
        self._until.clear()
        self._until_standing.clear()
        self._followers.clear()
        self._stood.clear()
        self._routes.clear()
        self._route_watchers.clear()
        self._marks.clear()
        self._mark_watchers.clear()
        self._writes.clear()
        self._writers.clear()
        self.to_write.clear()

    def planner_changed(self, planner: object, changed_marks: Callable[[], Iterable[Hashable]] | None) -> None:
        """What the planner says of its own state now: its ``quiet_epoch`` (:meth:`epoch`) and, when it
        names them (``changed_marks``: its method, if it has one), the marks of it that changed
        (:meth:`marks_changed`)."""
        self.epoch(getattr(planner, "quiet_epoch", None))
        if changed_marks is not None:
            self.marks_changed(changed_marks())

    def marks_changed(self, marks: Iterable[Hashable]) -> None:
        """The planner's marks ``marks`` changed: those watching one wake, and those that write one are due
        to write it again."""
        watchers, writers = self._mark_watchers, self._writers
        for mark in marks:
            woken = watchers.get(mark)
            if woken:
                for vehicle in sorted(woken):
                    self.wake(vehicle)
            writing = writers.get(mark)
            if writing:
                self.to_write |= writing

    def wake_standing(self, states: Mapping[int, VehicleState]) -> None:
        """Wake the vehicles resting until they stand that stand now, and those watching a vehicle that
        came to rest or started to move since their rest began (a planning round begins)."""
        if self._until_standing:
            for vehicle in sorted(self._until_standing):
                if states[vehicle].speed < STANDING:
                    self.wake(vehicle)
        if self._followers:
            # (Those that changed found first, then woken in order: few change in a round.)
            changed = [key for key in self._followers if (states[key[0]].speed < STANDING) is not key[1]]
            for key in sorted(changed):
                for vehicle in sorted(self._followers.get(key, ())):
                    self.wake(vehicle)

    def _followed(self, vehicle: int) -> None:
        """``vehicle`` changed: those watching it wake."""
        followers = self._followers
        woken = followers.get((vehicle, False), set()) | followers.get((vehicle, True), set())
        for other in sorted(woken):
            self.wake(other)

    def wake_due(self, time: float) -> None:
        """Wake the vehicles whose ``until`` has come (a planning round at ``time`` begins)."""
        due = self._due
        while due and due[0][0] <= time:
            until, vehicle = heapq.heappop(due)
            if self._until.get(vehicle) == until:
                self.wake(vehicle)

    def plan_changed(self, before: FleetPlan | None, after: FleetPlan) -> None:
        """A vehicle's plan changed: it wakes, and so do those watching near the fixed legs it gained or lost."""
        vehicle = after.vehicle_id
        self.wake(vehicle)
        if self._followers:
            self._followed(vehicle)
        if self._watchers:
            self._near(vehicle, _fixed_segments(before) ^ _fixed_segments(after))
        if self._route_watchers:
            self._near(vehicle, _route_changes(before, after), self._route_watchers)

    def queue_changed(self, vehicles: Iterable[int], plans: Mapping[int, FleetPlan]) -> None:
        """These vehicles' task queues changed: they wake, and so do those watching near their fixed legs."""
        for vehicle in vehicles:
            self.wake(vehicle)
            if self._followers:
                self._followed(vehicle)
            if self._watchers:
                self._near(vehicle, _fixed_segments(plans.get(vehicle)))

    def _near(self, vehicle: int, segments: Iterable[int], watching: dict[int, set[int]] | None = None) -> None:
        """Wake those watching (``watching``: the routes near; else the fixed legs near) a segment that
        conflicts with one of ``segments``, where ``vehicle``'s changed."""
        watchers, conflicts = self._watchers if watching is None else watching, self._conflicts
        for segment in segments:
            for near in conflicts(segment):
                woken = watchers.get(near)
                if woken:
                    for other in sorted(woken):
                        if other != vehicle:
                            self.wake(other)
