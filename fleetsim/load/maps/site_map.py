"""Load a driving map in any format fleetsim reads: Tiled (TMX, JSON), VDA 5050 LIF, Open-RMF building,
MovingAI grid map.

The format follows the file: ``*.tmx``/``*.tmj`` are Tiled; ``*.lif.json`` and any JSON whose top level
has ``metaInformation`` plus ``layouts`` or ``origins`` are LIF; other ``*.json`` files are Tiled; a
``*.building.yaml`` (or ``.yaml``/``.yml``) is an Open-RMF building map; a ``*.map`` is a MovingAI grid
map (:mod:`fleetsim.load.movingai`). Every problem is a located
:class:`~fleetsim.errors.MapError` (several found in one pass: a :class:`~fleetsim.errors.LoadErrors` of
them); nothing is returned half loaded.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

from fleetsim.errors import Location, MapError
from fleetsim.load.common.import_notes import ImportNotes
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.common.text import read_text_file
from fleetsim.load.lif.reader import is_lif_document, load_lif
from fleetsim.load.movingai.reader import load_movingai
from fleetsim.load.rmf.reader import load_building
from fleetsim.load.tiled.reader import load_map
from fleetsim.load.tiled.templates import parse_json

__all__ = ["MAP_SUFFIXES", "load_site_map", "map_format"]

MAP_SUFFIXES = (".json", ".tmj", ".tmx", ".yaml", ".yml", ".map")
_LIF_MARK = '"metaInformation"'  # only a file holding this text can be LIF: no need to parse the rest twice
# Which format each map option is for (an option given for a map of another format is noted, not used).
_OPTION_FORMAT = dict.fromkeys(("layout", "robot_type", "level", "graph"), "LIF and RMF") | {"cell_size": "MovingAI"}


def map_format(path: Path) -> str:
    """``tiled``, ``lif``, ``rmf`` or ``movingai`` by name alone (``.json`` files may still turn out to be LIF)."""
    name = path.name.lower()
    if name.endswith((".yaml", ".yml")):
        return "rmf"
    if name.endswith(".map"):
        return "movingai"
    if name.endswith(".lif.json"):
        return "lif"
    if name.endswith((".json", ".tmj", ".tmx")):
        return "tiled"
    known = (
        "a Tiled map (.json, .tmj, .tmx), a LIF file (.lif.json), an RMF building map (.building.yaml) "
        "or a MovingAI grid map (.map)"
    )
    raise MapError(
        f"this is not a map file: a map is {known}, and this file ends in {path.suffix or 'no suffix'!r}",
        Location(path),
    )


def load_site_map(path: str | os.PathLike[str], options: MapOptions | None = None) -> SiteMap:
    """Load the driving map at ``path``; ``options`` choose the part of a LIF or RMF file to drive on and
    the cell size of a MovingAI map."""
    map_path = Path(path)
    options = options if options is not None else MapOptions()
    kind = map_format(map_path)
    if kind == "movingai":
        return load_movingai(map_path, options)
    if kind == "rmf":
        return _noting(load_building(map_path, options), options, ("cell_size",))
    if map_path.suffix.lower() == ".json":
        text = read_text_file(map_path, MapError)
        if kind == "lif" or _LIF_MARK in text:
            document = parse_json(text, map_path)
            if is_lif_document(document):
                return _noting(load_lif(map_path, document, options), options, ("cell_size",))
            if kind == "lif":
                msg = "this .lif.json file is not LIF: its top level needs 'metaInformation' and 'layouts' (1.0) or 'origins' (2.0)"
                raise MapError(msg, Location(map_path))
    tiled = load_map(map_path)
    site = SiteMap(tiled.path, "tiled", tiled.segments, tiled.warnings, tiled.meters_per_pixel, stations=tiled.stations)
    return _noting(site, options, tuple(_OPTION_FORMAT))


def _noting(site: SiteMap, options: MapOptions, names: tuple[str, ...]) -> SiteMap:
    """``site``, with a note for each map option of ``names`` given: one for maps of another format."""
    given = [name for name in options.given() if name in names]
    if not given:
        return site
    notes = ImportNotes(site.path)
    for name in given:
        notes.note("option-ignored", f"map option {name!r} (for {_OPTION_FORMAT[name]} maps)", "map_options")
    return replace(site, warnings=(*site.warnings, *notes.warnings()))
