"""Station sets of an Open-RMF level: vertices whose parameters make them stations, at the lanes ending there.

traffic-editor marks a vertex as a place vehicles work at with parameters (``[type, value]`` each):

| parameter | set |
|---|---|
| ``pickup_dispenser`` (the dispenser's name) | ``pick`` |
| ``dropoff_ingestor`` (the ingestor's name) | ``drop`` |
| ``is_parking_spot: true`` | ``park`` |
| ``is_charger: true`` | ``charge`` |

An empty dispenser or ingestor name, or ``false``, marks nothing. A station vertex's segments are the
lanes of the chosen graph a vehicle ends at it on: a one-way lane whose end vertex it is, a two-way lane
at either end. Each :class:`~fleetsim.orders.Station` is named after its vertex. A station vertex that no
lane of the graph ends at is noted (``not-modelled``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from fleetsim.enums import Direction
from fleetsim.layout.segment import Segment
from fleetsim.load.common.import_notes import ImportNotes
from fleetsim.load.common.stations import StationSets, station_sets
from fleetsim.orders import Station

__all__ = ["STATION_PARAMETERS", "rmf_station_sets", "station_parameter"]

STATION_PARAMETERS = {
    "pickup_dispenser": "pick",
    "dropoff_ingestor": "drop",
    "is_parking_spot": "park",
    "is_charger": "charge",
}


def station_parameter(key: str, value: object) -> str | None:
    """The set a vertex parameter's value puts its vertex in, or ``None``; a ``ValueError`` says what is
    wrong with a value of the wrong type."""
    if key in ("pickup_dispenser", "dropoff_ingestor"):
        if not isinstance(value, str):
            msg = f"{key} is {value!r}; it must be a string (the name of the {key.split('_')[1]})"
            raise ValueError(msg)
        return STATION_PARAMETERS[key] if value.strip() else None
    if not isinstance(value, bool):
        raise ValueError(f"{key} is {value!r}; it must be true or false")
    return STATION_PARAMETERS[key] if value else None


def rmf_station_sets(
    marked: Mapping[int, Sequence[str]],
    labels: Sequence[str],
    segments: Sequence[tuple[Segment, int, int]],
    notes: ImportNotes,
    where: Callable[[int], str],
) -> StationSets:
    """The station sets of the vertices ``marked`` (vertex index → its sets) over ``segments`` (each with
    its start and end vertex index); ``labels`` name the vertices, ``where`` says where a vertex is written."""
    ending: dict[int, list[int]] = {}
    for segment, start, end in segments:
        ending.setdefault(end, []).append(segment.id)
        if segment.direction is Direction.BOTH:
            ending.setdefault(start, []).append(segment.id)
    members: list[tuple[str, Station]] = []
    for vertex in sorted(marked):
        if not ending.get(vertex):
            notes.note(
                "not-modelled", "a station vertex no lane of the graph ends at", f"{where(vertex)} ({labels[vertex]!r})"
            )
        for segment_id in ending.get(vertex, ()):
            members += [(set_name, Station(segment_id, 1.0, labels[vertex])) for set_name in marked[vertex]]
    return station_sets(members)
