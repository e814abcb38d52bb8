"""``orders.csv``: transport orders, one row per order, read strictly and with located errors (issue 45).

```text
order_id,release,deadline,stops,dwell,vehicle_types,priority
o1,0,900,4>17,20>10,,
o2,00:05:00,,4>17:reverse>9,15,agv,2
```

- ``order_id`` (required): the order's id, unique in the file.
- ``stops`` (required): segment ids joined by ``>``, in the order they are served; each may end in
  ``:forward`` or ``:reverse``, the progress direction the vehicle must arrive with.
- ``dwell``: seconds the vehicle stands at each stop: one value for every stop, or one per stop joined
  by ``>``; empty: 0.
- ``release``: when the order appears, seconds or ``hh:mm:ss`` (empty: 0); rows come in release order.
- ``deadline``: when its last stop must be served, seconds or ``hh:mm:ss``, after the release; empty: none.
- ``vehicle_types``: the types allowed to carry it, separated by spaces or ``;`` (empty: any).
- ``priority``: a whole number, higher is more urgent (empty: 0).

The conventions are those of ``vehicles.csv`` and ``tasks.csv`` (:mod:`fleetsim.load.tables.table`):
header required, comments and blank rows skipped, every bad cell of every row reported at once.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import TypeVar

from fleetsim.enums import Progress
from fleetsim.errors import ScenarioFileError
from fleetsim.layout.segment import Segment
from fleetsim.layout.segment_ids import not_in_map
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.tables.table import Columns, Row, read_table
from fleetsim.orders import Order, Stop

__all__ = ["ORDERS_FILE_NAME", "ORDER_COLUMNS", "collect_orders", "read_orders"]

ORDERS_FILE_NAME = "orders.csv"
ORDER_COLUMNS = Columns(("order_id", "stops"), ("release", "deadline", "dwell", "vehicle_types", "priority"))

T = TypeVar("T")
_STOP = re.compile(r"(?P<segment>[0-9]+)(?::(?P<progress>[A-Za-z]*))?")
_CLOCK = re.compile(r"(?P<h>[0-9]+):(?P<m>[0-5][0-9]):(?P<s>[0-5][0-9](?:\.[0-9]*)?)")
_SECONDS = re.compile(r"[0-9]+(?:\.[0-9]*)?|\.[0-9]+")
_INTEGER = re.compile(r"[+-]?[0-9]+")


def read_orders(
    path: Path | str,
    segments: Mapping[int, Segment],
    vehicle_types: Collection[str] | None = None,
) -> tuple[Order, ...]:
    """The orders of ``orders.csv`` in file order (each with its ``line``).

    ``vehicle_types`` are the type names a row may allow (``None``: any name). Every row is checked:
    one error is raised as itself (a [`ScenarioFileError`][fleetsim.errors.ScenarioFileError]),
    several as one [`LoadErrors`][fleetsim.errors.LoadErrors].
    """
    errors = ErrorCollector()
    orders = collect_orders(Path(path), segments, vehicle_types, errors)
    errors.raise_if_any()
    return orders


def collect_orders(
    path: Path,
    segments: Mapping[int, Segment] | None,
    vehicle_types: Collection[str] | None,
    errors: ErrorCollector,
) -> tuple[Order, ...]:
    """Every row of ``orders.csv`` checked, each bad cell's error added to ``errors``; the orders of the
    rows without one. Without ``segments`` (the map did not load) stops are checked for their form only."""
    rows = read_table(path, ORDER_COLUMNS, errors)
    if rows is None:
        return ()
    types = {name.casefold(): name for name in vehicle_types} if vehicle_types is not None else None
    first_line: dict[str, int] = {}  # order id → the line of the row that has it
    latest: tuple[float, Row] | None = None  # the latest release so far, and its row
    orders = []
    for row in rows:
        cells = _Cells(errors)
        order_id = cells.read(_order_id, row, first_line)
        stops = cells.read(_stops, row, segments)
        dwells = cells.read(_dwells, row, len(stops) if stops is not None else None)
        release = cells.read(_time, row, "release")
        deadline = cells.read(_time, row, "deadline")
        if release is not None and latest is not None and release < latest[0]:
            cells.read(_out_of_order, row, release, latest)
        if release is not None and (latest is None or release >= latest[0]):
            latest = (release, row)
        if deadline is not None and release is not None and deadline <= release:
            cells.read(_deadline_before_release, row, deadline, release)
        allowed = cells.read(_vehicle_types, row, types)
        priority = cells.read(_priority, row)
        if cells.ok and order_id is not None and stops is not None and dwells is not None and segments is not None:
            served = tuple(
                Stop(segment, progress, dwell) for (segment, progress), dwell in zip(stops, dwells, strict=True)
            )
            orders.append(Order(order_id, served, release or 0.0, deadline, allowed, priority or 0, row.line))
    return tuple(orders)


class _Cells:
    """Reads one row's cells each on its own: a bad cell is collected and reads as ``None``."""

    def __init__(self, errors: ErrorCollector) -> None:
        self.errors = errors
        self.ok = True

    def read(self, read: Callable[..., T], row: Row, *args: object) -> T | None:
        try:
            return read(row, *args)
        except ScenarioFileError as error:
            self.errors.add(error)
            self.ok = False
            return None


def _order_id(row: Row, first_line: dict[str, int]) -> str:
    order_id = row.get("order_id")
    if not order_id:
        raise row.error("order_id", "missing: every order needs an id")
    if order_id in first_line:
        raise row.error("order_id", f"order id {order_id!r} is already used on line {first_line[order_id]}")
    first_line[order_id] = row.line
    return order_id


def _stops(row: Row, segments: Mapping[int, Segment] | None) -> list[tuple[int, Progress | None]]:
    text = row.get("stops")
    if not text:
        raise row.error("stops", "missing: an order needs at least one stop (segment ids joined by '>', e.g. 4>17)")
    stops = []
    for number, part in enumerate(text.split(">"), start=1):
        match = _STOP.fullmatch(part.strip())
        if match is None:
            msg = (
                f"stop {number} of {text!r} is {part.strip()!r}: a stop is a segment id, optionally with "
                "':forward' or ':reverse' (e.g. 4>17:reverse)"
            )
            raise row.error("stops", msg)
        segment = int(match["segment"])
        progress = None
        if match["progress"] is not None:
            word = match["progress"].lower()
            if word not in ("forward", "reverse"):
                msg = f"stop {number} of {text!r} arrives {match['progress']!r}; it must be ':forward' or ':reverse'"
                raise row.error("stops", msg)
            progress = Progress(word)
        if segments is not None and segment not in segments:
            raise row.error("stops", f"stop {number} of {text!r} is on {not_in_map(segment, segments)}")
        stops.append((segment, progress))
    return stops


def _dwells(row: Row, count: int | None) -> list[float]:
    text = row.get("dwell")
    if not text:
        return [0.0] * (count or 0)
    values = []
    for part in text.split(">"):
        value = part.strip()
        if value.startswith("-") and _SECONDS.fullmatch(value[1:]):
            raise row.error("dwell", f"dwell {value!r} is negative; a vehicle stands 0 seconds or more")
        if not _SECONDS.fullmatch(value) or not math.isfinite(float(value)):
            raise row.error("dwell", f"dwell {value!r} of {text!r} is not a number of seconds")
        values.append(float(value))
    if count is None:
        return values
    if len(values) == 1:
        return values * count
    if len(values) != count:
        msg = f"{text!r} gives {len(values)} dwell times for {count} stops; give one for every stop, or one per stop"
        raise row.error("dwell", msg)
    return values


def _time(row: Row, column: str) -> float | None:
    """Seconds or ``hh:mm:ss``; ``None`` for an empty cell."""
    text = row.get(column)
    if not text:
        return None
    clock = _CLOCK.fullmatch(text)
    if clock is not None:
        return int(clock["h"]) * 3600 + int(clock["m"]) * 60 + float(clock["s"])
    if _SECONDS.fullmatch(text):
        value = float(text)
        if math.isfinite(value):
            return value
    if text.startswith("-"):
        raise row.error(column, f"{column} {text!r} is negative; times count from the start of the run (0)")
    raise row.error(column, f"{column} {text!r} is not a time: give seconds (300) or hh:mm:ss (00:05:00)")


def _out_of_order(row: Row, release: float, latest: tuple[float, Row]) -> None:
    before, other = latest
    msg = (
        f"release {row.get('release')!r} ({release:g} s) is before the release {other.get('release')!r} "
        f"({before:g} s) of order {other.get('order_id')!r} on line {other.line}; rows must be in release order"
    )
    raise row.error("release", msg)


def _deadline_before_release(row: Row, deadline: float, release: float) -> None:
    msg = f"deadline {row.get('deadline')!r} ({deadline:g} s) is not after the release ({release:g} s)"
    raise row.error("deadline", msg)


def _vehicle_types(row: Row, types: Mapping[str, str] | None) -> tuple[str, ...] | None:
    text = row.get("vehicle_types")
    names = [name for name in re.split(r"[;\s]+", text) if name]
    if not names:
        return None
    if types is None:
        return tuple(dict.fromkeys(names))
    allowed = []
    for name in names:
        if name.casefold() not in types:
            known = list(types.values())
            msg = f"vehicle type {name!r} is not defined{did_you_mean(name, known)} (known: {', '.join(known)})"
            raise row.error("vehicle_types", msg)
        allowed.append(types[name.casefold()])
    return tuple(dict.fromkeys(allowed))


def _priority(row: Row) -> int:
    text = row.get("priority")
    if not text:
        return 0
    if not _INTEGER.fullmatch(text):
        raise row.error("priority", f"priority {text!r} is not a whole number")
    return int(text)
