"""Station sets: the named groups of segments (``pick``, ``drop``, ``park``, ...) order stops are drawn from.

Every map format names them its own way (a Tiled property, LIF stations, Open-RMF vertex parameters) and
a suite may add sets of its own; all of them end up as one mapping, set name → stations, in which each
set lists each segment once, by ascending segment id, and the names come in sorted order: nothing that
depends on the order a file happened to list things in.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from types import MappingProxyType

from fleetsim.orders import Station

__all__ = ["NO_STATIONS", "SET_NAME", "StationSets", "merge_station_sets", "station_sets"]

StationSets = Mapping[str, tuple[Station, ...]]
NO_STATIONS: StationSets = MappingProxyType({})
# What a set name may be: it is written in suites (``from: pick``) and in Tiled properties ("pick,drop").
SET_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")


def station_sets(members: Iterable[tuple[str, Station]]) -> StationSets:
    """Set name → its stations (read-only), from (set name, station) pairs.

    A segment given twice in one set counts once: the first pair given for it stands.
    """
    found: dict[str, dict[int, Station]] = {}
    for name, station in members:
        found.setdefault(name, {}).setdefault(station.segment, station)
    return MappingProxyType(
        {name: tuple(stations[segment] for segment in sorted(stations)) for name, stations in sorted(found.items())}
    )


def merge_station_sets(base: StationSets, over: StationSets) -> StationSets:
    """``base`` with the sets of ``over``: a set of ``over`` replaces the set of ``base`` of that name."""
    merged = {**base, **over}
    return MappingProxyType({name: merged[name] for name in sorted(merged)})
