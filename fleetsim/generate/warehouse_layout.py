"""The segments of a generated warehouse: aisles, cross aisles, pick lay-bys, the dock and the parking rows.

The plan, in metres (drawn for a one-way site; ``^``/``v`` the aisles' directions)::

    dock:       |  |  |  |  |        drop stations: rungs of a ladder above the top cross aisle
    top      ->-+--+--+--+--+->-     cross aisle, one way round
              ^ |  v  ^  v  v
    aisles    ^ |] v ]^ ]v ]v ]      parallel aisles; pick stations are lay-bys (]) on their right
              ^ |  v  ^  v  v
    bottom   -<-+--+--+--+--+-<-     cross aisle
    parking:    |  |  |  |  |        parking places: rungs of a ladder below the bottom cross aisle

Every station is a drive-through place, one-way in both kinds of site, so a vehicle that stands there (a
dwell, or parked) blocks nobody's way: a *lay-by* leaves its aisle at a right angle, runs beside it
(the station) and comes back; a *rung* of a ladder leaves its cross aisle through a connector, holds a
station, and goes on through a second connector to the ladder's back lane, which returns to the cross
aisle past the last rung. Connectors are as long as the *clearance*: the swept diameter of the vehicle
(``2·r``, SPEC §4) plus 0.2 m, rounded up to the quarter metre; so a station is at least that far from
every lane it does not touch and from every other station, and its segment conflicts with its own
connectors only. A row of parking places that does not fit along the cross aisle continues on a second
ladder hanging from the first one's back lane (the first then gets an entry rung), and so on.

All junctions are right angles: the site is for vehicles that turn in place. Coordinates come out on a
quarter-metre grid wherever the options are multiples of a quarter metre, and centred on the origin.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from itertools import pairwise
from types import MappingProxyType

from fleetsim.enums import Direction, Shape
from fleetsim.generate.options import GenerateError, WarehouseOptions
from fleetsim.layout.segment import Point, Segment
from fleetsim.orders import Station

__all__ = ["DROP", "PARK", "PICK", "Sizes", "WarehouseLayout", "sizes_for", "warehouse_layout"]

PICK, DROP, PARK = "pick", "drop", "park"  # the station sets the generated suite's order stream names
GRID = 0.25  # metres: derived sizes and positions are multiples of it
_SLACK = 0.2  # metres of clearance beyond the swept diameter
_MIN_GAP = 0.75  # metres between junctions on a lane: well over 10 connection tolerances (no near-miss lint)


def _up(value: float) -> float:
    return math.ceil(round(value / GRID, 9)) * GRID


def _down(value: float) -> float:
    return math.floor(round(value / GRID, 9)) * GRID


@dataclass(frozen=True, slots=True)
class Sizes:
    """The layout's spacing for a vehicle size, in metres.

    Attributes:
        clearance: Connector length, and the least distance between a station and any lane it does not
            touch, between two stations, and between neighbouring rungs.
        station: A station segment's length.
        gap: The least distance between two junctions on one lane.
    """

    clearance: float
    station: float
    gap: float

    @property
    def depth(self) -> float:
        """A ladder's depth: connector, station, connector."""
        return 2 * self.clearance + self.station


def sizes_for(vehicle_length: float, vehicle_width: float) -> Sizes:
    """The spacing that keeps vehicles of this size on neighbouring places from conflicting."""
    diameter = math.hypot(vehicle_length, vehicle_width)  # 2·r, r the swept radius
    clearance = max(1.0, _up(diameter + _SLACK))
    return Sizes(clearance, max(clearance, _up(vehicle_length + 0.4)), max(_MIN_GAP, _up(clearance / 2)))


@dataclass(frozen=True, slots=True)
class WarehouseLayout:
    """A generated warehouse's segments and station sets.

    Attributes:
        segments: Every segment, by ascending id (1, 2, ...).
        stations: The station sets ``pick``, ``drop`` and ``park``, each by ascending segment id.
        parking: The parking places' segment ids in the order vehicles are put on them.
        sizes: The spacing used.
    """

    segments: tuple[Segment, ...]
    stations: Mapping[str, tuple[Station, ...]]
    parking: tuple[int, ...]
    sizes: Sizes


@dataclass(frozen=True, slots=True)
class _Frame:
    """A lane's frame: ``t`` along its flow from ``origin``, ``n`` off it (to the side its rows are on)."""

    origin: Point
    flow: Point
    side: Point

    def at(self, t: float, n: float = 0.0) -> Point:
        (ox, oy), (fx, fy), (sx, sy) = self.origin, self.flow, self.side
        return (ox + t * fx + n * sx, oy + t * fy + n * sy)

    def off(self, n: float) -> _Frame:
        return _Frame(self.at(0.0, n), self.flow, self.side)


@dataclass(frozen=True, slots=True)
class _Row:
    """One ladder: its rungs' positions along the lane it hangs from."""

    entry: float | None  # a rung without a station, when another row hangs from this one's back lane
    bays: tuple[float, ...]
    back: float  # the return rung

    @property
    def rungs(self) -> tuple[float, ...]:
        return (*((self.entry,) if self.entry is not None else ()), *self.bays, self.back)


class _Drawing:
    """Segments as they are drawn, numbered 1, 2, ... in drawing order."""

    def __init__(self, two_way_lanes: bool) -> None:
        self.lines: list[tuple[tuple[Point, Point], Direction, str | None]] = []
        self.sets: dict[str, list[int]] = {PICK: [], DROP: [], PARK: []}
        self.lane_direction = Direction.BOTH if two_way_lanes else Direction.FORWARD

    def add(self, a: Point, b: Point, *, lane: bool = False, station: str | None = None) -> int:
        """A straight segment from ``a`` to ``b``; a ``lane`` follows the site's directions, anything else
        is one-way from ``a`` to ``b``; a ``station`` joins that set (and is named after it)."""
        name = None
        if station is not None:
            self.sets[station].append(len(self.lines) + 1)
            name = f"{station}-{len(self.sets[station])}"
        self.lines.append(((a, b), self.lane_direction if lane else Direction.FORWARD, name))
        return len(self.lines)

    def lane(self, frame: _Frame, length: float, cuts: Iterable[float], *, lane: bool = True) -> None:
        """A lane from ``t = 0`` to ``length``, cut into segments at ``cuts`` (junctions)."""
        points = sorted({0.0, length, *cuts})
        for a, b in pairwise(points):
            self.add(frame.at(a), frame.at(b), lane=lane)

    def segments(self) -> tuple[Segment, ...]:
        """The segments, moved so that the drawing is centred on the origin (on the grid)."""
        xs = [x for (a, b), _, _ in self.lines for x, _ in (a, b)]
        ys = [y for (a, b), _, _ in self.lines for _, y in (a, b)]
        dx, dy = _down((min(xs) + max(xs)) / 2), _down((min(ys) + max(ys)) / 2)
        return tuple(
            Segment(
                index + 1,
                Shape.STRAIGHT,
                direction,
                ((a[0] - dx, a[1] - dy), (b[0] - dx, b[1] - dy)),
                (name,) if name else (),
            )
            for index, ((a, b), direction, name) in enumerate(self.lines)
        )


def warehouse_layout(options: WarehouseOptions) -> WarehouseLayout:
    """The segments and station sets of the warehouse ``options`` describe (see the module docstring).

    Raises [`GenerateError`][fleetsim.generate.GenerateError] when the stations do not fit: aisles too
    close for the lay-bys, too short for their share of pick stations, cross aisles too short for the
    dock.
    """
    sizes = sizes_for(options.vehicle_length, options.vehicle_width)
    _check_spacing(options, sizes)
    length, spacing, count = float(options.aisle_length), float(options.aisle_spacing), options.aisles
    width = (count - 1) * spacing
    aisle_x = [i * spacing for i in range(count)]
    lay_bys = _lay_by_positions(options, sizes)
    top = _Frame((0.0, length), (1.0, 0.0), (0.0, 1.0))  # flows right, the dock above it
    bottom = _Frame((width, 0.0), (-1.0, 0.0), (0.0, -1.0))  # flows left, the parking below it
    dock = _rows(width, aisle_x, options.drop_stations, sizes, spread=True)
    if dock is None:
        raise _no_room("drop_stations", options.drop_stations, "drop stations", "top cross aisle", options)
    parking = _rows(width, [width - x for x in aisle_x], options.parking_places, sizes, spread=False)
    if parking is None:
        option = "parking" if options.parking is not None else "vehicles"
        raise _no_room(option, options.parking_places, "parking places", "bottom cross aisle", options)

    drawing = _Drawing(two_way_lanes=not options.one_way)
    for i, x in enumerate(aisle_x):
        up = not options.one_way or (i % 2 == 0 and i != count - 1)  # the last aisle closes the loop: down
        aisle = _Frame((x, 0.0), (0.0, 1.0), (1.0, 0.0)) if up else _Frame((x, length), (0.0, -1.0), (1.0, 0.0))
        places = lay_bys[i] if up else [length - t - sizes.station for t in reversed(lay_bys[i])]
        drawing.lane(aisle, length, [t + d for t in places for d in (0.0, sizes.station)])
        for t in places:
            c, s = sizes.clearance, sizes.station
            drawing.add(aisle.at(t), aisle.at(t, c))
            drawing.add(aisle.at(t, c), aisle.at(t + s, c), station=PICK)
            drawing.add(aisle.at(t + s, c), aisle.at(t + s))
    drawing.lane(top, width, [*aisle_x, *dock[0].rungs])
    drawing.lane(bottom, width, [*(width - x for x in aisle_x), *parking[0].rungs])
    _draw_rows(drawing, top, dock, DROP, sizes)
    _draw_rows(drawing, bottom, parking, PARK, sizes)

    segments = drawing.segments()
    stations = MappingProxyType(
        {name: tuple(Station(sid) for sid in sorted(ids)) for name, ids in sorted(drawing.sets.items())}
    )
    return WarehouseLayout(segments, stations, tuple(drawing.sets[PARK]), sizes)


def _check_spacing(options: WarehouseOptions, sizes: Sizes) -> None:
    least = 2 * sizes.clearance  # a lay-by beside the aisle, and a clearance to the next aisle
    if options.aisle_spacing < least:
        size = f"{options.vehicle_length:g} x {options.vehicle_width:g} m"
        reason = (
            f"must be at least {least:g} m for vehicles of {size}: a pick lay-by {sizes.clearance:g} m beside "
            f"each aisle and {sizes.clearance:g} m of clearance to the next"
        )
        raise GenerateError("aisle_spacing", options.aisle_spacing, reason)


def _lay_by_positions(options: WarehouseOptions, sizes: Sizes) -> list[list[float]]:
    """Per aisle, where its pick lay-bys leave it (metres from its bottom end), spread evenly."""
    c, s = sizes.clearance, sizes.station
    share, extra = divmod(options.pick_stations, options.aisles)
    positions: list[list[float]] = []
    for i in range(options.aisles):
        k = share + (1 if i < extra else 0)
        free = _down((options.aisle_length - 2 * c - k * s) / (k + 1)) if k else 0.0
        if k and (free < 0 or (k > 1 and free < c)):
            least = 2 * c + k * s + ((k + 1) * c if k > 1 else 0.0)
            reason = (
                f"puts {k} pick stations beside an aisle, which takes aisles of at least {least:g} m "
                f"(aisle_length is {options.aisle_length:g}); give more aisles, longer ones, or fewer pick stations"
            )
            raise GenerateError("pick_stations", options.pick_stations, reason)
        positions.append([c + free + j * (s + free) for j in range(k)])
    return positions


def _place(lo: float, hi: float, blocked: list[float], count: int, pitch: float, gap: float) -> list[float]:
    """Up to ``count`` positions from ``lo`` up to ``hi``, ``pitch`` apart or more, each at least ``gap``
    from every ``blocked`` position (a junction already on the lane)."""
    placed: list[float] = []
    t = lo
    while len(placed) < count:
        moved = True
        while moved:
            moved = False
            for b in blocked:
                if abs(t - b) < gap:
                    t, moved = b + gap, True
        if t > hi:
            break
        placed.append(t)
        t += pitch
    return placed


def _rows(length: float, junctions: list[float], wanted: int, sizes: Sizes, *, spread: bool) -> list[_Row] | None:
    """Ladders for ``wanted`` stations along a lane of ``length`` with ``junctions``: the first hangs
    from the lane, each next one from the previous one's back lane. ``None`` when they do not fit."""
    pitch, gap = sizes.clearance, sizes.gap
    lo, hi, blocked = 0.0, length, sorted({0.0, length, *junctions})
    rows: list[_Row] = []
    while True:
        room = _place(lo, hi - gap, blocked, wanted + 2, pitch, gap)
        if len(room) >= wanted + 1:  # the last row: the stations and the return rung
            if spread and not rows and wanted > 0:
                wide = _down((hi - lo - 2 * gap) / wanted)
                spaced = _place(lo, hi - gap, blocked, wanted + 1, wide, gap) if wide > pitch else []
                room = spaced if len(spaced) == wanted + 1 else room
            room = room[: wanted + 1]
            rows.append(_Row(None, tuple(room[:-1]), room[-1]))
            return rows
        room = _place(lo, hi - gap, blocked, int((hi - lo) / pitch) + 1, pitch, gap)  # as many as fit
        if len(room) < 3:  # an entry rung, a station and a return rung at least
            return None
        rows.append(_Row(room[0], tuple(room[1:-1]), room[-1]))
        wanted -= len(room) - 2
        lo, hi, blocked = room[0], room[-1], room


def _draw_rows(drawing: _Drawing, lane: _Frame, rows: list[_Row], station: str, sizes: Sizes) -> None:
    c, s, depth = sizes.clearance, sizes.station, sizes.depth
    for index, row in enumerate(rows):
        main, back = lane.off(index * depth), lane.off((index + 1) * depth)
        if row.entry is not None:
            drawing.add(main.at(row.entry), back.at(row.entry))
        for t in row.bays:
            drawing.add(main.at(t), main.at(t, c))
            drawing.add(main.at(t, c), main.at(t, c + s), station=station)
            drawing.add(main.at(t, c + s), back.at(t))
        drawing.add(back.at(row.back), main.at(row.back))
        below = rows[index + 1].rungs if index + 1 < len(rows) else ()
        start = row.rungs[0]  # the back lane runs from the first rung to the return rung
        cuts = [t - start for t in (*row.rungs, *below)]
        drawing.lane(_Frame(back.at(start), lane.flow, lane.side), row.back - start, cuts, lane=False)


def _no_room(option: str, value: int, places: str, where: str, options: WarehouseOptions) -> GenerateError:
    width = (options.aisles - 1) * options.aisle_spacing
    reason = (
        f"asks for {value} {places}, more than fit beyond the {where} ({width:g} m long: {options.aisles} aisles "
        f"{options.aisle_spacing:g} m apart), even in rows one behind the other; give more aisles or a wider "
        "aisle spacing"
    )
    return GenerateError(option, value, reason)
