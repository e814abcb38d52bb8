"""What every vehicle's plan holds near each segment, kept up to date from the plans that changed.

A planner asks the same few questions on every call: does another vehicle hold a fixed leg that
conflicts with this segment (then fixing a leg there would raise a collision alert), who are they, whose
routes come near it (soon, or at all), and does anyone plan to drive it the other way. The answers are
counted per segment and per vehicle; plans are immutable, so an unchanged plan is the very same object
and only the vehicles whose plans changed are counted again.

Fixed legs and the next legs are counted on every segment they come near (their conflicts), where the
questions about them are asked many times. Whole routes are long and change often (a vehicle sent away
to wait gets a new route on, tried and taken back while others make way), and whose routes come near a
place is asked only of the few places a search finds: a route is counted once, as the drives
(segment, traverse) of its legs, and the routes near a segment are gathered from the drives of the
segments it is near when asked.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from itertools import compress, islice
from operator import is_not

from fleetsim.enums import Traverse
from fleetsim.layout.layout import Layout
from fleetsim.planning.plans import FleetLeg, FleetPlan
from fleetsim.planning.reservations import fixed_segments
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.planning.views import replaced

__all__ = ["FleetIndex"]

Counts = dict[int, int]  # vehicle -> how many of its legs
Drive = tuple[int, Traverse]


def _add(table: dict[object, Counts], key: object, vehicle: int, amount: int) -> None:
    counts = table.get(key)
    if counts is None:
        counts = table[key] = {}
    total = counts.get(vehicle, 0) + amount
    if total:
        counts[vehicle] = total
    else:
        del counts[vehicle]
        if not counts:
            del table[key]


def _parts(plan: FleetPlan, ahead: int) -> tuple[Sequence[object], ...]:
    """What a plan counts: its fixed legs' and its next ``ahead`` legs' segments, and its drives (segment,
    traverse)."""
    return (*_short_parts(plan, ahead), _drives(plan))


def _short_parts(plan: FleetPlan, ahead: int) -> tuple[list[int], list[int]]:
    """Its fixed legs' and its next ``ahead`` legs' segments."""
    return fixed_segments(plan), [leg.segment for leg in plan.legs[:ahead]]


def _drives(plan: FleetPlan | None) -> list[Drive]:
    """Its legs' drives (segment, traverse); none without a plan."""
    return [] if plan is None else [(leg.segment, leg.traverse) for leg in plan.legs]


def _delta(before: Sequence[object], after: Sequence[object]) -> Iterable[tuple[object, int]]:
    """How many more of each key ``after`` has than ``before``, keys in the order of ``after`` then
    ``before`` (first occurrences)."""
    delta = Counter(after)
    delta.subtract(before)
    return delta.items()


def _others(old: Sequence[FleetLeg], new: Sequence[FleetLeg]) -> Iterator[tuple[FleetLeg, FleetLeg]]:
    """The pairs of legs at the same places of two routes of one length that are other objects."""
    return compress(zip(old, new, strict=True), map(is_not, old, new))


class FleetIndex:
    """Per segment, the vehicles whose fixed legs, next ``ahead`` legs and whole routes come near it."""

    def __init__(self, layout: Layout, ahead: int) -> None:
        self._conflicts = {sid: tuple(sorted(layout.conflicts(sid))) for sid in layout.segments}
        # Per segment, the segments whose conflicts hold it: where a leg comes near it from.
        near_from: dict[int, list[int]] = {sid: [] for sid in layout.segments}
        for sid, conflicts in self._conflicts.items():
            for segment in conflicts:
                near_from[segment].append(sid)
        self._near_from = {segment: tuple(sources) for segment, sources in near_from.items()}
        self._ahead = ahead
        self._plans: object = None  # the mapping last refreshed from, when the snapshot has no plans version
        self._version: int | None = None  # else the plans version last refreshed from
        self._touched: set[int] = set()  # vehicles assumed or restored since the last refresh
        self._order: dict[int, int] = {}  # vehicle -> its place in the plans mapping (the order counted in)
        self._seen: dict[int, FleetPlan] = {}
        self._drives_only: dict[int, FleetPlan] = {}  # vehicle -> the plan assume_drives counts the drives of
        self.fixed_near: dict[int, Counts] = {}
        self.ahead_near: dict[int, Counts] = {}
        self.drives: dict[Drive, Counts] = {}  # per (segment, traverse), the vehicles whose routes drive it
        # When each segment's fixed holders last changed, in changes counted (``tick``): what a search read
        # of them still holds while its segments' stamps are no later than when it read them.
        self.tick = 0
        self.stamps: dict[int, int] = {}
        self.drive_stamps: dict[int, int] = {}  # ... and when a plan driving it either way changed

    def refresh(self, fleet: FleetSnapshot) -> None:
        """Count the plans of a snapshot that changed since the last refresh: those the snapshot says changed
        since the version last refreshed from (:meth:`FleetSnapshot.plans_changed`) and those this index
        assumed meanwhile, else every plan that is another object than the one counted. An unchanged fleet
        is known by its ``plans_version`` without holding on to its plans (which would make every later
        snapshot copy them whole), or else by the mapping's identity."""
        plans, version = fleet.plans, fleet.plans_version
        if version is not None:
            if version == self._version:
                return  # the same plans as last call
            changed = fleet.plans_changed(self._version) if self._version is not None else None
            self._version, self._plans = version, None
        elif plans is self._plans:
            return  # the same snapshot as last call: nothing can have changed
        else:
            changed, self._version, self._plans = None, None, plans
        if changed is None or len(self._order) != len(plans):
            # Every plan that is another object (found in C: a large fleet's differ in a few plans).
            self._order = {vehicle: place for place, vehicle in enumerate(plans)}
            again = replaced(plans, self._seen)
        else:
            # The same vehicles as counting them all would find, in the same order: any other vehicle's plan
            # is the one counted at an earlier refresh, unchanged since.
            again = sorted(changed | self._touched, key=self._order.__getitem__)
        seen = self._seen
        for vehicle_id in again:
            plan = plans[vehicle_id]
            if plan is not seen.get(vehicle_id):
                self.assume(vehicle_id, plan)
        self._touched.clear()

    def assume(self, vehicle: int, plan: FleetPlan) -> FleetPlan | None:
        """Count ``plan`` as the vehicle's from now on (a plan about to be returned, so that what else the
        same response decides sees it); the plan it replaces, for :meth:`restore`."""
        assert not self._drives_only, "restore_drives first"
        old = self._seen.get(vehicle)
        if old is not plan:
            self._touched.add(vehicle)
            if old is None:
                self._count(vehicle, plan, 1)
            else:
                self._recount(vehicle, old, plan)
            self._seen[vehicle] = plan
        return old

    def restore(self, vehicle: int, old: FleetPlan | None) -> None:
        """Undo :meth:`assume`."""
        assert not self._drives_only, "restore_drives first"
        current = self._seen.get(vehicle)
        if current is old:
            return
        self._touched.add(vehicle)
        if current is None:
            assert old is not None
            self._count(vehicle, old, 1)
        elif old is None:
            self._count(vehicle, current, -1)
        else:
            self._recount(vehicle, current, old)
        if old is None:
            self._seen.pop(vehicle, None)
        else:
            self._seen[vehicle] = old

    def assume_drives(self, vehicle: int, plan: FleetPlan) -> FleetPlan | None:
        """Count only the drives of ``plan`` as the vehicle's, until :meth:`restore_drives` (which must
        come before any other change of this index): for a question that reads nothing else, such as a
        route search's costs. The plan counted, whose drives :meth:`restore_drives` counts again."""
        assert vehicle not in self._drives_only, f"vehicle {vehicle}'s drives are assumed already"
        old = self._seen.get(vehicle)
        if old is not plan:
            self._drives_only[vehicle] = plan
            self._add_all(self._tables()[2], vehicle, _delta(_drives(old), _drives(plan)))
        return old

    def restore_drives(self, vehicle: int, old: FleetPlan | None) -> None:
        """Undo :meth:`assume_drives`."""
        plan = self._drives_only.pop(vehicle, None)
        if plan is not None:
            self._add_all(self._tables()[2], vehicle, _delta(_drives(plan), _drives(old)))

    def _count(self, vehicle: int, plan: FleetPlan, amount: int) -> None:
        for table, keys in zip(self._tables(), _parts(plan, self._ahead), strict=True):
            self._add_all(table, vehicle, ((key, amount) for key in keys))

    def _recount(self, vehicle: int, old: FleetPlan, new: FleetPlan) -> None:
        """Count ``new`` instead of ``old``: only the legs that differ (a plan mostly changes by a leg
        fixed or a leg driven).

        The whole route's table (drives) needs no walk through a long route in the two
        commonest changes: legs fixed (the same drives, only legs' flags changed) and the first leg driven
        past (the same leg objects but the first). Either way the changes are those the general way
        finds, in the same order (the order of a vehicle's entries in the tables depends on it)."""
        ahead = self._ahead
        tables = self._tables()
        short = _short_parts(old, ahead), _short_parts(new, ahead)
        for table, before, after in zip(tables[:2], *short, strict=True):
            if before != after:
                self._add_all(table, vehicle, _delta(before, after))
        o, n = old.legs, new.legs
        if len(o) == len(n) and all(a.segment == b.segment and a.traverse == b.traverse for a, b in _others(o, n)):
            return  # the same route, driven the same way
        if len(n) == len(o) - 1 and not any(map(is_not, islice(o, 1, None), n)):
            first = o[0]
            self._add_all(tables[2], vehicle, (((first.segment, first.traverse), -1),))
            return
        was, now = _drives(old), _drives(new)
        if was != now:
            self._add_all(tables[2], vehicle, _delta(was, now))

    def _tables(self) -> tuple[dict[object, Counts], ...]:
        return (self.fixed_near, self.ahead_near, self.drives)  # type: ignore[return-value]

    def _add_all(self, table: dict[object, Counts], vehicle: int, changes: Iterable[tuple[object, int]]) -> None:
        """Add each ``(key, amount)``: to the segments near the key's segment (fixed and next legs), or to
        the key itself (drives)."""
        self.tick += 1
        tick = self.tick
        if table is self.fixed_near or table is self.ahead_near:
            conflicts = self._conflicts
            stamps = self.stamps if table is self.fixed_near else None
            for key, amount in changes:
                if amount:
                    for segment in conflicts[key]:  # type: ignore[index]
                        _add(table, segment, vehicle, amount)
                        if stamps is not None:
                            stamps[segment] = tick
            return
        stamps = self.drive_stamps
        for key, amount in changes:
            if amount:
                _add(table, key, vehicle, amount)
                stamps[key[0]] = tick  # type: ignore[index]

    # -- questions -----------------------------------------------------------------------------------

    def others_fixed_near(self, vehicle: int, segment: int) -> bool:
        """Another vehicle has a fixed leg that conflicts with ``segment``."""
        counts = self.fixed_near.get(segment)
        return counts is not None and (len(counts) > 1 or vehicle not in counts)

    def holders(self, vehicle: int, segment: int) -> list[int]:
        """The other vehicles whose fixed legs conflict with ``segment``, by id."""
        counts = self.fixed_near.get(segment)
        if not counts:
            return []
        if len(counts) == 1:
            return [] if vehicle in counts else list(counts)
        return sorted(other for other in counts if other != vehicle)

    def ahead(self, segment: int) -> Counts:
        """Vehicles whose next legs come near ``segment`` (read only)."""
        return self.ahead_near.get(segment, {})

    def routes_near(self, vehicle: int, segment: int) -> int:
        """How many other vehicles' routes come near ``segment``."""
        drives = self.drives
        found = [
            counts
            for near in self._near_from.get(segment, ())
            for drive in ((near, Traverse.FORWARD), (near, Traverse.BACKWARD))
            if (counts := drives.get(drive))
        ]
        if not found:
            return 0
        if len(found) == 1:
            return len(found[0]) - (vehicle in found[0])
        others = set().union(*found)
        others.discard(vehicle)
        return len(others)

    def route_stamp(self, segment: int) -> int:
        """When the routes near ``segment`` last changed (a ``tick``; 0: never)."""
        stamps = self.drive_stamps
        return max([stamps.get(near, 0) for near in self._near_from.get(segment, ())], default=0)

    def others_drive(self, vehicle: int, segment: int, traverse: Traverse) -> bool:
        """Another vehicle's plan drives ``segment`` with ``traverse``."""
        counts = self.drives.get((segment, traverse))
        return counts is not None and (len(counts) > 1 or vehicle not in counts)
