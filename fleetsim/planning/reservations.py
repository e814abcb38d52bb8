"""Reservations and collision alerts (SPEC §7).

Each fixed leg of each plan makes a *primary* reservation of its segment; every segment that conflicts
with a primary segment gets a *secondary* reservation by the same vehicle. A segment with a primary
reservation of one vehicle must carry no reservation of any other vehicle; each offending segment gives
a collision alert listing its primary and secondary holders. Planned legs never reserve.

A run keeps one :class:`ReservationIndex`: per segment, who holds reservations on it and how many, kept
up to date by folding in only what changed. Plans are immutable, so an unchanged plan is the same
object; a changed one mostly differs from the last by a leg driven past or a leg newly fixed, and only
those reservations move. Which segments alert is re-judged only where holders changed, so a step's
check costs in proportion to what changed, not to the fleet or the map (1000 vehicles on a
10,000-segment map stay cheap).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass

from fleetsim.layout.layout import Layout
from fleetsim.planning.plans import FleetPlan

__all__ = ["CollisionAlert", "ConflictTable", "ReservationIndex", "find_alerts", "fixed_segments"]


@dataclass(frozen=True, slots=True)
class CollisionAlert:
    """A possible collision: a segment reserved by one vehicle's fixed leg and also by another vehicle.

    Alerts reject no plan, but a scenario fails on them unless it expects them (``expect.collisions``).

    Attributes:
        segment: The segment's id.
        primary: Ids of the vehicles with a fixed leg on the segment, ascending.
        secondary: Ids of the other vehicles with a fixed leg on a segment that conflicts with it
            ([`Layout.conflicts`][fleetsim.layout.layout.Layout.conflicts]), ascending.
    """

    segment: int
    primary: tuple[int, ...]
    secondary: tuple[int, ...]

    @property
    def vehicles(self) -> tuple[int, ...]:
        """Every vehicle involved, primary and secondary, by ascending id."""
        return tuple(sorted({*self.primary, *self.secondary}))

    def text(self) -> str:
        """The thesis's alert text: ``COLLISION ALERT: Possible collision detected on segment '11'``,
        then the primary and the secondary holders, one ``- vehicle_N`` line each."""
        lines = [
            f"COLLISION ALERT: Possible collision detected on segment '{self.segment}'",
            "Primary reservations",
            *(f" - vehicle_{vehicle}" for vehicle in self.primary),
            "Secondary reservations",
            *(f" - vehicle_{vehicle}" for vehicle in self.secondary),
        ]
        return "\n".join(lines)

    def __str__(self) -> str:
        secondary = ", ".join(map(str, self.secondary)) or "-"
        return (
            f"possible collision on segment {self.segment}: primary "
            f"{', '.join(map(str, self.primary))}; secondary {secondary}"
        )


class ConflictTable:
    """Each segment's conflict set (which includes the segment itself), built once per layout."""

    def __init__(self, layout: Layout) -> None:
        self.rows: dict[int, tuple[int, ...]] = {
            segment: tuple(sorted(layout.conflicts(segment))) for segment in sorted(layout.segments)
        }


def fixed_segments(plan: FleetPlan) -> list[int]:
    """The segments of the plan's fixed prefix, in driving order."""
    return [leg.segment for leg in plan.fixed_legs]


def _difference(old: list[int], new: list[int]) -> tuple[list[int], list[int]]:
    """The primary reservations a vehicle gives up and takes on going from ``old`` to ``new`` (multisets).

    The common changes first: legs driven past leave the front, newly fixed legs join the back.
    """
    kept = len(new)
    if kept <= len(old) and old[len(old) - kept :] == new:
        return old[: len(old) - kept], []
    if len(old) <= kept and new[: len(old)] == old:
        return [], new[len(old) :]
    before, after = Counter(old), Counter(new)
    return sorted((before - after).elements()), sorted((after - before).elements())


class ReservationIndex:
    """The reservations of the plans in force, kept up to date as plans change, and their alerts.

    ``_holders[s]`` counts each vehicle's reservations (primary or secondary) on segment ``s`` and
    ``_primaries[s]`` its primary ones; a segment alerts when it has a primary holder and two or more
    holders. Only segments whose holders changed are judged again, and an alert whose holders stay the
    same stays the same object (so that what is new is told by identity).
    """

    def __init__(self, table: ConflictTable) -> None:
        self.table = table
        self._held: dict[int, tuple[FleetPlan, list[int]]] = {}  # vehicle -> (plan, primary segments)
        self._holders: dict[int, dict[int, int]] = {}  # segment -> {vehicle: reservations}
        self._primaries: dict[int, dict[int, int]] = {}  # segment -> {vehicle: primary reservations}
        # The alert of each alerting segment: kept, the very same object, while its holders stay the same.
        self._alerts: dict[int, CollisionAlert] = {}
        self._sorted: tuple[CollisionAlert, ...] | None = ()  # the alerts by segment (None: to be sorted again)

    def _reserve(self, vehicle: int, segments: Iterable[int], delta: int, touched: set[int]) -> None:
        """Add (``delta`` = 1) or remove (-1) the vehicle's primary reservations of ``segments`` and the
        secondary reservations that come with them."""
        rows = self.table.rows
        for segment in segments:
            _count(self._primaries, (segment,), vehicle, delta)
            _count(self._holders, rows[segment], vehicle, delta)
            touched.update(rows[segment])

    def _fold(self, plans: Mapping[int, FleetPlan], candidates: Collection[int] | None) -> None:
        """Bring the reservations up to ``plans``: out with what changed plans gave up, in with the new.
        ``candidates``: the only vehicles whose plans may have changed since the last fold, when the caller
        knows them (else every plan is compared)."""
        held = self._held
        if candidates is None:
            gone = [vehicle for vehicle in held if vehicle not in plans]
            candidates = plans.keys()
        else:
            gone = sorted(vehicle for vehicle in candidates if vehicle not in plans and vehicle in held)
            candidates = sorted(vehicle for vehicle in candidates if vehicle in plans)
        changed = [
            vehicle for vehicle in candidates if (entry := held.get(vehicle)) is None or entry[0] is not plans[vehicle]
        ]
        if not gone and not changed:
            return
        touched: set[int] = set()
        for vehicle in gone:
            self._reserve(vehicle, held.pop(vehicle)[1], -1, touched)
        for vehicle in changed:
            entry = held.get(vehicle)
            new = fixed_segments(plans[vehicle])
            left, joined = _difference(entry[1] if entry is not None else [], new)
            self._reserve(vehicle, left, -1, touched)
            self._reserve(vehicle, joined, 1, touched)
            held[vehicle] = (plans[vehicle], new)
        holders, primaries, alerts = self._holders, self._primaries, self._alerts
        for segment in touched:
            old = alerts.get(segment)
            if segment in primaries and len(holders.get(segment, ())) > 1:
                primary = tuple(sorted(primaries[segment]))
                secondary = tuple(sorted(holders[segment].keys() - set(primary)))
                if old is None or old.primary != primary or old.secondary != secondary:
                    alerts[segment] = CollisionAlert(segment, primary, secondary)
                    self._sorted = None
            elif old is not None:
                del alerts[segment]
                self._sorted = None

    def alerts(
        self, plans: Mapping[int, FleetPlan], changed: Collection[int] | None = None
    ) -> tuple[CollisionAlert, ...]:
        """Collision alerts for the plans in force, sorted by segment id. ``changed``: the vehicles whose
        plans may have changed since the last call, when the caller keeps count (a run's controller does);
        without it every plan is compared with the last seen."""
        self._fold(plans, changed)
        if self._sorted is None:
            alerts = self._alerts
            self._sorted = tuple(alerts[segment] for segment in sorted(alerts))
        return self._sorted


def _count(counts: dict[int, dict[int, int]], segments: Iterable[int], vehicle: int, delta: int) -> None:
    """Change a vehicle's count on each of ``segments`` by ``delta``; counts that reach zero go, and so do
    segments left with none."""
    for segment in segments:
        on = counts.get(segment)
        if on is None:
            on = counts[segment] = {}
        total = on.get(vehicle, 0) + delta
        if total:
            on[vehicle] = total
            continue
        del on[vehicle]
        if not on:
            del counts[segment]


def find_alerts(plans: Mapping[int, FleetPlan], table: ConflictTable) -> tuple[CollisionAlert, ...]:
    """Collision alerts for ``plans`` from scratch (a run keeps a :class:`ReservationIndex` instead)."""
    return ReservationIndex(table).alerts(plans)
