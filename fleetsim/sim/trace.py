"""The canonical, versioned trace of a run and its hash (SPEC §10).

Per step the trace holds what changed: each vehicle's leg, traverse, progress, position, heading and
speed (quantised to integers: millimetres, hundredths of a degree, mm/s), the plans accepted, and the
events (task completions, rejections, route errors, alerts, the end). Lines are compact JSON with a
fixed layout; the hash is SHA-256 over the header and every line. Nothing from the wall clock, the host,
hash seeds or dict iteration order enters it, so the same behaviour gives the same hash everywhere.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from bisect import bisect_left
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from itertools import chain
from pathlib import Path
from typing import IO, Any

import numpy as np
import numpy.typing as npt
import orjson

from fleetsim.enums import Progress, Traverse
from fleetsim.motion.fleet_cruise import StateColumns
from fleetsim.planning.plans import FleetPlan
from fleetsim.planning.snapshot import VehicleState

__all__ = [
    "TRACE_FORMAT",
    "Trace",
    "TraceFile",
    "complete_lines",
    "cruised_records",
    "plan_record",
    "vehicle_record",
    "vehicle_records",
]

TRACE_FORMAT = "fleetsim-trace/1"
CHECKPOINT_EVERY = 100  # steps between the running digests kept for locating a divergence later

VehicleRecord = tuple[int, int, str, str, int, int, int, int]


_TRAVERSE = {Traverse.FORWARD: "f", Traverse.BACKWARD: "b"}
_PROGRESS = {Progress.FORWARD: "f", Progress.REVERSE: "r"}
_DEGREES_PER_RADIAN = 180.0 / 3.141592653589793
# A step's line: compact JSON, as json.dumps with these separators writes it (ASCII, other characters
# escaped). No check for circular references: a line holds only fresh lists, tuples, ints and strings.
_json_step = json.JSONEncoder(separators=(",", ":"), check_circular=False).encode


def _encode_step(line: list[Any]) -> bytes:
    """A step's line as bytes, exactly as ``_json_step`` writes it: by orjson, which writes the same
    bytes several times faster for what lines hold (ints within 64 bits, ASCII strings), and by
    ``json`` for the rest (a planner's route error message in other letters, say)."""
    try:
        encoded = orjson.dumps(line)
    except orjson.JSONEncodeError:
        return _json_step(line).encode("ascii")
    # json escapes every character outside ASCII and DEL; orjson writes them as they are.
    return encoded if encoded.isascii() and b"\x7f" not in encoded else _json_step(line).encode("ascii")


def vehicle_records(states: Iterable[VehicleState]) -> list[VehicleRecord]:
    """Each state as (id, segment, traverse, progress, x mm, y mm, heading centidegrees, speed mm/s).

    ``round`` of a float is an int, rounded half to even, so -0.0 and tiny values become 0. One call for
    all of a step's moving vehicles (a function call per vehicle would cost as much as the record); for
    many, the rounding is done in arrays, with the same products and the same rounding.
    """
    listed = states if isinstance(states, list) else list(states)
    if len(listed) >= _IN_ARRAYS_FROM:
        records = _records_in_arrays(listed)
        if records is not None:
            return records
    return [
        (
            state.id,
            state.segment,
            _TRAVERSE[state.traverse],
            _PROGRESS[state.progress],
            round(state.x * 1000.0),
            round(state.y * 1000.0),
            round(state.heading * _DEGREES_PER_RADIAN * 100.0),
            round(state.speed * 1000.0),
        )
        for state in listed
    ]


# States from which rounding in arrays costs less than one by one (measured: 48 states 21 µs against 24,
# 64 25 against 26, 128 43 against 52; 16 states 14 against 7).
_IN_ARRAYS_FROM = 64
_EXACT = 2.0**53  # below this, every whole float is an exact int64 too


def _records_in_arrays(states: list[VehicleState]) -> list[VehicleRecord] | None:
    """:func:`vehicle_records` with the products and the rounding (half to even, as ``round``) in arrays;
    ``None`` if some value is too large to pass through int64 exactly."""
    ids, segments, traverses, progresses, _, speeds, xs, ys, headings, _, _ = zip(*states, strict=True)
    values = _quantised(np.array((xs, ys, headings, speeds)))
    if values is None:
        return None
    return _zipped(ids, segments, traverses, progresses, values.tolist())


def _quantised(values: npt.NDArray[np.float64]) -> npt.NDArray[np.int64] | None:
    """Rows of x, y, heading and speed (changed in place) as millimetres, centidegrees and mm/s: the
    products and the rounding of one record at a time, in the same order. ``None`` if some value is too
    large to pass through int64 exactly."""
    values[0] *= 1000.0
    values[1] *= 1000.0
    values[2] *= _DEGREES_PER_RADIAN  # then * 100.0: the order of the one-by-one product
    values[2] *= 100.0
    values[3] *= 1000.0
    np.rint(values, out=values)
    if not (np.abs(values) < _EXACT).all():
        return None
    return values.astype(np.int64)


def _zipped(
    ids: Iterable[int],
    segments: Iterable[int],
    traverses: Iterable[Traverse],
    progresses: Iterable[Progress],
    quantised: list[list[int]],
) -> list[VehicleRecord]:
    x, y, heading, speed = quantised
    traverse = map(_TRAVERSE.__getitem__, traverses)
    progress = map(_PROGRESS.__getitem__, progresses)
    return list(zip(ids, segments, traverse, progress, x, y, heading, speed, strict=True))


# Records made, compared and encoded at a time: a piece's objects stay in the processor's cache from the
# first to the last (a large fleet's whole step of records does not: 10,000 vehicles' take some 2 MiB).
_PIECE = 1024


def _pieces(alone: list[VehicleRecord], cruised: StateColumns | None) -> Iterator[list[VehicleRecord]]:
    """A step's records, ascending id, in pieces of about ``_PIECE``: ``alone``, the records of the
    vehicles stepped one by one, merged with those of the cruising vehicles, read from their columns."""
    if cruised is None or not cruised.ids:
        yield alone
        return
    values = None
    if len(cruised.ids) >= _IN_ARRAYS_FROM:
        speed, x, y, heading = cruised.motion
        values = _quantised(np.array((x, y, heading, speed)))
    if values is None:  # few, or a value too large for the arrays: one by one
        records = alone + vehicle_records(cruised.states)
        records.sort()  # by id (ids are unique): two runs, merged
        yield records
        return
    ids, segments, traverses, progresses = cruised.ids, cruised.segments, cruised.traverses, cruised.progresses
    alone_ids = [record[0] for record in alone]
    taken = 0  # of alone
    count = len(ids)
    for start in range(0, count, _PIECE):
        end = min(start + _PIECE, count)
        piece = _zipped(
            ids[start:end],
            segments[start:end],
            traverses[start:end],
            progresses[start:end],
            values[:, start:end].tolist(),
        )
        until = bisect_left(alone_ids, ids[end]) if end < count else len(alone)  # those before the next piece
        if until > taken:
            piece += alone[taken:until]
            piece.sort()
            taken = until
        yield piece


def cruised_records(cruised: StateColumns) -> list[VehicleRecord]:
    """:func:`vehicle_records` of a step's cruising vehicles, read from the columns their states were made
    of (the same floats), so no state is taken apart again."""
    return list(chain.from_iterable(_pieces([], cruised)))


def vehicle_record(state: VehicleState) -> VehicleRecord:
    """One state's record (see :func:`vehicle_records`)."""
    return vehicle_records((state,))[0]


def plan_record(plan: FleetPlan) -> list[Any]:
    """[vehicle id, [[segment, traverse, progress, fixed 0/1, goal task or None], ...]]."""
    return [
        plan.vehicle_id,
        [
            [leg.segment, _TRAVERSE[leg.traverse], _PROGRESS[leg.progress], int(leg.fixed), leg.goal_for_task]
            for leg in plan.legs
        ],
    ]


class TraceFile:
    """A trace written while its run goes, so a run killed outright (SIGKILL, out of memory, a machine
    gone) leaves a trace that is valid up to its last complete line.

    Lines are those the hash is taken over, each ending in a newline, so the file's SHA-256 is the trace
    hash of a complete run. They are written and flushed at every checkpoint (every 100 steps) and at
    least every ``FLUSH_SECONDS`` of wall time (a slow planner takes long over 100 steps), and synced to
    the disk at most that often.
    """

    FLUSH_SECONDS = 1.0

    def __init__(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self._file: IO[str] = path.open("w", encoding="utf-8", newline="\n")
        self._pending: list[str] = []
        self._flushed = self._synced = -self.FLUSH_SECONDS  # the first step is written at once

    def add(self, line: str) -> None:
        self._pending.append(line)

    @property
    def due(self) -> bool:
        """The last flush is ``FLUSH_SECONDS`` old."""
        return time.monotonic() - self._flushed >= self.FLUSH_SECONDS

    def flush(self, *, sync: bool = False) -> None:
        """Write the pending lines and flush them to the operating system (and to the disk, when ``sync``
        or the last sync is ``FLUSH_SECONDS`` old)."""
        if self._file.closed:
            return
        if self._pending:
            self._file.write("".join(f"{line}\n" for line in self._pending))
            self._pending.clear()
        self._file.flush()
        now = self._flushed = time.monotonic()
        if sync or now - self._synced >= self.FLUSH_SECONDS:
            os.fsync(self._file.fileno())
            self._synced = now

    def close(self) -> None:
        """Write what is pending, sync and close (again: nothing)."""
        if not self._file.closed:
            try:
                self.flush(sync=True)
            finally:
                self._file.close()


def complete_lines(text: str) -> tuple[list[str], bool]:
    """The lines of a trace file that are whole, and whether the file ended cleanly.

    A run killed while writing may leave a last line without its newline (or cut inside a character);
    that line is dropped and the second value is False.
    """
    lines = text.split("\n")
    tail = lines.pop()  # after the last newline: empty when the file ends cleanly
    return lines, not tail


@dataclass(slots=True)
class Trace:
    """The trace being written: its running hash, checkpoints, (optionally) its lines, and (optionally) the
    file it streams to."""

    keep_lines: bool = True
    lines: list[str] = field(default_factory=list)
    checkpoints: list[tuple[int, str]] = field(default_factory=list)  # (step, digest so far)
    steps: int = 0
    sink: TraceFile | None = None
    # Called with each line once it is written (the header, then each step's, after the sink's flush): a
    # live view, which may hold the run there (a paused page) and must not change anything.
    watcher: Callable[[str], None] | None = None
    _hash: Any = field(default_factory=hashlib.sha256)
    _last: dict[int, VehicleRecord] = field(default_factory=dict)

    def begin(self, header: dict[str, Any]) -> None:
        header_line = json.dumps({"format": TRACE_FORMAT, **header}, separators=(",", ":"), sort_keys=True)
        self._write(header_line.encode("ascii"))
        if self.watcher is not None:
            self.watcher(header_line)

    def record(
        self,
        step: int,
        vehicles: Iterable[VehicleState],
        plans: Sequence[list[Any]],
        events: Sequence[list[Any]],
        cruised: StateColumns | None = None,
    ) -> None:
        """One step's line: the records of the vehicles that differ from their last, the plans accepted and
        the events. The vehicles are ``vehicles`` (ascending id) and those of ``cruised``, in columns."""
        # The line is written piece by piece (see _pieces), as one json.dumps of [step, changed, plans,
        # events] would write it.
        encoded = []
        last = self._last
        for piece in _pieces(vehicle_records(vehicles), cruised):
            changed = []
            for record in piece:
                if last.get(record[0]) != record:
                    last[record[0]] = record
                    changed.append(record)
            if changed:
                encoded.append(_encode_step(changed)[1:-1])
        rest = _encode_step([list(plans), list(events)])  # "[[plans],[events]]"
        line = b"[%d,[%b],%b" % (step, b",".join(encoded), rest[1:])
        text = self._write(line)
        self.steps = step + 1
        sink = self.sink
        if self.steps % CHECKPOINT_EVERY == 0:
            self.checkpoints.append((step, self._hash.copy().hexdigest()))
            if sink is not None:
                sink.flush()
        elif sink is not None and sink.due:
            sink.flush()
        if self.watcher is not None:
            self.watcher(text if text is not None else line.decode("ascii"))

    def _write(self, line: bytes) -> str | None:
        """One line (ASCII: the header and step lines escape anything else) into the hash and to whoever
        keeps lines; the line as text if it was decoded for them."""
        self._hash.update(line)
        self._hash.update(b"\n")
        if not (self.keep_lines or self.sink is not None):
            return None
        text = line.decode("ascii")
        if self.keep_lines:
            self.lines.append(text)
        if self.sink is not None:
            self.sink.add(text)
        return text

    @property
    def digest(self) -> str:
        digest: str = self._hash.hexdigest()
        return digest
