"""Load a driving map in any format fleetsim reads: Tiled (TMX, JSON), VDA 5050 LIF, Open-RMF building.

The format follows the file: ``*.tmx``/``*.tmj`` are Tiled; ``*.lif.json`` and any JSON whose top level
has ``metaInformation`` plus ``layouts`` or ``origins`` are LIF; other ``*.json`` files are Tiled; a
``*.building.yaml`` (or ``.yaml``/``.yml``) is an Open-RMF building map. Every problem is a located
:class:`~fleetsim.errors.MapError` (several found in one pass: a :class:`~fleetsim.errors.LoadErrors` of
them); nothing is returned half loaded.
"""

from __future__ import annotations

import os
from pathlib import Path

from fleetsim.errors import Location, MapError
from fleetsim.load.common.import_notes import ImportNotes
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.common.text import read_text_file
from fleetsim.load.lif.reader import is_lif_document, load_lif
from fleetsim.load.rmf.reader import load_building
from fleetsim.load.tiled.reader import load_map
from fleetsim.load.tiled.templates import parse_json

__all__ = ["MAP_SUFFIXES", "load_site_map", "map_format"]

MAP_SUFFIXES = (".json", ".tmj", ".tmx", ".yaml", ".yml")
_LIF_MARK = '"metaInformation"'  # only a file holding this text can be LIF: no need to parse the rest twice


def map_format(path: Path) -> str:
    """``tiled``, ``lif`` or ``rmf`` by name alone (``.json`` files may still turn out to be LIF)."""
    name = path.name.lower()
    if name.endswith((".yaml", ".yml")):
        return "rmf"
    if name.endswith(".lif.json"):
        return "lif"
    if name.endswith((".json", ".tmj", ".tmx")):
        return "tiled"
    known = "a Tiled map (.json, .tmj, .tmx), a LIF file (.lif.json) or an RMF building map (.building.yaml)"
    raise MapError(
        f"this is not a map file: a map is {known}, and this file ends in {path.suffix or 'no suffix'!r}",
        Location(path),
    )


def load_site_map(path: str | os.PathLike[str], options: MapOptions | None = None) -> SiteMap:
    """Load the driving map at ``path``; ``options`` choose the part of a LIF or RMF file to drive on."""
    map_path = Path(path)
    options = options if options is not None else MapOptions()
    kind = map_format(map_path)
    if kind == "rmf":
        return load_building(map_path, options)
    if map_path.suffix.lower() == ".json":
        text = read_text_file(map_path, MapError)
        if kind == "lif" or _LIF_MARK in text:
            document = parse_json(text, map_path)
            if is_lif_document(document):
                return load_lif(map_path, document, options)
            if kind == "lif":
                msg = "this .lif.json file is not LIF: its top level needs 'metaInformation' and 'layouts' (1.0) or 'origins' (2.0)"
                raise MapError(msg, Location(map_path))
    tiled = load_map(map_path)
    notes = ImportNotes(map_path)
    for name in options.given():
        notes.note("option-ignored", f"map option {name!r} (for LIF and RMF maps)", "map_options")
    warnings = (*tiled.warnings, *notes.warnings())
    return SiteMap(tiled.path, "tiled", tiled.segments, warnings, tiled.meters_per_pixel, stations=tiled.stations)
