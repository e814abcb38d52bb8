"""Station sets of a LIF layout: its ``stations``, each at the segments that end at its interaction nodes.

A LIF station (``stationId``, ``interactionNodeIds``, and descriptive members: ``stationName``,
``stationDescription``, ``stationHeight``, ``stationPosition``) is where a vehicle interacts with the site
(loads, unloads, charges). LIF gives stations no type, so fleetsim names two kinds of sets:

- ``stations``: every station of the layout;
- one set per station, named by its ``stationId`` (``from: [dock-north]`` in a suite draws stops there).

A station's segments are those a vehicle ends at one of its interaction nodes on: a one-way segment whose
end node it is, a two-way segment at either of whose nodes it is. Each :class:`~fleetsim.orders.Station`
is named after its ``stationId``. An interaction node that is no node of the layout is an error; a
station that no usable edge of the chosen robot type leads to is noted (``not-modelled``).
"""

from __future__ import annotations

from fleetsim.enums import Traverse
from fleetsim.layout.segment import Segment
from fleetsim.load.common.closest import did_you_mean
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.common.import_notes import ImportNotes
from fleetsim.load.common.json_at import JsonAt
from fleetsim.load.common.stations import StationSets, station_sets
from fleetsim.orders import Station

__all__ = ["ALL_STATIONS", "lif_station_sets"]

ALL_STATIONS = "stations"  # the set of every station of the layout
_DESCRIPTIVE = {"stationName", "stationDescription", "stationHeight", "stationPosition"}


def lif_station_sets(layout: JsonAt, nodes: set[str], segments: tuple[Segment, ...], notes: ImportNotes) -> StationSets:
    """The station sets of ``layout`` (``nodes``: its node ids) over its ``segments``; every broken
    station is reported (several as one :class:`~fleetsim.errors.LoadErrors`)."""
    listed = layout.get("stations")
    if listed is None:
        return station_sets(())
    ending = _segments_ending_at(segments)
    errors = ErrorCollector()
    members: list[tuple[str, Station]] = []
    seen: dict[str, str] = {}  # station id → the pointer of the station that has it
    for at in listed.items():
        with errors.collecting():
            station_id = at.need("stationId").identifier()
            if station_id in seen:
                raise at.need("stationId").error(f"stationId {station_id!r} is used twice: by {seen[station_id]} too")
            seen[station_id] = at.pointer
            found: set[int] = set()
            for node in at.need("interactionNodeIds").items(allow_empty=False):
                node_id = node.identifier()
                if node_id not in nodes:
                    hint = did_you_mean(node_id, sorted(nodes))
                    raise node.error(f"station {station_id!r}: node {node_id!r} is not a node of this layout{hint}")
                found.update(ending.get(node_id, ()))
            for key in at.keys():  # noqa: SIM118 - JsonAt.keys(), not a dict's
                if key not in ("stationId", "interactionNodeIds") and key not in _DESCRIPTIVE:
                    notes.note("not-modelled", f"station attribute {key!r}", f"{at.pointer}/{key}")
            if not found:
                notes.note("not-modelled", "a station no usable edge ends at", f"{at.pointer} ({station_id!r})")
            for segment in sorted(found):
                station = Station(segment, 1.0, station_id)
                members += [(ALL_STATIONS, station), (station_id, station)]
    errors.raise_if_any()
    return station_sets(members)


def _segments_ending_at(segments: tuple[Segment, ...]) -> dict[str, list[int]]:
    """Node id → the segments a vehicle may end at it on, by the segment ends' node ids."""
    ending: dict[str, list[int]] = {}
    for segment in segments:
        if segment.ends is None:
            continue
        first, last = segment.ends
        if segment.allows(Traverse.FORWARD):
            ending.setdefault(last, []).append(segment.id)
        if segment.allows(Traverse.BACKWARD):
            ending.setdefault(first, []).append(segment.id)
    return ending
