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
the distance divided by the most the distance can change per unit of the interpolation (the pair's
relative travel plus each one's turn times its half diagonal), and again, until the footprints touch (within :data:`TOUCH` metres) or
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

from fleetsim.contact.geometry import Footprint, interpolate, separation, signed_distance

__all__ = ["TOUCH", "Approach", "Contact", "ContactMonitor", "ContactReport"]

TOUCH = 1e-4  # metres: footprints closer than this touch
_ADVANCES = 32  # conservative advancement steps per pair and step before sampling the rest
_SAMPLES = 16  # samples of what is left of a step after that
# The broad phase counts vehicles per cell in an array while there are at most this many cells per vehicle.
_DENSE_CELLS = 8
# Half the 3 x 3 cells round a cell, as (dx, dy) columns: each pair of neighbouring cells once.
_NEIGHBOURS = np.array([[0, 1, 1, 1, 0], [0, -1, 0, 1, 1]], dtype=np.int64)

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
        self._largest = 2.0 * float(self.radius.max(initial=0.0))
        self.safety_margin, self.near_miss = safety_margin, near_miss
        self.reach = max(reach, near_miss)
        self.contacts: list[Contact] = []
        self._active: dict[tuple[int, int], int] = {}  # a pair of indices in contact -> its contact
        self._closest: dict[tuple[int, int], Approach] = {}  # pairs closer than near_miss
        self._clearance: Approach | None = None
        self._poses: Floats | None = None  # at the last step's end: x, y, heading, half sizes (5, n)

    # -- the run ----------------------------------------------------------------------------------------

    def begin(self, x: Floats, y: Floats, heading: Floats, time: float = 0.0) -> list[Contact]:
        """The poses at the start: footprints that overlap already are contacts from ``time``."""
        self._poses = poses = np.array((x, y, heading, self.half_length, self.half_width), dtype=np.float64)
        i, j = self._candidates(poses, np.ones(len(self.ids), dtype=bool), 0.0)
        gap = np.hypot(poses[0, j] - poses[0, i], poses[1, j] - poses[1, i]) - self.radius[i] - self.radius[j]
        near = np.flatnonzero(gap < self.reach)
        return self._judge_end(i[near], j[near], poses, time)

    def step(
        self, t0: float, t1: float, x: Floats, y: Floats, heading: Floats, moved: npt.NDArray[np.bool_]
    ) -> list[Contact]:
        """The step from ``t0`` to ``t1`` ended with these poses; ``moved``: which vehicles' poses changed.
        Returns the contacts that began in it."""
        start = self._poses
        assert start is not None, "begin() first"
        end = start.copy()
        end[0], end[1], end[2] = x, y, heading
        self._poses = end
        if not moved.any():  # nothing moved: no distance changed
            return []
        dx, dy = end[0] - start[0], end[1] - start[1]
        i, j = self._candidates(end, moved, float(np.hypot(dx, dy).max()))
        if len(i) == 0:
            return []
        # Per pair, from gathers of per-vehicle rows: the bounding circles' gaps at both ends, and the most
        # their footprints' distance can change over the step (relative travel, plus each one's turn times
        # its half diagonal, the farthest any point of it lies from its centre).
        spin = np.abs(np.remainder(end[2] - start[2] + np.pi, 2.0 * np.pi) - np.pi) * self.radius
        rows = np.array((end[0], end[1], dx, dy, self.radius, spin))
        first, second = rows[:, i], rows[:, j]
        offset = second - first
        reach = first[4] + second[4]
        gap1 = np.hypot(offset[0], offset[1]) - reach
        gap0 = np.hypot(offset[0] - offset[2], offset[1] - offset[3]) - reach
        bound = np.hypot(offset[2], offset[3]) + first[5] + second[5]
        active = self._in_contact(i, j)  # in contact at the step's start: followed, never swept anew
        fresh: list[Contact] = []
        # Between the steps: pairs that could have touched and were not touching already (the circles'
        # gaps at both ends add up to no more than the bound).
        maybe = np.flatnonzero((gap0 + gap1 <= bound + TOUCH) & ~active)
        if len(maybe):
            p, q = i[maybe], j[maybe]
            pairs = zip(
                p.tolist(), q.tolist(), _footprints(start, p), _footprints(end, p), _footprints(start, q),
                _footprints(end, q), bound[maybe].tolist(), strict=True,
            )  # fmt: skip
            for first_id, second_id, a0, a1, b0, b1, most in pairs:
                contact = self._sweep(first_id, second_id, a0, a1, b0, b1, most, t0, t1)
                if contact is not None:
                    fresh.append(contact)
        # At the step's end: the contacts in force, and the pairs whose circles come close enough to count.
        limit = max(self.near_miss, self._clearance.distance if self._clearance is not None else self.reach)
        near = np.flatnonzero((gap1 < limit) | active)
        if len(near):
            held = active[near]
            if held.any():
                self._follow(i[near[held]], j[near[held]], end, t1)
            near = near[~held]
            fresh += self._judge_end(i[near], j[near], end, t1)
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

    def _candidates(self, poses: Floats, moved: npt.NDArray[np.bool_], travel: float) -> tuple[Ints, Ints]:
        """Pairs (i < j) in the same or neighbouring cells of a grid as large as two footprints can be
        apart and still matter, at least one of them moved."""
        count = len(self.ids)
        if count < 2:
            return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
        size = self._largest + self.reach + 2.0 * travel + TOUCH
        cells = np.floor(poses[:2] / size).astype(np.int64)
        cells -= cells.min(axis=1, keepdims=True)
        span = int(cells[1].max()) + 3  # room for the neighbours' rows
        key = cells[0] * span + (cells[1] + 1)
        order = np.argsort(key, kind="stable")
        targets = (key[:, None] + _NEIGHBOURS[0] * span + _NEIGHBOURS[1]).ravel()
        keys = (int(cells[0].max()) + 2) * span
        if keys <= _DENSE_CELLS * count + 4096:  # few cells: count the vehicles in each, in one array
            per_cell = np.bincount(key, minlength=keys)
            counts = per_cell[targets]
            left = (np.cumsum(per_cell) - per_cell)[targets]
        else:  # a sparse fleet on a vast map: look each cell up among the vehicles' sorted cells
            ordered = key[order]
            left = np.searchsorted(ordered, targets, side="left")
            counts = np.searchsorted(ordered, targets, side="right") - left
        total = int(counts.sum())
        if total == 0:
            return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
        cell = np.repeat(np.arange(count * len(_NEIGHBOURS[0]), dtype=np.intp), counts)
        i = cell // len(_NEIGHBOURS[0])
        j = order[np.arange(total) + np.repeat(left - (np.cumsum(counts) - counts), counts)]
        same_cell = cell % len(_NEIGHBOURS[0]) == 0
        keep = np.where(same_cell, i < j, i != j) & (moved[i] | moved[j])
        i, j = i[keep], j[keep]
        return np.minimum(i, j), np.maximum(i, j)

    def _judge_end(self, i: Ints, j: Ints, poses: Floats, time: float) -> list[Contact]:
        """The pairs ``(i, j)``, not in contact before, at ``time`` (``poses``): those that touch now begin
        a contact (unless the sweep began it already), the others' distances are recorded."""
        fresh = []
        for p, q, a, b in zip(i.tolist(), j.tolist(), _footprints(poses, i), _footprints(poses, j), strict=True):
            distance, x, y = signed_distance(a, b)
            if distance > TOUCH:
                self._approach(p, q, distance, time, x, y)
            elif (p, q) not in self._active:  # a touch the sweep could not tell apart (it began at the end)
                fresh.append(self._begin_contact(p, q, time, x, y, -distance))
        return fresh

    def _sweep(
        self,
        p: int,
        q: int,
        a0: Footprint,
        a1: Footprint,
        b0: Footprint,
        b1: Footprint,
        bound: float,
        t0: float,
        t1: float,
    ) -> Contact | None:
        """Conservative advancement of the pair ``(p, q)`` over the step (its footprints ``a0``, ``b0`` at
        the start and ``a1``, ``b1`` at the end; ``bound``: the most their distance can change over it): the
        contact that begins in it, if any."""
        # The separating-axis separations, lower bounds of the distance much closer than the circles' for
        # side-by-side rectangles, sort out the pairs that merely drive alongside each other.
        if separation(a0, b0) + separation(a1, b1) > bound + TOUCH:
            return None
        scale = 1.0 / max(bound, 1e-12)
        duration = t1 - t0
        tau, touched = 0.0, None
        for _ in range(_ADVANCES):
            distance, x, y = signed_distance(interpolate(a0, a1, tau), interpolate(b0, b1, tau))
            if distance <= TOUCH:
                touched = (tau, x, y)
                break
            if tau > 0.0:  # the closest they came between the steps counts too
                self._approach(p, q, distance, t0 + tau * duration, x, y)
            tau += distance * scale
            if tau > 1.0:
                return None
        else:  # still advancing (a graze, where each advance is short): sample what is left of the step
            for k in range(_SAMPLES):
                at = tau + (1.0 - tau) * k / (_SAMPLES - 1)
                distance, x, y = signed_distance(interpolate(a0, a1, at), interpolate(b0, b1, at))
                if distance <= TOUCH:
                    touched = (at, x, y)
                    break
        if touched is None or (p, q) in self._active:
            return None
        begun, x, y = min(touched[0], 1.0), touched[1], touched[2]
        # How deep they went within the step (at its end, the next step's follow-up takes over).
        inside = [
            signed_distance(interpolate(a0, a1, at), interpolate(b0, b1, at))[0]
            for at in (begun + (1.0 - begun) * k / (_SAMPLES - 1) for k in range(_SAMPLES))
        ]
        contact = self._begin_contact(p, q, t0 + begun * duration, x, y, max(0.0, -min(inside)))
        if inside[-1] > TOUCH:  # apart again by the step's end: passed through each other
            self.contacts[self._active.pop((p, q))] = contact = replace(contact, until=t1)
        return contact

    def _follow(self, i: Ints, j: Ints, poses: Floats, t1: float) -> None:
        """Deepen or end the contacts of the pairs ``(i, j)``, in force at the step's start."""
        for p, q, a, b in zip(i.tolist(), j.tolist(), _footprints(poses, i), _footprints(poses, j), strict=True):
            d = signed_distance(a, b)[0]
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

    def _in_contact(self, i: Ints, j: Ints) -> npt.NDArray[np.bool_]:
        """Which of the pairs ``(i, j)`` are in contact now."""
        if not self._active:
            return np.zeros(len(i), dtype=bool)
        count = len(self.ids)
        known = np.array([p * count + q for p, q in self._active], dtype=np.int64)
        return np.isin(i.astype(np.int64) * count + j, known)

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


def _footprints(poses: Floats, rows: Ints) -> list[Footprint]:
    """The footprints of the vehicles ``rows`` from a (5, n) array of poses and half sizes."""
    return list(zip(*poses[:, rows].tolist(), strict=True))
