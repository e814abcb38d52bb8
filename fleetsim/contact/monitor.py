"""The physical judgement of a run: did two footprints touch, and how close did they come.

:class:`ContactMonitor` is told every vehicle's pose after every step (in arrays, by the loop's vehicle
order), or only the poses of the vehicles that moved (:meth:`ContactMonitor.step_moved`), and keeps:

- the *contacts*: each time two footprints begin to overlap, with the first moment, the place, and the
  deepest penetration while they overlap (an episode ends when they are apart again);
- the *clearance*: the closest any two footprints came over the run, with when, where and which pair;
- the *near misses*: for every pair that came closer than ``near_miss`` metres without touching, its
  closest approach.

Each step is judged in three phases. The broad phase lists the candidate pairs: it hashes the vehicles'
positions into a grid of cells as large as the farthest two footprints can be apart and still matter
(two half diagonals, the ``reach`` of interest, and both vehicles' travel), takes the pairs in the same
or neighbouring cells (no pair of the fleet is looked at otherwise) and keeps those whose centres are
that close. The list is drawn ``skin`` metres wider and kept over the steps (a Verlet list) until some
vehicle has drifted so far from where it was then that a pair from outside could have come in.
Of the listed pairs, one is looked at again only when its two vehicles have moved enough to close the
gap between it and what counts (each vehicle's *spent* distance: the most any point of its footprint can
have moved, its centre's travel plus its turn times its half diagonal, added up over the steps; the
gap: the pair's distance when last looked at, less the limit below which a distance counts, or less
the pair's own closest approach so far when that is closer: only a closer one would be recorded), and at
least one of them moved in the step. Their bounding circles sort out most of those (the distance
between circles never exceeds the distance between the rectangles they hold). The narrow phase takes
the exact distance (:mod:`.geometry`) of the pairs whose circles come close enough to matter, one pair
at a time in plain Python: a step leaves a handful per hundred vehicles.

A step in which few vehicles moved (told only what moved), and every step of a fleet of a few (at most
sixteen vehicles, every pair listed), skips the arrays, whose fixed cost per step would be most of its
judgement (:class:`_Told`): the poses and spent distances are plain floats and only the moved vehicles'
are brought up to date; what a pair's two vehicles may spend before it is looked at again is shared
between them, so only a moved vehicle that spent its share has its pairs looked at, on the same rule;
and a vehicle that drifted too far is listed again alone. What a pair adds to the report does not depend
on how often it is looked at beyond that rule, so the report is the same either way.

The continuous phase catches what no sampled step shows: two fast vehicles that pass through each other
within one step. It is conservative advancement along the poses interpolated between the step's start
and end (centre along the straight line, heading along the shorter turn): from the start, advance by
the distance divided by the most the distance can change per unit of the interpolation (the pair's
relative travel plus each one's turn times its half diagonal), and again, until the footprints touch
(within :data:`TOUCH` metres) or the step ends. Such an advance can never step over a touch. A pair needs it only when its circles'
distances at both ends add up to no more than that bound: otherwise it cannot have touched between.
The interpolation is a chord of the true path (an arc in a curve): at the 0.1 s step of fleetsim's
scenarios the two differ by millimetres.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from itertools import chain
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
_SKIN = 2.0  # metres: the candidate pairs are listed this much wider, and kept while no vehicle drove farther
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
        # Pairs closer than near_miss: their closest approach as (distance, time, x, y), made an Approach
        # only for the report (most are beaten again many times over a run).
        self._closest: dict[tuple[int, int], tuple[float, float, float, float]] = {}
        self._clearance: Approach | None = None
        self._limit = self.reach  # how close two footprints must come for their distance to count now
        self._sizes = np.array((self.half_length, self.half_width, self.radius))  # per vehicle
        self._size_rows: list[list[float]] = self._sizes.T.tolist()  # the same, by vehicle
        self._poses: Floats | None = None  # at the last step's end: x, y, heading (3, n)
        self._listed: _Listed | None = None  # the candidate pairs
        # Per vehicle, metres: the farthest any point of its footprint can have moved since the start.
        self._spent = np.zeros(len(self.ids))
        # While few vehicles move (and always for a fleet of a few), the state above is kept in plain Python
        # lists instead (``_told``), without the arrays' fixed cost per step; the arrays are stale meanwhile.
        self._few = len(self.ids) <= _FEW
        self._told: _Told | None = None
        self.looked = 0  # pairs looked at over the steps (a diagnostic: what the broad phase left)

    # -- the run ----------------------------------------------------------------------------------------

    def begin(self, x: Floats, y: Floats, heading: Floats, time: float = 0.0) -> list[Contact]:
        """The poses at the start: footprints that overlap already are contacts from ``time``."""
        self._poses = poses = np.array((x, y, heading), dtype=np.float64)
        self._told = self._tell() if self._few else None  # (a few: every pair listed, for good)
        i, j = self._candidates(poses, 0.0)
        table = np.vstack((poses, self._sizes))  # per vehicle: x, y, heading, half sizes, radius
        fresh = []
        for p, q, a, b in zip(i.tolist(), j.tolist(), table[:, i].T.tolist(), table[:, j].T.tolist(), strict=True):
            if math.hypot(b[0] - a[0], b[1] - a[1]) - a[5] - b[5] < self.reach:
                contact = self._judge(p, q, (a[0], a[1], a[2], a[3], a[4]), (b[0], b[1], b[2], b[3], b[4]), time)[1]
                if contact is not None:
                    fresh.append(contact)
        return fresh

    def step(
        self, t0: float, t1: float, x: Floats, y: Floats, heading: Floats, moved: npt.NDArray[np.bool_]
    ) -> list[Contact]:
        """The step from ``t0`` to ``t1`` ended with these poses; ``moved``: which vehicles' poses changed.
        Returns the contacts that began in it."""
        assert self._poses is not None, "begin() first"
        if self._few:
            at = moved.nonzero()[0]
            poses = list(zip(x[at].tolist(), y[at].tolist(), heading[at].tolist(), strict=True))
            return self._step_told(t0, t1, at.tolist(), poses)
        self._flush()
        return self._step_arrays(t0, t1, np.array((x, y, heading), dtype=np.float64), moved)

    def _step_arrays(self, t0: float, t1: float, end: Floats, moved: npt.NDArray[np.bool_]) -> list[Contact]:
        """:meth:`step` in arrays, the poses at its end in rows x, y, heading (kept as they are)."""
        start = self._poses
        assert start is not None
        self._poses = end
        if not np.count_nonzero(moved):  # nothing moved: no distance changed
            return []
        delta = end - start
        shift = np.hypot(delta[0], delta[1])
        # No point of a footprint moved farther than its centre's shift plus its turn times its half
        # diagonal; it turns the shorter way, at most half a turn (a heading that wraps round, from pi to
        # -pi, counts as half a turn: more, never less). Two footprints' distance changed by no more than
        # the sum of theirs.
        spin = np.minimum(np.abs(delta[2]), math.pi) * self.radius
        self._spent += shift + spin
        listed = self._neighbours(end, float(shift.max()))
        spent = self._spent[listed.i] + self._spent[listed.j]
        due = (listed.due <= spent).nonzero()[0]
        due = due[moved[listed.i[due]] | moved[listed.j[due]]]
        if len(due) == 0:
            return []
        self.looked += len(due)
        # The step's few pairs read their two vehicles from plain lists, gathered once for all of them:
        # x, y, heading at the end and at the start, and the spin, for the pairs' first vehicles and then
        # their second ones.
        i, j = listed.i[due], listed.j[due]
        both = np.concatenate((i, j))
        ends, starts, spins = end[:, both].T.tolist(), start[:, both].T.tolist(), spin[both].tolist()
        fresh: list[Contact] = []
        slack = self._look(t0, t1, i.tolist(), j.tolist(), ends, starts, spins, fresh)
        listed.due[due] = spent[due] + np.array(slack)
        return fresh

    @property
    def few(self) -> bool:
        """The fleet is a few: its steps are always judged in plain Python (:meth:`step_moved`)."""
        return self._few

    def step_moved(
        self, t0: float, t1: float, moved: list[int], poses: list[tuple[float, float, float]]
    ) -> list[Contact]:
        """:meth:`step`, told only which vehicles moved (their indices) and their poses (x, y,
        heading) at the step's end; the others stand where they were. The same contacts and report as
        :meth:`step`. While few vehicles move (at most :data:`_TOLD`, or any number in a fleet of a few)
        the step is judged in plain Python, in proportion to what moved; else in arrays."""
        assert self._poses is not None, "begin() first"
        if self._few or len(moved) <= _TOLD:
            return self._step_told(t0, t1, moved, poses)
        self._flush()
        end = self._poses.copy()
        at = np.array(moved, dtype=np.intp)
        end.T[at] = np.fromiter(chain.from_iterable(poses), dtype=np.float64, count=3 * len(moved)).reshape(-1, 3)
        stirred = np.zeros(len(self.ids), dtype=np.bool_)
        stirred[at] = True
        return self._step_arrays(t0, t1, end, stirred)

    def _step_told(
        self, t0: float, t1: float, moved: list[int], poses: list[tuple[float, float, float]]
    ) -> list[Contact]:
        """The step in plain Python (:class:`_Told`): the moved vehicles' poses and spent distances brought
        up to date as :meth:`step` does in arrays (the centre's shift, plus the turn times the half
        diagonal), and the pairs of the moved vehicles that are due looked at, in the pairs' order: the
        pairs :meth:`step` looks at. What a pair adds to the report does not depend on how often it is
        looked at beyond that rule, so the report is the same either way."""
        if not moved:  # nothing moved: no distance changed
            return []
        told = self._told
        if told is None:
            told = self._told = self._tell()
        xs, ys, hs = told.poses
        spent, radius, cx, cy = told.spent, told.radius, told.cx, told.cy
        # The moved vehicles' poses at the step's start, and their spins (a standing vehicle's is 0.0, as
        # step() works it out); those that drifted so far from where their pairs were listed that a pair
        # from outside could have come in.
        starts: dict[int, tuple[float, float, float]] = {}
        spins: dict[int, float] = {}
        travel, skin = 0.0, told.skin
        drifted: list[int] = []
        for v, (x, y, h) in zip(moved, poses, strict=True):
            x0, y0, h0 = starts[v] = (xs[v], ys[v], hs[v])
            xs[v], ys[v], hs[v] = x, y, h
            shift = math.hypot(x - x0, y - y0)
            spin = spins[v] = min(abs(h - h0), math.pi) * radius[v]
            spent[v] += shift + spin
            if shift > travel:
                travel = shift
            if shift + math.hypot(x - cx[v], y - cy[v]) > skin:
                drifted.append(v)
        if not self._few:
            if self._listed is None or travel > skin:  # listed anew, wider (as step() does)
                told.flush()
                assert self._poses is not None
                self._drifted(self._poses, travel)
                told = self._told = self._tell()
            elif drifted:
                told.list_again(drifted)
        looked = told.due(moved)
        if not looked:
            return []
        self.looked += len(looked)
        firsts = [p for p, _ in looked]
        seconds = [q for _, q in looked]
        both = firsts + seconds
        ends = [[xs[v], ys[v], hs[v]] for v in both]
        begun = [list(starts[v]) if v in starts else [xs[v], ys[v], hs[v]] for v in both]
        fresh: list[Contact] = []
        slack = self._look(t0, t1, firsts, seconds, ends, begun, [spins.get(v, 0.0) for v in both], fresh)
        told.looked(looked, slack)
        return fresh

    def _tell(self) -> _Told:
        """The state in plain lists, to be judged in Python: the poses, spent distances and listed pairs (the
        arrays are stale until :meth:`_flush`)."""
        assert self._poses is not None
        count = len(self.ids)
        if self._few:  # every pair, for good
            pairs = [(p, q, -math.inf) for p in range(count) for q in range(p + 1, count)]
            return _Told(self, pairs, None, math.inf)
        listed = self._listed
        if listed is None:
            return _Told(self, [], None, -math.inf)  # (listed at the first step)
        pairs = list(zip(listed.i.tolist(), listed.j.tolist(), listed.due.tolist(), strict=True))
        return _Told(self, pairs, listed.centres, listed.skin)

    def _flush(self) -> None:
        """Bring the arrays up to date from the lists of a step judged in Python, and judge in arrays on."""
        if self._told is not None:
            self._told.flush()
            self._told = None

    def _look(
        self,
        t0: float,
        t1: float,
        firsts: list[int],
        seconds: list[int],
        ends: list[list[float]],
        starts: list[list[float]],
        spins: list[float],
        fresh: list[Contact],
    ) -> list[float]:
        """Look at the pairs ``(firsts[k], seconds[k])``, in order: ``ends``, ``starts`` and ``spins`` hold
        their first vehicles' x, y, heading at the step's end and start and spin, then their second ones'.
        Contacts begun go to ``fresh``; returns each pair's slack: what the two must spend before it needs
        to be looked at again."""
        sizes = self._size_rows
        pairs = len(firsts)
        slack: list[float] = []
        active, closest = self._active, self._closest
        for k, (p, q) in enumerate(zip(firsts, seconds, strict=True)):
            (ax, ay, ah), (ax0, ay0, ah0), (al, aw, ar) = ends[k], starts[k], sizes[p]
            (bx, by, bh), (bx0, by0, bh0), (bl, bw, br) = ends[pairs + k], starts[pairs + k], sizes[q]
            a1, b1 = (ax, ay, ah, al, aw), (bx, by, bh, bl, bw)
            distance = gap = math.hypot(bx - ax, by - ay) - ar - br  # the bounding circles' gap at the end
            if (p, q) in active:  # in contact at the step's start: followed, never swept anew
                distance = self._follow(p, q, a1, b1, t1)
            else:
                # Between the steps: they could have touched only if the circles' gaps at both ends add up to
                # no more than the most their distance can change (relative travel plus both spins).
                gap0 = math.hypot(bx0 - ax0, by0 - ay0) - ar - br
                most = math.hypot(bx - bx0 - ax + ax0, by - by0 - ay + ay0) + spins[k] + spins[pairs + k]
                if gap0 + gap <= most + TOUCH:
                    a0, b0 = (ax0, ay0, ah0, al, aw), (bx0, by0, bh0, bl, bw)
                    contact = self._sweep(p, q, a0, a1, b0, b1, most, t0, t1)
                    if contact is not None:
                        fresh.append(contact)
                # Close enough at the step's end to count: within the limit and, once the pair has a closest
                # approach on record, within that too (only a closer one, or a touch, would be recorded).
                known = closest.get((p, q))
                bar = self._limit if known is None else max(min(known[0], self._limit), TOUCH)
                if gap < self._limit and gap <= bar:
                    distance, contact = self._judge(p, q, a1, b1, t1, bar)
                    if contact is not None:
                        fresh.append(contact)
            # The pair need not be looked at again until the fleet has spent what keeps it farther apart than
            # anything it could still add to the report: the limit (which only shrinks over a run), or its own
            # closest approach so far, which only a closer one replaces (the clearance is never farther).
            known = closest.get((p, q))
            floor = self._limit if known is None else min(known[0], self._limit)
            slack.append(distance - floor - TOUCH)
        return slack

    def report(self) -> ContactReport:
        """What was found; an overlap still in force at the end has ``until`` None."""
        touched = {c.vehicles for c in self.contacts}
        misses = sorted(
            (
                Approach((self.ids[p], self.ids[q]), *closest)
                for (p, q), closest in self._closest.items()
                if (self.ids[p], self.ids[q]) not in touched
            ),
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

    def _neighbours(self, poses: Floats, travel: float) -> _Listed:
        """Every pair (i < j, in order) whose centres are within the broad phase's distance (see
        :meth:`_candidates`) at ``poses``, after a step in which no vehicle drove farther than ``travel``:
        the pairs listed ``skin`` wider, while no vehicle has drifted so far from where it was then that
        a pair could have come in from outside (travel + drift <= skin), else listed anew."""
        listed = self._listed
        if listed is not None:
            # No vehicle drifted farther than the farthest travels of the steps since added up: look at
            # each one's drift only when that does not settle it.
            listed.travelled += travel
            if travel + listed.travelled <= listed.skin:
                return listed
        return self._drifted(poses, travel)

    def _drifted(self, poses: Floats, travel: float) -> _Listed:
        """:meth:`_neighbours` once the travels added up do not settle it: each vehicle's drift."""
        listed = self._listed
        if listed is not None:
            centres = listed.centres
            drift = float(np.hypot(poses[0] - centres[0], poses[1] - centres[1]).max(initial=0.0))
            if travel + drift <= listed.skin:
                return listed
        skin = max(_SKIN, travel)
        i, j = self._candidates(poses, skin)
        size = self._largest + self.reach + 2.0 * skin + TOUCH
        keep = np.hypot(poses[0, j] - poses[0, i], poses[1, j] - poses[1, i]) <= size
        keys = i[keep] * len(self.ids) + j[keep]
        keys.sort()
        due = np.full(len(keys), -np.inf)
        if listed is not None and len(listed.keys) and len(keys):  # what is known of the pairs listed before
            at = np.minimum(np.searchsorted(listed.keys, keys), len(listed.keys) - 1)
            known = listed.keys[at] == keys
            due[known] = listed.due[at[known]]
        self._listed = listed = _Listed(keys, due, poses[:2].copy(), skin, len(self.ids))
        return listed

    def _candidates(self, poses: Floats, travel: float) -> tuple[Ints, Ints]:
        """Pairs (i < j) in the same or neighbouring cells of a grid as large as two footprints can be
        apart and still matter (after a step in which no vehicle drove farther than ``travel``)."""
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
        keep = np.where(same_cell, i < j, i != j)
        i, j = i[keep], j[keep]
        return np.minimum(i, j), np.maximum(i, j)

    def _judge(
        self, p: int, q: int, a: Footprint, b: Footprint, time: float, bar: float | None = None
    ) -> tuple[float, Contact | None]:
        """The pair ``(p, q)``, not in contact before, at ``time`` (footprints ``a``, ``b``): if they touch
        now they begin a contact (unless the sweep began it already), else their distance is recorded.
        Their signed distance (or a lower bound of it beyond ``bar``), and the contact begun. ``bar``: how
        close they must be for anything to count, at most the limit and at least :data:`TOUCH` (the limit
        when None); beyond it they neither touch nor come closer than anything on record."""
        bar = self._limit if bar is None else bar
        distance, x, y = signed_distance(a, b, bar)  # beyond the bar, nothing counts
        if distance > bar:
            return distance, None
        if distance > TOUCH:
            self._approach(p, q, distance, time, x, y)
            return distance, None
        if (p, q) in self._active:
            return distance, None
        return distance, self._begin_contact(p, q, time, x, y, -distance)

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
            contact = self._end_contact(p, q, t1)
        return contact

    def _follow(self, p: int, q: int, a: Footprint, b: Footprint, t1: float) -> float:
        """Deepen or end the contact of the pair ``(p, q)``, in force at the step's start; their signed
        distance."""
        d = signed_distance(a, b)[0]
        index = self._active[(p, q)]
        contact = self.contacts[index]
        if d > TOUCH:
            self._end_contact(p, q, t1)
        elif -d > contact.depth:
            self.contacts[index] = Contact(contact.time, contact.vehicles, contact.x, contact.y, -d)
        return d

    # -- bookkeeping --------------------------------------------------------------------------------------

    def _begin_contact(self, p: int, q: int, time: float, x: float, y: float, depth: float) -> Contact:
        contact = Contact(time, (self.ids[p], self.ids[q]), x, y, max(depth, 0.0))
        self._active[(p, q)] = len(self.contacts)
        self.contacts.append(contact)
        self._approach(p, q, 0.0, time, x, y)
        return contact

    def _end_contact(self, p: int, q: int, t1: float) -> Contact:
        index = self._active.pop((p, q))
        self.contacts[index] = contact = replace(self.contacts[index], until=t1)
        return contact

    def _approach(self, p: int, q: int, distance: float, time: float, x: float, y: float) -> None:
        distance = max(distance, 0.0)
        best = self._clearance
        if distance <= self.reach and (best is None or distance < best.distance):
            self._clearance = Approach((self.ids[p], self.ids[q]), distance, time, x, y)
            # How close two footprints must come for their distance to count now: within the near-miss
            # distance, or closer than the clearance so far (within ``reach`` before there is one).
            self._limit = max(self.near_miss, distance)
        if distance < self.near_miss:
            known = self._closest.get((p, q))
            if known is None or distance < known[0]:
                self._closest[(p, q)] = (distance, time, x, y)


# Fleets of at most this many vehicles (120 pairs) are judged in plain Python (ContactMonitor._step_told),
# every pair listed: up to it, the arrays' fixed cost per step (some twenty operations) is more than the
# pairs' own. Measured on random walks (µs a step, plain Python against arrays): 6 vehicles 26 against 48
# crowded, 16 against 33 spread out; 16 vehicles 95 against 104 and 35 against 50; 20 vehicles 134
# against 133 crowded.
_FEW = 16
# A larger fleet's step is judged in plain Python while at most this many vehicles moved in it: about
# where the arrays' fixed cost per step (some twenty operations) meets plain Python's cost per moved
# vehicle (replayed steps of runs of 100 vehicles: about 31 µs a step against 0.84 µs a moved vehicle,
# the pairs looked at apart; in a run, with the rest of the harness and the planner between the steps,
# both cost more: with 80 to 90 of 100 vehicles moving, 130 µs a step in plain Python against 102 in
# arrays; with 13, in a shift, about half what the arrays took).
_TOLD = 40


class _Told:
    """A monitor's state in plain lists, for the steps judged in Python (:meth:`ContactMonitor._step_told`):
    the poses (x, y, heading rows), each vehicle's spent distance and half diagonal, the listed pairs and,
    per vehicle, where its pairs were listed (its centre then).

    It is kept in proportion to what moved. A pair is listed with what its two vehicles must have spent
    before it is due (as :class:`_Listed`), and that is split into a share for each: while neither has
    spent its share the two together have not spent it, so only a moved vehicle that spent its own (its
    ``low``, the least of its shares) has its pairs looked at, and a pair that is not due yet has what is
    left split again. A vehicle whose centre drifted so far from where its pairs were listed that a pair
    from outside could have come in (its drift plus its step's travel beyond the skin) is listed again
    alone, against the others' centres then: a pair is listed while the two centres its vehicles were
    listed at are within the broad phase's distance, whatever the others do.
    """

    __slots__ = ("cx", "cy", "every", "low", "monitor", "pairs", "poses", "radius", "size", "skin", "spent")

    # A share is split this much short (relative), so that a pair whose two vehicles have not spent their
    # shares is never due in floating point either: at worst a pair is found not due yet once more.
    _SHORT = 1e-9

    def __init__(
        self,
        monitor: ContactMonitor,
        pairs: Iterable[tuple[int, int, float]],
        centres: Floats | None,
        skin: float,
    ) -> None:
        assert monitor._poses is not None
        count = len(monitor.ids)
        self.monitor = monitor
        self.poses: list[list[float]] = monitor._poses.tolist()
        self.spent: list[float] = monitor._spent.tolist()
        self.radius: list[float] = monitor.radius.tolist()
        # Where each vehicle's pairs were listed (none: every pair is listed, or none yet), and how far it
        # may drift from there.
        self.skin = skin
        self.size = monitor._largest + monitor.reach + 2.0 * skin + TOUCH
        self.cx: list[float] = [0.0] * count if centres is None else centres[0].tolist()
        self.cy: list[float] = [0.0] * count if centres is None else centres[1].tolist()
        # Per vehicle, its listed pairs by the other vehicle: [due, the first's share, the second's share]
        # (shared by the two), and the least of its shares.
        self.pairs: list[dict[int, list[float]]] = [{} for _ in range(count)]
        self.low = [math.inf] * count
        # A fleet of a few, every pair listed for good: its pairs in order, each looked at in turn (for so
        # few, cheaper than the shares).
        self.every: list[tuple[int, int, list[float]]] | None = [] if monitor._few else None
        spent, low = self.spent, self.low
        for p, q, due in pairs:
            self.pairs[p][q] = self.pairs[q][p] = pair = [due, 0.0, 0.0]
            if self.every is not None:
                self.every.append((p, q, pair))
                continue
            self._split(pair, p, q, due - spent[p] - spent[q])
            low[p], low[q] = min(low[p], pair[1]), min(low[q], pair[2])

    def _split(self, pair: list[float], p: int, q: int, left: float) -> None:
        """Share what the pair ``(p, q)``'s two vehicles have ``left`` to spend before it is due."""
        half = 0.5 * left - self._SHORT * (1.0 + abs(pair[0]))
        pair[1], pair[2] = self.spent[p] + half, self.spent[q] + half

    def due(self, moved: list[int]) -> list[tuple[int, int]]:
        """The pairs (p < q, in order) due after a step in which ``moved`` moved: those of a moved vehicle
        whose two vehicles have spent what it was listed with (as :meth:`ContactMonitor.step` finds them)."""
        spent, low, pairs = self.spent, self.low, self.pairs
        if self.every is not None:
            stirred = set(moved)
            return [
                (p, q) for p, q, pair in self.every if pair[0] <= spent[p] + spent[q] and (p in stirred or q in stirred)
            ]
        found: set[tuple[int, int]] = set()
        for v in moved:
            spent_v = spent[v]
            if spent_v < low[v]:
                continue  # none of its pairs can be due: it spent no share of theirs
            least = math.inf
            for w, pair in pairs[v].items():
                p, q = (v, w) if v < w else (w, v)
                if pair[1 if v < w else 2] <= spent_v:
                    if pair[0] <= spent[p] + spent[q]:
                        found.add((p, q))
                        continue  # (its new shares are made when it has been looked at)
                    self._split(pair, p, q, pair[0] - spent[p] - spent[q])
                    other = pair[2] if v < w else pair[1]
                    if other < low[w]:
                        low[w] = other
                share = pair[1 if v < w else 2]
                if share < least:
                    least = share
            low[v] = least
        return sorted(found)

    def looked(self, looked: list[tuple[int, int]], slack: list[float]) -> None:
        """The pairs ``looked`` at are due again when their two vehicles have spent ``slack`` more."""
        spent, low, pairs = self.spent, self.low, self.pairs
        for (p, q), more in zip(looked, slack, strict=True):
            pair = pairs[p][q]
            pair[0] = (spent[p] + spent[q]) + more
            if self.every is None:
                self._split(pair, p, q, more)
                low[p], low[q] = min(low[p], pair[1]), min(low[q], pair[2])

    def list_again(self, drifted: list[int]) -> None:
        """List the pairs of the vehicles that ``drifted`` anew, from where they are (a pair found anew is
        due at once, as one listed anew by the arrays; one no longer near is dropped)."""
        xs, ys = self.poses[0], self.poses[1]
        cx, cy, pairs, low = self.cx, self.cy, self.pairs, self.low
        for v in drifted:
            cx[v], cy[v] = xs[v], ys[v]
        centres = np.array((cx, cy))
        for v in drifted:
            near = np.hypot(centres[0] - cx[v], centres[1] - cy[v]) <= self.size
            near[v] = False
            now = set(near.nonzero()[0].tolist())
            mine = pairs[v]
            for w in [w for w in mine if w not in now]:
                del mine[w], pairs[w][v]
            for w in now:
                if w not in mine:
                    mine[w] = pairs[w][v] = [-math.inf, -math.inf, -math.inf]
                    low[v] = low[w] = -math.inf

    def flush(self) -> None:
        """Bring the monitor's arrays up to date from these lists (the pairs listed as they are here)."""
        monitor = self.monitor
        monitor._poses = np.array(self.poses, dtype=np.float64)
        monitor._spent = np.array(self.spent, dtype=np.float64)
        if monitor._few or monitor._listed is None:
            return
        count = len(self.pairs)
        listed = sorted(
            (p * count + q, pair[0]) for p, mine in enumerate(self.pairs) for q, pair in mine.items() if p < q
        )
        keys = np.array([key for key, _ in listed], dtype=np.intp)
        due = np.array([due for _, due in listed], dtype=np.float64)
        monitor._listed = _Listed(keys, due, np.array((self.cx, self.cy), dtype=np.float64), self.skin, count)
        # Each vehicle drifted less than the skin from its own centre: the arrays look at the drifts next.
        monitor._listed.travelled = self.skin


class _Listed:
    """The broad phase's candidate pairs (``keys``: i * count + j, i < j, in order) and the centres and skin
    they were listed for; per pair, what its two vehicles must have spent before it needs to be looked at
    again (``due``)."""

    __slots__ = ("centres", "due", "i", "j", "keys", "skin", "travelled")

    def __init__(self, keys: Ints, due: Floats, centres: Floats, skin: float, count: int) -> None:
        self.keys, self.due, self.centres, self.skin = keys, due, centres, skin
        self.i, self.j = keys // count, keys % count
        self.travelled = 0.0  # the farthest travels of the steps since, added up
