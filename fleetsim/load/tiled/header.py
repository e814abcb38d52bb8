"""The header of a Tiled map: its size in pixels and metres per pixel, the facts the world transform needs.

Each bad header value is collected (with the objects' errors, see :mod:`fleetsim.load.tiled.reader`) and a
stand-in used, so that one load reports the header's problems and every object's together.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from fleetsim.errors import Location, MapError
from fleetsim.load.common.collect import ErrorCollector
from fleetsim.load.tiled.templates import PropertyValue, as_bool, as_int, as_number

__all__ = ["MapHeader", "read_header"]


@dataclass(frozen=True, slots=True)
class MapHeader:
    """The map-level facts the world transform needs."""

    width_px: float
    height_px: float
    meters_per_pixel: float


_LARGEST = 2**31 - 1  # Tiled keeps a map's and a tile's sizes in signed 32-bit integers


def _positive_int(raw: object, name: str, where: Location) -> int:
    if raw is None:
        raise MapError(f"map attribute {name!r} is missing", where)
    value = as_int(raw, name, where)
    if value <= 0:
        raise MapError(f"{name} is {raw!r}; it must be a positive integer", where)
    if value > _LARGEST:
        raise MapError(f"{name} is {raw!r}; it must be at most {_LARGEST} (Tiled keeps it in 32 bits)", where)
    return value


def _check_orientation(attrs: Mapping[str, object], where: Location) -> None:
    orientation = attrs.get("orientation")
    if orientation != "orthogonal":
        msg = f"the map's orientation is {orientation!r}; fleetsim reads orthogonal maps only"
        raise MapError(msg, where)


def _check_finite(attrs: Mapping[str, object], where: Location) -> None:
    infinite = attrs.get("infinite", False)
    if as_bool(infinite, "infinite", where):
        msg = f"the map is infinite (infinite = {infinite!r}); fleetsim reads fixed-size maps only (untick Infinite in Tiled's map properties)"
        raise MapError(msg, where)


def _scale(properties: Mapping[str, PropertyValue], tile_width: int, where: Location) -> float:
    raw_scale = properties.get("meters_per_pixel")
    if raw_scale is None:
        return 1.0 / tile_width  # default: one tile is one metre
    scale = as_number(raw_scale, "meters_per_pixel", where)
    if scale <= 0:
        raise MapError(f"the map property meters_per_pixel is {raw_scale!r}; it must be a positive number", where)
    return scale


def read_header(
    attrs: Mapping[str, object], properties: Mapping[str, PropertyValue], path: Path, errors: ErrorCollector
) -> MapHeader:
    """The header; each bad attribute is collected and a stand-in value used, so objects still get checked."""
    where = Location(path)
    with errors.collecting():
        _check_orientation(attrs, where)
    with errors.collecting():
        _check_finite(attrs, where)
    sizes = [1, 1, 1, 1]  # stand-ins for a bad value (the load fails anyway)
    for index, name in enumerate(("width", "height", "tilewidth", "tileheight")):
        with errors.collecting():
            sizes[index] = _positive_int(attrs.get(name), name, where)
    width, height, tile_width, tile_height = sizes
    scale = 1.0
    with errors.collecting():
        scale = _scale(properties, tile_width, where)
    return MapHeader(float(width * tile_width), float(height * tile_height), scale)
