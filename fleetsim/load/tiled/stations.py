"""Station sets in a Tiled map: a segment's custom properties ``station`` and ``station_weight``.

``station`` is a string of one or more set names separated by commas (``pick``, ``drop,park``): the
segment is a station of each. ``station_weight`` (a number > 0, default 1) is its weight when stops are
drawn by weight. Both are resolved like ``direction``: a template's value stands unless the instance
sets its own, so a template can make every segment drawn with it a station. An empty ``station`` (a
template's default, say) makes no station. A set name is letters, digits, ``_``, ``.`` or ``-``,
starting with a letter or digit, and is matched exactly (``Pick`` is not ``pick``).
"""

from __future__ import annotations

from collections.abc import Mapping

from fleetsim.errors import Location, MapError
from fleetsim.load.common.stations import SET_NAME
from fleetsim.load.tiled.templates import PropertyValue, as_number
from fleetsim.orders import Station

__all__ = ["STATION_PROPERTIES", "segment_stations", "station_note"]

STATION_PROPERTIES = ("station", "station_weight")


def segment_stations(
    segment: int, properties: Mapping[str, PropertyValue], where: Location
) -> list[tuple[str, Station]]:
    """(set name, station) for each set the segment's ``station`` property names; a bad value raises a
    :class:`MapError` at ``where`` (the file and object)."""
    raw = properties.get("station")
    if raw is None:
        return []
    if not isinstance(raw, str):
        msg = f"the station property is {raw!r}; it must be a string of station set names, e.g. 'pick' or 'drop,park'"
        raise MapError(msg, where)
    names: list[str] = []
    for part in raw.split(","):
        set_name = part.strip()
        if not set_name or set_name in names:
            continue
        if not SET_NAME.fullmatch(set_name):
            msg = (
                f"the station property is {raw!r}: {set_name!r} is not a station set name (letters, digits, "
                "'_', '.' or '-', starting with a letter or digit); separate several names with commas"
            )
            raise MapError(msg, where)
        names.append(set_name)
    if not names:
        return []
    weight = 1.0
    if properties.get("station_weight") is not None:
        weight = as_number(properties["station_weight"], "the station_weight property", where)
        if weight <= 0:
            msg = f"the station_weight property is {properties['station_weight']!r}; it must be a number > 0"
            raise MapError(msg, where)
    return [(set_name, Station(segment, weight)) for set_name in names]


def station_note(geometry: str, properties: Mapping[str, PropertyValue], where: Location) -> str | None:
    """The warning for a ``station`` property on an object that is no segment (a point, say), or ``None``."""
    raw = properties.get("station")
    if not isinstance(raw, str) or not raw.replace(",", " ").strip():
        return None
    return (
        f"{where}: a station property ({raw!r}) on a {geometry}, which is not a segment; ignored "
        "(stations are segments: polylines of class straight, curve, s_curve or path)"
    )
