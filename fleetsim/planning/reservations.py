"""Reservations and collision alerts (SPEC §7).

Each fixed leg of each plan makes a *primary* reservation of its segment; every segment that conflicts
with a primary segment gets a *secondary* reservation by the same vehicle. A segment with a primary
reservation of one vehicle must carry no reservation of any other vehicle; each offending segment gives
a collision alert listing its primary and secondary holders. Planned legs never reserve.

The check is vectorised over a segment-indexed conflict table (CSR arrays built once per layout), and a
:class:`ReservationIndex` keeps per-segment sums of the reservations in force, updated only for the
vehicles whose plan changed (plans are immutable, so an unchanged plan is the same object), so a step's
check stays cheap for 1000 vehicles on a 10,000-segment map.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fleetsim.layout.geometry import ragged_arange
from fleetsim.layout.layout import Layout
from fleetsim.planning.protocol import FleetPlan

__all__ = ["CollisionAlert", "ConflictTable", "ReservationIndex", "find_alerts", "fixed_segments"]

IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True, slots=True)
class CollisionAlert:
    """A possible collision: a segment reserved by one vehicle's fixed leg and also by another vehicle."""

    segment: int
    primary: tuple[int, ...]  # vehicles with a fixed leg on the segment
    secondary: tuple[int, ...]  # other vehicles whose fixed legs conflict with it

    @property
    def vehicles(self) -> tuple[int, ...]:
        return tuple(sorted({*self.primary, *self.secondary}))

    def text(self) -> str:
        """The thesis's alert text."""
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
    """Each segment's conflict set as CSR arrays over dense segment positions; built once per layout."""

    def __init__(self, layout: Layout) -> None:
        self.ids: IntArray = np.array(sorted(layout.segments), dtype=np.int64)
        self.position: dict[int, int] = {sid: k for k, sid in enumerate(self.ids.tolist())}
        rows = [sorted(self.position[other] for other in layout.conflicts(sid)) for sid in self.ids.tolist()]
        self.indptr: IntArray = np.cumsum([0, *map(len, rows)], dtype=np.int64)
        self.indices: IntArray = np.fromiter(
            (k for row in rows for k in row), dtype=np.int64, count=int(self.indptr[-1])
        )

    def __len__(self) -> int:
        return len(self.ids)


def fixed_segments(plan: FleetPlan) -> list[int]:
    """The segments of the plan's fixed prefix, in driving order."""
    segments = []
    for leg in plan.legs:
        if not leg.fixed:
            break
        segments.append(leg.segment)
    return segments


class ReservationIndex:
    """The reservations of the plans in force, kept up to date as plans change, and their alerts.

    Per segment it holds how many reservations it carries, the sum and the sum of squares of their
    holders' ranks (a small number per vehicle), and how many of them are primary. A segment is reserved
    by two or more vehicles iff its holders' ranks are not all equal: n·Σr² − (Σr)² > 0, exact in
    float64 for these integer sizes and found without sorting. A check folds in only the vehicles whose
    plan object changed since the last one (plans are immutable): the reservations they dropped count
    −1, the new ones +1, in one ``bincount`` per sum.
    """

    def __init__(self, table: ConflictTable) -> None:
        self.table = table
        n = len(table)
        self._count = np.zeros(n)
        self._total = np.zeros(n)
        self._squares = np.zeros(n)
        self._primaries = np.zeros(n)
        self._held: dict[int, tuple[FleetPlan, list[int]]] = {}  # vehicle -> (plan, primary positions)
        self._rank: dict[int, int] = {}  # vehicle -> rank, from 1 in order of first sight
        self._vehicle_of: list[int] = [-1]  # rank -> vehicle

    def _expand(self, primary: IntArray) -> tuple[IntArray, IntArray]:
        """Every primary reservation's conflict set (which includes the segment itself): for each
        reservation, its index in ``primary``, and the reserved segment position."""
        table = self.table
        counts = table.indptr[primary + 1] - table.indptr[primary]
        origin = np.repeat(np.arange(len(primary), dtype=np.int64), counts)
        return origin, table.indices[np.repeat(table.indptr[primary], counts) + ragged_arange(counts)]

    def _fold(self, plans: Mapping[int, FleetPlan]) -> None:
        """Bring the per-segment sums up to ``plans``: out with what changed plans held, in with the new."""
        held = self._held
        gone = [vehicle for vehicle in held if vehicle not in plans]
        changed = [vehicle for vehicle, plan in plans.items() if (entry := held.get(vehicle)) is None or entry[0] is not plan]
        if not gone and not changed:
            return
        primary: list[int] = []  # the primary reservations leaving and arriving,
        signs: list[float] = []  # -1 leaving, +1 arriving,
        ranks: list[float] = []  # and their holders' ranks
        position = self.table.position
        for vehicle in sorted(gone + changed):
            old = held.pop(vehicle, None)
            if old is not None:
                primary += old[1]
                signs += [-1.0] * len(old[1])
                ranks += [float(self._rank[vehicle])] * len(old[1])
            plan = plans.get(vehicle)
            if plan is not None:
                rank = self._rank.get(vehicle)
                if rank is None:
                    rank = self._rank[vehicle] = len(self._vehicle_of)
                    self._vehicle_of.append(vehicle)
                new = [position[segment] for segment in fixed_segments(plan)]
                held[vehicle] = (plan, new)
                primary += new
                signs += [1.0] * len(new)
                ranks += [float(rank)] * len(new)
        if not primary:
            return
        n = len(self.table)
        primaries = np.array(primary, dtype=np.int64)
        sign, rank_of = np.array(signs), np.array(ranks)
        origin, reserved = self._expand(primaries)
        sign_r, rank_r = sign[origin], rank_of[origin]
        self._count += np.bincount(reserved, weights=sign_r, minlength=n)
        self._total += np.bincount(reserved, weights=sign_r * rank_r, minlength=n)
        self._squares += np.bincount(reserved, weights=sign_r * rank_r * rank_r, minlength=n)
        self._primaries += np.bincount(primaries, weights=sign, minlength=n)

    def alerts(self, plans: Mapping[int, FleetPlan]) -> tuple[CollisionAlert, ...]:
        """Collision alerts for the plans in force, sorted by segment id."""
        self._fold(plans)
        shared = self._count * self._squares - self._total * self._total > 0.5
        alerting = np.flatnonzero((self._primaries > 0.5) & shared)
        if len(alerting) == 0:
            return ()
        vehicles = sorted(self._held)
        p_seg = np.array([k for vehicle in vehicles for k in self._held[vehicle][1]], dtype=np.int64)
        p_veh = np.repeat(
            np.array([self._rank[vehicle] for vehicle in vehicles], dtype=np.int64),
            [len(self._held[vehicle][1]) for vehicle in vehicles],
        )
        origin, s_seg = self._expand(p_seg)
        return _describe(alerting, p_seg, p_veh, s_seg, p_veh[origin], self._vehicle_of, self.table)


def find_alerts(plans: Mapping[int, FleetPlan], table: ConflictTable) -> tuple[CollisionAlert, ...]:
    """Collision alerts for ``plans`` from scratch (a run keeps a :class:`ReservationIndex` instead)."""
    return ReservationIndex(table).alerts(plans)


def _holders(segments: IntArray, vehicles: IntArray, wanted: IntArray) -> list[set[int]]:
    order = np.argsort(segments, kind="stable")
    segments, vehicles = segments[order], vehicles[order]
    lo = np.searchsorted(segments, wanted, side="left")
    hi = np.searchsorted(segments, wanted, side="right")
    return [set(vehicles[a:b].tolist()) for a, b in zip(lo.tolist(), hi.tolist())]


def _describe(
    alerting: IntArray,
    p_seg: IntArray,
    p_veh: IntArray,
    s_seg: IntArray,
    s_veh: IntArray,
    vehicle_of: list[int],
    table: ConflictTable,
) -> tuple[CollisionAlert, ...]:
    primaries = _holders(p_seg, p_veh, alerting)
    reservers = _holders(s_seg, s_veh, alerting)
    alerts = []
    for position, first, everyone in zip(alerting.tolist(), primaries, reservers):
        alerts.append(
            CollisionAlert(
                segment=int(table.ids[position]),
                primary=tuple(sorted(vehicle_of[k] for k in first)),
                secondary=tuple(sorted(vehicle_of[k] for k in everyone - first)),
            )
        )
    return tuple(alerts)
