"""``fleetsim convert``: any loadable map written as a Tiled map (with its station sets, as ``station``
properties) or as a LIF 1.0 file (segments only)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from fleetsim.errors import Location, MapError
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.lif.writer import DEFAULT_ROBOT_TYPE, write_lif
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.load.tiled.writer import write_map

__all__ = ["convert_map"]


def convert_map(
    source: Path, target: Path, options: MapOptions | None = None, *, connection_tolerance: float = 0.05
) -> tuple[SiteMap, Path]:
    """Load ``source`` and write its segments to ``target`` in the format ``target``'s name asks for."""
    options = options if options is not None else MapOptions()
    name = target.name.lower()
    if not name.endswith((".json", ".tmj", ".tmx")):
        msg = "the output must end in .lif.json (LIF 1.0) or .json, .tmj, .tmx (Tiled)"
        raise MapError(f"{msg}, not {target.suffix or 'no suffix'!r}", Location(target))
    site = load_site_map(source, options)
    if name.endswith(".lif.json") and site.format != "lif" and (options.layout or options.robot_type):
        # From a Tiled or RMF map, --layout and --robot-type name the LIF written, not a part to read.
        site = load_site_map(source, replace(options, layout=None, robot_type=None))
    if name.endswith(".lif.json"):
        layout_id = options.layout or source.name.split(".")[0] or "layout"
        written = write_lif(
            target,
            site.segments,
            layout_id=layout_id,
            robot_type=options.robot_type or DEFAULT_ROBOT_TYPE,
            connection_tolerance=connection_tolerance,
        )
    else:
        written = write_map(target, site.segments, stations=site.stations)
    return site, written
