"""A suite entry's order keys (issue 45): ``orders``, ``order_stream``, ``stations``, ``shift``, ``dispatcher``.

The schema has checked each value's form (durations included); this module checks what it cannot say,
each problem at its YAML path and line: a stream's arrivals name exactly one process, an interval or a
duration is more than 0, ``[min, max]`` ranges are ordered, the warm-up is shorter than the shift, a
stream's vehicle types are the suite's, a station set lists each segment once, and the ``orders`` file
exists. Every problem of the entry is reported (several as one :class:`~fleetsim.errors.SuiteErrors`).

``defaults`` may hold every key but ``orders``. An entry's ``order_stream`` and ``shift`` replace the
defaults' key by key, its ``stations`` set by set, its ``dispatcher`` the defaults' one. A scenario
without ``orders`` reads the ``orders.csv`` of its ``dir`` when there is one.

What needs the map (a station set's segments exist, the sets a stream draws from are defined) is checked
when the scenario is loaded, at the places this module keeps (:class:`OrderSetup`).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

from fleetsim.enums import Progress
from fleetsim.errors import Location, SuiteError
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.durations import duration_seconds
from fleetsim.load.common.stations import NO_STATIONS, StationSets, station_sets
from fleetsim.load.common.yaml_source import Locate
from fleetsim.load.suites.schema import dotted_path, raise_suite_errors, suite_error
from fleetsim.load.tables.orders import ORDERS_FILE_NAME
from fleetsim.orders import Arrivals, OrderStream, Shift, Station, StopDraw

__all__ = ["DEFAULT_ORDER_KEYS", "ORDER_KEYS", "OrderSetup", "Place", "order_setup"]

ORDER_KEYS = ("orders", "order_stream", "stations", "shift", "dispatcher")
DEFAULT_ORDER_KEYS = ORDER_KEYS[1:]  # every one but ``orders`` may be a default
_PROCESSES = ("poisson", "interval", "pool")

YamlPath = tuple[Hashable, ...]
TypeName = Callable[[str, YamlPath], str]  # a vehicle type's canonical name, or a SuiteError at the path


@dataclass(frozen=True, slots=True)
class Place:
    """Where a suite says something: its YAML path (``scenarios[0].stations.pick[1]``) and location."""

    path: str
    location: Location

    def error(self, problem: str) -> SuiteError:
        return SuiteError(f"{self.path}: {problem}", self.location)


@dataclass(frozen=True, slots=True)
class OrderSetup:
    """What a suite entry says of orders, stations, the shift and its dispatcher (each optional).

    Attributes:
        orders_path: The ``orders.csv`` to read, or ``None``.
        order_stream: The orders to generate as the run goes, or ``None``.
        stations: The suite's own station sets (over the map's: a set of the same name replaces it).
        shift: The run as a shift, or ``None``.
        dispatcher: The dispatcher spec (``module:attr``), or ``None``.
        stream_from: Where each of the stream's stop draws names its station sets (``from``).
        station_items: Where each segment of each of the suite's station sets is listed, by set name.
    """

    orders_path: Path | None = None
    order_stream: OrderStream | None = None
    stations: StationSets = field(default_factory=lambda: NO_STATIONS)
    shift: Shift | None = None
    dispatcher: str | None = None
    stream_from: tuple[Place, ...] = ()
    station_items: Mapping[str, Mapping[int, Place]] = field(default_factory=lambda: MappingProxyType({}))


def order_setup(
    entry: Mapping[str, Any],
    defaults: Mapping[str, Any],
    root: Path,
    folder: Path | None,
    locate: Locate,
    where: YamlPath,
    type_name: TypeName,
) -> OrderSetup:
    """The entry's order keys over the defaults' (both schema-checked); ``root`` is the suite's folder,
    ``folder`` the entry's ``dir`` (or ``None``). Every problem is raised (several as one SuiteErrors)."""
    reader = _Reader(locate)
    orders_path = reader.orders_path(entry, root, folder, where)
    stream: OrderStream | None = None
    stream_from: tuple[Place, ...] = ()
    block = _merged(entry, defaults, "order_stream", where)
    if block is not None:
        with reader.errors.collecting():
            stream, stream_from = reader.stream(block, type_name)
    shift = None
    block = _merged(entry, defaults, "shift", where)
    if block is not None:
        with reader.errors.collecting():
            shift = reader.shift(block)
    stations, items = reader.stations(entry, defaults, where)
    raise_suite_errors(reader.errors)
    return OrderSetup(
        orders_path=orders_path,
        order_stream=stream,
        stations=stations,
        shift=shift,
        dispatcher=entry.get("dispatcher", defaults.get("dispatcher")),
        stream_from=stream_from,
        station_items=items,
    )


@dataclass(frozen=True, slots=True)
class _Block:
    """A merged block: its values by key, the YAML path of each value, and the block's own path."""

    values: Mapping[str, Any]
    paths: Mapping[str, YamlPath]
    path: YamlPath


def _merged(entry: Mapping[str, Any], defaults: Mapping[str, Any], key: str, where: YamlPath) -> _Block | None:
    """The defaults' block ``key`` with the entry's keys over it, or ``None`` when neither has one."""
    if key not in entry and key not in defaults:
        return None
    values: dict[str, Any] = {}
    paths: dict[str, YamlPath] = {}
    for source, prefix in ((defaults, ("defaults", key)), (entry, (*where, key))):
        for name, value in source.get(key, {}).items():
            values[name] = value
            paths[name] = (*prefix, name)
    return _Block(values, paths, (*where, key) if key in entry else ("defaults", key))


class _Reader:
    """Reads the blocks, every problem located and collected."""

    def __init__(self, locate: Locate) -> None:
        self.locate = locate
        self.errors = ErrorCollector()

    def place(self, path: YamlPath) -> Place:
        return Place(dotted_path(path), self.locate(path))

    def error(self, problem: str, path: YamlPath) -> SuiteError:
        return suite_error(problem, path, self.locate(path))

    def seconds(self, value: Any, path: YamlPath, *, positive: bool = False) -> float:
        try:
            seconds = duration_seconds(value)
        except ValueError as problem:
            raise self.error(str(problem), path) from None
        if positive and seconds <= 0:
            raise self.error(f"{value!r} must be more than 0 seconds", path)
        return seconds

    def range_of(self, value: Any, path: YamlPath, read: Callable[[Any, YamlPath], float]) -> tuple[float, float]:
        """A fixed value or a ``[min, max]`` pair (in order), each item read by ``read``."""
        if not isinstance(value, list):
            single = read(value, path)
            return single, single
        low, high = read(value[0], (*path, 0)), read(value[1], (*path, 1))
        if low > high:
            raise self.error(f"{value!r} must be [min, max] with min <= max", path)
        return low, high

    # -- orders.csv -----------------------------------------------------------------------------

    def orders_path(self, entry: Mapping[str, Any], root: Path, folder: Path | None, where: YamlPath) -> Path | None:
        if "orders" in entry:
            path: Path = root / str(entry["orders"])
            if not path.is_file():
                here = (*where, "orders")
                self.errors.add(self.error(f"no such file: {str(path)!r}", here))
            return path
        found: Path | None = folder / ORDERS_FILE_NAME if folder is not None else None
        if found is not None and found.is_file():
            return found
        return None

    # -- order_stream ---------------------------------------------------------------------------

    def stream(self, block: _Block, type_name: TypeName) -> tuple[OrderStream, tuple[Place, ...]]:
        values, paths = block.values, block.paths
        missing = [key for key in ("arrivals", "stops") if key not in values]
        if missing:
            needed = " and ".join(repr(key) for key in missing)
            raise self.error(
                f"an order stream needs {needed} (when orders are released, where their stops are)", block.path
            )
        errors = ErrorCollector()
        arrivals = None
        with errors.collecting():
            arrivals = self.arrivals(values["arrivals"], paths["arrivals"])
        draws = []
        for index, raw in enumerate(values["stops"]):
            with errors.collecting():
                draws.append(self.draw(raw, (*paths["stops"], index)))
        deadline = None
        if "deadline" in values:
            with errors.collecting():
                deadline = self.seconds(values["deadline"], paths["deadline"], positive=True)
        types = []
        for index, name in enumerate(values.get("vehicle_types", ())):
            with errors.collecting():
                types.append(type_name(name, (*paths["vehicle_types"], index)))
        raise_suite_errors(errors)
        assert arrivals is not None  # else raised
        stream = OrderStream(
            seed=values.get("seed", 0),
            arrivals=arrivals,
            stops=tuple(draws),
            deadline=deadline,
            vehicle_types=tuple(types) if "vehicle_types" in values else None,
            priority=values.get("priority", 0),
            limit=values.get("limit"),
        )
        froms = tuple(self.place((*paths["stops"], index, "from")) for index in range(len(draws)))
        return stream, froms

    def arrivals(self, raw: Mapping[str, Any], path: YamlPath) -> Arrivals:
        given = [key for key in _PROCESSES if key in raw]
        if len(given) != 1:
            found = f"it has {' and '.join(map(repr, given))}" if given else "it has none"
            msg = (
                "give exactly one of 'poisson' (orders per hour), 'interval' (time between releases) or "
                f"'pool' (orders open at once); {found}"
            )
            raise self.error(msg, path)
        (process,) = given
        start = self.seconds(raw.get("start", 0), (*path, "start"))
        until = self.seconds(raw["until"], (*path, "until")) if "until" in raw else None
        if until is not None and until <= start:
            raise self.error(f"{raw['until']!r} ({until:g} s) must be after start ({start:g} s)", (*path, "until"))
        if process == "interval":
            interval = self.seconds(raw["interval"], (*path, "interval"), positive=True)
            return Arrivals("interval", interval=interval, start=start, until=until)
        if process == "poisson":
            return Arrivals("poisson", rate=float(raw["poisson"]), start=start, until=until)
        return Arrivals("pool", open=int(raw["pool"]), start=start, until=until)

    def draw(self, raw: Mapping[str, Any], path: YamlPath) -> StopDraw:
        names = raw["from"] if isinstance(raw["from"], list) else [raw["from"]]
        dwell = self.range_of(raw.get("dwell", 0), (*path, "dwell"), self.seconds)
        count = self.range_of(raw.get("count", 1), (*path, "count"), lambda value, _: int(value))
        progress = raw.get("progress")
        return StopDraw(
            stations=tuple(names),
            weighted=bool(raw.get("weighted", False)),
            dwell=dwell,
            count=(int(count[0]), int(count[1])),
            progress=Progress(progress) if progress is not None else None,
        )

    # -- shift ----------------------------------------------------------------------------------

    def shift(self, block: _Block) -> Shift:
        values, paths = block.values, block.paths
        if "duration" not in values:
            raise self.error("a shift needs a duration (e.g. duration: 8h)", block.path)
        errors = ErrorCollector()
        read: dict[str, float | None] = {"duration": None, "warmup": 0.0, "dispatch_period": None, "stall_after": 300.0}
        for key in read:
            if key in values:
                with errors.collecting():
                    read[key] = self.seconds(values[key], paths[key], positive=key != "warmup")
        duration, warmup = read["duration"], read["warmup"]
        if duration is not None and warmup is not None and warmup >= duration:
            msg = f"{values['warmup']!r} ({warmup:g} s) must be shorter than the shift's duration ({duration:g} s)"
            errors.add(self.error(msg, paths["warmup"]))
        raise_suite_errors(errors)
        assert duration is not None and warmup is not None and read["stall_after"] is not None
        return Shift(duration, warmup, read["dispatch_period"], read["stall_after"], values.get("on_stall", "count"))

    # -- stations -------------------------------------------------------------------------------

    def stations(
        self, entry: Mapping[str, Any], defaults: Mapping[str, Any], where: YamlPath
    ) -> tuple[StationSets, Mapping[str, Mapping[int, Place]]]:
        """The suite's sets (the entry's over the defaults', set by set) and where each item is."""
        written: dict[str, tuple[list[Any], YamlPath]] = {}
        for source, prefix in ((defaults, ("defaults", "stations")), (entry, (*where, "stations"))):
            for name, items in source.get("stations", {}).items():
                written[name] = (items, (*prefix, name))
        members: list[tuple[str, Station]] = []
        places: dict[str, Mapping[int, Place]] = {}
        for name, (items, path) in sorted(written.items()):
            first: dict[int, int] = {}  # segment → the index of the item that lists it
            for index, item in enumerate(items):
                segment = item if isinstance(item, int) else item["segment"]
                weight = 1.0 if isinstance(item, int) else float(item.get("weight", 1.0))
                if segment in first:
                    msg = f"segment {segment} is listed twice in station set {name!r} (first as item {first[segment]})"
                    self.errors.add(self.error(msg, (*path, index)))
                    continue
                first[segment] = index
                members.append((name, Station(segment, weight)))
            places[name] = MappingProxyType({segment: self.place((*path, index)) for segment, index in first.items()})
        return station_sets(members), MappingProxyType(places)
