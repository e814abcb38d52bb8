"""What every vehicle's plan holds near each segment, kept up to date from the plans that changed.

A planner asks the same few questions on every call: does another vehicle hold a fixed leg that
conflicts with this segment (then fixing a leg there would raise a collision alert), who are they, whose
routes come near it (soon, or at all), and does anyone plan to drive it the other way. The answers are
counted per segment and per vehicle; plans are immutable, so an unchanged plan is the very same object
and only the vehicles whose plans changed are counted again.
"""

from __future__ import annotations

from collections.abc import Mapping

from fleetsim.enums import Traverse
from fleetsim.layout.layout import Layout
from fleetsim.planning.protocol import FleetPlan

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


class FleetIndex:
    """Per segment, the vehicles whose fixed legs, next ``ahead`` legs and whole routes come near it."""

    def __init__(self, layout: Layout, ahead: int) -> None:
        self._conflicts = {sid: tuple(sorted(layout.conflicts(sid))) for sid in layout.segments}
        self._ahead = ahead
        self._plans: object = None  # the mapping last refreshed from
        self._seen: dict[int, FleetPlan] = {}
        self.fixed_near: dict[int, Counts] = {}
        self.ahead_near: dict[int, Counts] = {}
        self.route_near: dict[int, Counts] = {}
        self.drives: dict[Drive, Counts] = {}

    def refresh(self, plans: Mapping[int, FleetPlan]) -> None:
        if plans is self._plans:
            return  # the same snapshot as last call: nothing can have changed
        self._plans = plans
        for vehicle_id, plan in plans.items():
            self.assume(vehicle_id, plan)

    def assume(self, vehicle: int, plan: FleetPlan) -> FleetPlan | None:
        """Count ``plan`` as the vehicle's from now on (a plan about to be returned, so that what else the
        same response decides sees it); the plan it replaces, for :meth:`restore`."""
        old = self._seen.get(vehicle)
        if old is not plan:
            if old is not None:
                self._count(vehicle, old, -1)
            self._count(vehicle, plan, 1)
            self._seen[vehicle] = plan
        return old

    def restore(self, vehicle: int, old: FleetPlan | None) -> None:
        """Undo :meth:`assume`."""
        current = self._seen.get(vehicle)
        if current is not None and current is not old:
            self._count(vehicle, current, -1)
            del self._seen[vehicle]
        if old is not None and current is not old:
            self._count(vehicle, old, 1)
            self._seen[vehicle] = old

    def _count(self, vehicle: int, plan: FleetPlan, amount: int) -> None:
        fixed = len(plan.fixed_legs)
        tables: tuple[dict[object, Counts], ...] = (self.fixed_near, self.ahead_near, self.route_near)  # type: ignore[assignment]
        for index, leg in enumerate(plan.legs):
            _add(self.drives, (leg.segment, leg.traverse), vehicle, amount)  # type: ignore[arg-type]
            for near in self._conflicts[leg.segment]:
                if index < fixed:
                    _add(tables[0], near, vehicle, amount)
                if index < self._ahead:
                    _add(tables[1], near, vehicle, amount)
                _add(tables[2], near, vehicle, amount)

    # -- questions -----------------------------------------------------------------------------------

    def others_fixed_near(self, vehicle: int, segment: int) -> bool:
        """Another vehicle has a fixed leg that conflicts with ``segment``."""
        counts = self.fixed_near.get(segment)
        return counts is not None and (len(counts) > 1 or vehicle not in counts)

    def holders(self, vehicle: int, segment: int) -> list[int]:
        """The other vehicles whose fixed legs conflict with ``segment``, by id."""
        return sorted(other for other in self.fixed_near.get(segment, ()) if other != vehicle)

    def ahead(self, segment: int) -> Counts:
        """Vehicles whose next legs come near ``segment`` (read only)."""
        return self.ahead_near.get(segment, {})

    def routes_near(self, vehicle: int, segment: int) -> int:
        """How many other vehicles' routes come near ``segment``."""
        counts = self.route_near.get(segment, {})
        return len(counts) - (vehicle in counts)

    def others_drive(self, vehicle: int, segment: int, traverse: Traverse) -> bool:
        """Another vehicle's plan drives ``segment`` with ``traverse``."""
        counts = self.drives.get((segment, traverse))
        return counts is not None and (len(counts) > 1 or vehicle not in counts)
