"""The physical judgement of a run: did two footprints touch, and how close did they come.

:class:`ContactMonitor` is told every vehicle's pose after every step (in arrays, by the loop's vehicle
order) and keeps:

- the *contacts*: each time two footprints begin to overlap, with the first moment, the place, and the
  deepest penetration while they overlap (an episode ends when they are apart again);
- the *clearance*: the closest any two footprints came over the run, with when, where and which pair;
- the *near misses*: for every pair that came closer than ``near_miss`` metres without touching, its
  closest approach.

Each step is judged in three phases. The broad phase hashes the vehicles' end positions into a grid of
cells as large as the farthest two footprints can be apart and still matter (two half diagonals, the
``reach`` of interest, and both vehicles' travel in the step), and takes as candidates the pairs in the
same or neighbouring cells, at least one of which moved: no pair of the fleet is looked at otherwise.
Their bounding circles sort out most of them (the distance between circles never exceeds the distance
between the rectangles they hold). The narrow phase takes the exact distance (:mod:`.geometry`) of the
pairs whose circles come close enough to matter.

The continuous phase catches what no sampled step shows: two fast vehicles that pass through each other
within one step. It is conservative advancement along the poses interpolated between the step's start
and end (centre along the straight line, heading along the shorter turn): from the start, advance by
the distance divided by the most the distance can change per unit of the interpolation
(:func:`.geometry.motion_bound`), and again, until the footprints touch (within :data:`TOUCH` metres) or
the step ends. Such an advance can never step over a touch. A pair needs it only when its circles'
distances at both ends add up to no more than that bound: otherwise it cannot have touched between.
The interpolation is a chord of the true path (an arc in a curve): at the 0.1 s step of fleetsim's
scenarios the two differ by millimetres.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import numpy.typing as npt

from fleetsim.contact.geometry import Boxes, interpolate, motion_bound, separation, signed_distance

__all__ = ["TOUCH", "Approach", "Contact", "ContactMonitor", "ContactReport"]

TOUCH = 1e-4  # metres: footprints closer than this touch
_ADVANCES = 32  # conservative advancement steps per pair and step before sampling the rest
_SAMPLES = 16  # samples of what is left of a step after that
_NEIGHBOURS = ((0, 0), (1, -1), (1, 0), (1, 1), (0, 1))  # half the 3 x 3 cells: each pair of cells once

Floats = npt.NDArray[np.float64]
Ints = npt.NDArray[np.intp]


@dataclass(frozen=True, slots=True)
class Contact:
    """Two footprints overlapped: from ``time`` (where they first touched, at ``x, y``) until ``until``
    (None: still at the run's end), at most ``depth`` metres deep."""

    time: float
    vehicles: tuple[int, int]
    x: float
    y: float
    depth: float
    until: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {
            "time": round(self.time, 6),
            "vehicles": list(self.vehicles),
            "x": round(self.x, 4),
            "y": round(self.y, 4),
            "depth": round(self.depth, 4),
            "until": None if self.until is None else round(self.until, 6),
        }


@dataclass(frozen=True, slots=True)
class Approach:
    """Two vehicles' closest approach: ``distance`` metres between their footprints at ``time``, at ``x, y``
    (the midpoint of the closest points)."""

    vehicles: tuple[int, int]
    distance: float
    time: float
    x: float
    y: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "vehicles": list(self.vehicles),
            "distance": round(self.distance, 4),
            "time": round(self.time, 6),
            "x": round(self.x, 4),
            "y": round(self.y, 4),
        }


@dataclass(frozen=True, slots=True)
class ContactReport:
    """What the monitor found over a run (see the module docstring). ``clearance`` is None when no two
    footprints came within ``reach`` metres: it is more than that."""

    contacts: tuple[Contact, ...]
    clearance: Approach | None
    near_misses: tuple[Approach, ...]  # closest first
    reach: float
    near_miss: float
    safety_margin: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "contacts": [c.to_dict() for c in self.contacts],
            "clearance": None if self.clearance is None else self.clearance.to_dict(),
            "near_misses": [n.to_dict() for n in self.near_misses],
            "reach": self.reach,
            "near_miss": self.near_miss,
            "safety_margin": self.safety_margin,
        }


class ContactMonitor:
    """Contacts, clearance and near misses of one run (the module docstring says how).

    ``ids``: the vehicles in the loop's order; ``lengths``, ``widths``: their footprints (metres), each side
    grown by ``safety_margin``; ``reach``: how far apart two footprints may be for their distance to count
    towards the clearance (at least ``near_miss``).
    """

    def __init__(
        self,
        ids: Sequence[int],
        lengths: Sequence[float],
        widths: Sequence[float],
        *,
        safety_margin: float = 0.0,
        near_miss: float = 0.5,
        reach: float = 2.0,
    ) -> None:
        self.ids = list(ids)
        self.half_length = np.asarray(lengths, dtype=np.float64) / 2 + safety_margin
        self.half_width = np.asarray(widths, dtype=np.float64) / 2 + safety_margin
        self.radius = np.hypot(self.half_length, self.half_width)
        self.safety_margin, self.near_miss = safety_margin, near_miss
        self.reach = max(reach, near_miss)
        self.contacts: list[Contact] = []
        self._active: dict[tuple[int, int], int] = {}  # a pair of indices in contact -> its contact
        self._closest: dict[tuple[int, int], Approach] = {}  # pairs closer than near_miss
        self._clearance: Approach | None = None
        self._poses: Boxes | None = None

    # -- the run ----------------------------------------------------------------------------------------

    def begin(self, x: Floats, y: Floats, heading: Floats, time: float = 0.0) -> list[Contact]:
        """The poses at the start: footprints that overlap already are contacts from ``time``."""
        self._poses = self._boxes(x, y, heading)
        everyone = np.ones(len(self.ids), dtype=bool)
        i, j = self._candidates(self._poses, everyone, 0.0)
        return self._judge_static(i, j, self._poses, time)

    def step(
        self, t0: float, t1: float, x: Floats, y: Floats, heading: Floats, moved: npt.NDArray[np.bool_]
    ) -> list[Contact]:
        """The step from ``t0`` to ``t1`` ended with these poses; ``moved``: which vehicles' poses changed.
        Returns the contacts that began in it."""
        start = self._poses
        assert start is not None, "begin() first"
        end = self._boxes(x, y, heading)
        self._poses = end
        fresh: list[Contact] = []
        touching = set(self._active)  # at the step's start: not swept for a new contact
        if self._active:
            self._follow_active(end, t1)
        if not moved.any():
            return fresh
        travel = np.hypot(end.x - start.x, end.y - start.y)
        i, j = self._candidates(end, moved, float(travel.max(initial=0.0)))
        if len(i) == 0:
            return fresh
        a0, b0, a1, b1 = start.take(i), start.take(j), end.take(i), end.take(j)
        reach = self.radius[i] + self.radius[j]
        gap0 = np.hypot(b0.x - a0.x, b0.y - a0.y) - reach
        gap1 = np.hypot(b1.x - a1.x, b1.y - a1.y) - reach
        bound = motion_bound(a0, a1, b0, b1)
        active = self._in_contact(i, j, touching)
        # Between the steps: pairs that could have touched and were not touching already. The circles'
        # gaps sort out most; the separating-axis separations (also lower bounds of the distance, and much
        # closer for side-by-side rectangles) the rest of those that merely drive alongside each other.
        maybe = np.flatnonzero((gap0 + gap1 <= bound + TOUCH) & ~active)
        if len(maybe):
            bounds = separation(a0.take(maybe), b0.take(maybe)) + separation(a1.take(maybe), b1.take(maybe))
            maybe = maybe[bounds <= bound[maybe] + TOUCH]
        sweep = maybe
        if len(sweep):
            fresh += self._sweep(i[sweep], j[sweep], start, end, bound[sweep], t0, t1)
        # At the step's end: the pairs whose circles come close enough to count.
        limit = max(self.near_miss, self._clearance.distance if self._clearance is not None else self.reach)
        near = np.flatnonzero((gap1 < limit) & ~active)
        if len(near):
            distance, where = signed_distance(a1.take(near), b1.take(near))
            pi, qi = i[near], j[near]
            touch = distance <= TOUCH
            for k in np.flatnonzero(touch):  # a touch the sweep could not tell apart (it began at the end)
                p, q = int(pi[k]), int(qi[k])
                if (p, q) not in self._active:
                    fresh.append(
                        self._begin_contact(p, q, t1, float(where[k, 0]), float(where[k, 1]), -float(distance[k]))
                    )
            apart = ~touch
            self._record(pi[apart], qi[apart], distance[apart], np.full(int(apart.sum()), t1), where[apart])
        return fresh

    def report(self) -> ContactReport:
        """What was found; an overlap still in force at the end has ``until`` None."""
        touched = {c.vehicles for c in self.contacts}
        misses = sorted(
            (a for a in self._closest.values() if a.vehicles not in touched),
            key=lambda a: (a.distance, a.time, a.vehicles),
        )
        return ContactReport(
            tuple(self.contacts),
            self._clearance,
            tuple(misses),
            self.reach,
            self.near_miss,
            self.safety_margin,
        )

    # -- phases -------------------------------------------------------------------------------------------

    def _boxes(self, x: Floats, y: Floats, heading: Floats) -> Boxes:
        return Boxes(
            np.asarray(x, dtype=np.float64).copy(),
            np.asarray(y, dtype=np.float64).copy(),
            np.asarray(heading, dtype=np.float64).copy(),
            self.half_length,
            self.half_width,
        )

    def _candidates(self, poses: Boxes, moved: npt.NDArray[np.bool_], travel: float) -> tuple[Ints, Ints]:
        """Pairs (i < j) in the same or neighbouring cells of a grid as large as two footprints can be
        apart and still matter, at least one of them moved."""
        count = len(self.ids)
        if count < 2:
            return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
        size = 2.0 * float(self.radius.max()) + self.reach + 2.0 * travel + TOUCH
        cx = np.floor(poses.x / size).astype(np.int64)
        cy = np.floor(poses.y / size).astype(np.int64)
        cx -= cx.min()
        cy -= cy.min()
        span = int(cy.max()) + 3  # room for the neighbours' rows
        key = cx * span + (cy + 1)
        order = np.argsort(key, kind="stable")
        ordered = key[order]
        offsets = np.array([dx * span + dy for dx, dy in _NEIGHBOURS], dtype=np.int64)
        targets = (key[:, None] + offsets[None, :]).ravel()
        left = np.searchsorted(ordered, targets, side="left")
        right = np.searchsorted(ordered, targets, side="right")
        counts = right - left
        total = int(counts.sum())
        if total == 0:
            return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
        first = np.repeat(np.arange(count, dtype=np.intp), len(_NEIGHBOURS))
        starts = np.repeat(left - (np.cumsum(counts) - counts), counts)
        i = np.repeat(first, counts)
        j = order[np.arange(total) + starts]
        same_cell = np.repeat(np.tile(np.arange(len(_NEIGHBOURS)) == 0, count), counts)
        keep = np.where(same_cell, i < j, i != j) & (moved[i] | moved[j])
        i, j = i[keep], j[keep]
        low, high = np.minimum(i, j), np.maximum(i, j)
        return low, high

    def _judge_static(self, i: Ints, j: Ints, poses: Boxes, time: float) -> list[Contact]:
        fresh = []
        gap = np.hypot(poses.x[j] - poses.x[i], poses.y[j] - poses.y[i]) - self.radius[i] - self.radius[j]
        near = np.flatnonzero(gap < self.reach)
        distance, where = signed_distance(poses.take(i[near]), poses.take(j[near]))
        pi, qi = i[near], j[near]
        touch = distance <= TOUCH
        for k in np.flatnonzero(touch):
            p, q = int(pi[k]), int(qi[k])
            fresh.append(self._begin_contact(p, q, time, float(where[k, 0]), float(where[k, 1]), -float(distance[k])))
        apart = ~touch
        self._record(pi[apart], qi[apart], distance[apart], np.full(int(apart.sum()), time), where[apart])
        return fresh

    def _sweep(self, i: Ints, j: Ints, start: Boxes, end: Boxes, bound: Floats, t0: float, t1: float) -> list[Contact]:
        """Conservative advancement of the pairs ``(i, j)`` over the step: the contacts that begin in it."""
        a0, a1, b0, b1 = start.take(i), end.take(i), start.take(j), end.take(j)
        tau = np.zeros(len(i))
        touching = np.zeros(len(i), dtype=bool)
        going = np.ones(len(i), dtype=bool)
        place = np.zeros((len(i), 2))
        for _ in range(_ADVANCES):
            rows = np.flatnonzero(going)
            if len(rows) == 0:
                break
            t = tau[rows]
            distance, where = signed_distance(
                interpolate(a0.take(rows), a1.take(rows), t), interpolate(b0.take(rows), b1.take(rows), t)
            )
            on_the_way = (t > 0.0) & (distance > TOUCH)  # the closest they came between the steps counts too
            self._record(
                i[rows[on_the_way]], j[rows[on_the_way]], distance[on_the_way],
                t0 + t[on_the_way] * (t1 - t0), where[on_the_way],
            )  # fmt: skip
            touch = distance <= TOUCH
            touching[rows[touch]] = True
            place[rows[touch]] = where[touch]
            going[rows[touch]] = False
            advance = rows[~touch]
            step = distance[~touch] / np.maximum(bound[advance], 1e-12)
            tau[advance] = tau[advance] + step
            done = tau[advance] > 1.0
            going[advance[done]] = False
        # Pairs still advancing (a graze, where each advance is short): sample what is left of the step.
        for row in np.flatnonzero(going):
            samples = np.linspace(tau[row], 1.0, _SAMPLES)
            pa = interpolate(a0.take(np.full(_SAMPLES, row)), a1.take(np.full(_SAMPLES, row)), samples)
            pb = interpolate(b0.take(np.full(_SAMPLES, row)), b1.take(np.full(_SAMPLES, row)), samples)
            distance, where = signed_distance(pa, pb)
            hit = np.flatnonzero(distance <= TOUCH)
            if len(hit):
                touching[row], tau[row], place[row] = True, samples[hit[0]], where[hit[0]]
        fresh = []
        for row in np.flatnonzero(touching):
            p, q = int(i[row]), int(j[row])
            if (p, q) in self._active:
                continue
            begun = min(float(tau[row]), 1.0)
            # How deep they went within the step (at its end, the next step's follow-up takes over).
            samples = np.linspace(begun, 1.0, _SAMPLES)
            rows = np.full(_SAMPLES, row)
            inside, _ = signed_distance(
                interpolate(a0.take(rows), a1.take(rows), samples), interpolate(b0.take(rows), b1.take(rows), samples)
            )
            moment = t0 + begun * (t1 - t0)
            depth = max(0.0, -float(inside.min()))
            contact = self._begin_contact(p, q, moment, float(place[row, 0]), float(place[row, 1]), depth)
            if inside[-1] > TOUCH:  # apart again by the step's end: passed through each other
                self.contacts[self._active.pop((p, q))] = contact = replace(contact, until=t1)
            fresh.append(contact)
        return fresh

    def _follow_active(self, end: Boxes, t1: float) -> None:
        """Deepen or end the contacts in force."""
        pairs = sorted(self._active)
        i = np.array([p for p, _ in pairs], dtype=np.intp)
        j = np.array([q for _, q in pairs], dtype=np.intp)
        distance, _ = signed_distance(end.take(i), end.take(j))
        for (p, q), d in zip(pairs, distance.tolist(), strict=True):
            index = self._active[(p, q)]
            contact = self.contacts[index]
            if d > TOUCH:
                self.contacts[index] = replace(contact, until=t1)
                del self._active[(p, q)]
            elif -d > contact.depth:
                self.contacts[index] = replace(contact, depth=-d)

    # -- bookkeeping --------------------------------------------------------------------------------------

    def _begin_contact(self, p: int, q: int, time: float, x: float, y: float, depth: float) -> Contact:
        contact = Contact(time, (self.ids[p], self.ids[q]), x, y, max(depth, 0.0))
        self._active[(p, q)] = len(self.contacts)
        self.contacts.append(contact)
        self._approach(p, q, 0.0, time, x, y)
        return contact

    def _in_contact(self, i: Ints, j: Ints, pairs: set[tuple[int, int]]) -> npt.NDArray[np.bool_]:
        """Which of the pairs ``(i, j)`` are among ``pairs``."""
        if not pairs:
            return np.zeros(len(i), dtype=bool)
        count = len(self.ids)
        known = np.array([p * count + q for p, q in sorted(pairs)], dtype=np.int64)
        return np.isin(i.astype(np.int64) * count + j, known)

    def _record(self, i: Ints, j: Ints, distance: Floats, time: Floats, where: Floats) -> None:
        """Distances between footprints apart: the clearance, and each pair's closest approach below
        ``near_miss``."""
        if len(distance) == 0:
            return
        best = int(np.argmin(distance))
        self._approach(int(i[best]), int(j[best]), float(distance[best]), float(time[best]), *map(float, where[best]))
        for k in np.flatnonzero(distance < self.near_miss):
            self._approach(int(i[k]), int(j[k]), float(distance[k]), float(time[k]), *map(float, where[k]))

    def _approach(self, p: int, q: int, distance: float, time: float, x: float, y: float) -> None:
        distance = max(distance, 0.0)
        pair = (self.ids[p], self.ids[q])
        best = self._clearance
        if distance <= self.reach and (best is None or distance < best.distance):
            self._clearance = Approach(pair, distance, time, x, y)
        if distance < self.near_miss:
            known = self._closest.get((p, q))
            if known is None or distance < known.distance:
                self._closest[(p, q)] = Approach(pair, distance, time, x, y)
