"""``fleetsim generate warehouse``: write a ready-to-run warehouse scenario folder.

The folder holds the map (``map.json``, a Tiled map whose station segments carry the ``station``
property; or ``map.lif.json``, a LIF 1.0 file with one station per set), ``vehicles.csv`` (each vehicle
on a parking place of its own), an empty ``tasks.csv`` (for trips of one's own) and
``warehouse.fleetsim.yaml``: a suite whose one scenario runs the folder as a one-hour shift of a Poisson
order stream, pick then drop, dispatched by the reference dispatcher (nearest vehicle). The layout is :mod:`fleetsim.generate.warehouse_layout`'s.

The same options give byte-identical files (the LIF file's export time is fixed). Every option is checked,
and the layout built, before anything is written: a bad option writes nothing.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

from fleetsim.generate.options import GenerateError, WarehouseOptions
from fleetsim.generate.warehouse_layout import DROP, PARK, PICK, WarehouseLayout, warehouse_layout
from fleetsim.load.common.text import write_text_atomically
from fleetsim.load.lif.writer import write_lif
from fleetsim.load.tables.scenario_files import MAP_FILE_NAMES, TASKS_FILE_NAME, VEHICLES_FILE_NAME
from fleetsim.load.tiled.writer import write_map
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE

__all__ = ["SUITE_FILE_NAME", "GeneratedWarehouse", "generate_warehouse"]

SUITE_FILE_NAME = "warehouse.fleetsim.yaml"
VEHICLE_TYPE = "agv"  # the generated suite's one vehicle type
_LIF_TIMESTAMP = "2024-01-01T00:00:00.00Z"  # fixed, so that the same options give the same bytes
_METERS_PER_PIXEL = 1 / 32  # a 32-pixel tile is one metre


@dataclass(frozen=True, slots=True)
class GeneratedWarehouse:
    """What [`generate_warehouse`][fleetsim.generate.generate_warehouse] wrote.

    Attributes:
        folder: The scenario folder.
        map: Its map file (``map.json`` or ``map.lif.json``).
        vehicles: Its ``vehicles.csv``.
        tasks: Its ``tasks.csv`` (a header only).
        suite: Its suite file, ``warehouse.fleetsim.yaml``.
        layout: The segments and station sets written.
        options: The options it was generated with.
    """

    folder: Path
    map: Path
    vehicles: Path
    tasks: Path
    suite: Path
    layout: WarehouseLayout
    options: WarehouseOptions


def generate_warehouse(
    out_dir: str | os.PathLike[str], options: WarehouseOptions | None = None, *, force: bool = False
) -> GeneratedWarehouse:
    """Write a warehouse scenario folder to ``out_dir`` (made if missing) and return its paths.

    ``options`` default to a small working site (6 aisles, 12 pick and 4 drop stations, 8 vehicles).
    ``out_dir`` must not hold files unless ``force``, which replaces the files this writes and removes
    any other map file of the folder (a folder has one map). Raises
    [`GenerateError`][fleetsim.generate.GenerateError] for options it cannot build, and for a folder in
    the way, before writing anything.
    """
    options = options if options is not None else WarehouseOptions()
    folder = Path(out_dir)
    _check_folder(folder, force)
    layout = warehouse_layout(options)
    folder.mkdir(parents=True, exist_ok=True)
    map_name = "map.lif.json" if options.map_format == "lif" else "map.json"
    for name in MAP_FILE_NAMES:
        if name != map_name and (folder / name).is_file():
            (folder / name).unlink()  # only with force: an empty folder has none
    map_path = folder / map_name
    if options.map_format == "lif":
        write_lif(map_path, layout.segments, layout_id="warehouse", stations=layout.stations, timestamp=_LIF_TIMESTAMP)
    else:
        write_map(map_path, layout.segments, meters_per_pixel=_METERS_PER_PIXEL, stations=layout.stations)
    vehicles = folder / VEHICLES_FILE_NAME
    write_text_atomically(vehicles, vehicles_csv(layout, options.vehicles))
    tasks = folder / TASKS_FILE_NAME
    write_text_atomically(tasks, _TASKS_CSV)
    suite = folder / SUITE_FILE_NAME
    write_text_atomically(suite, suite_text(options, layout, map_name))
    return GeneratedWarehouse(folder, map_path, vehicles, tasks, suite, layout, options)


def _check_folder(folder: Path, force: bool) -> None:
    if folder.exists() and not folder.is_dir():
        raise GenerateError("out_dir", str(folder), "is a file; give a folder (it is made if missing)")
    if folder.is_dir() and not force and any(folder.iterdir()):
        reason = (
            "is not empty; force (--force) writes into it anyway, replacing map.json, vehicles.csv, tasks.csv "
            "and warehouse.fleetsim.yaml and removing any other map file there"
        )
        raise GenerateError("out_dir", str(folder), reason)


def vehicles_csv(layout: WarehouseLayout, count: int) -> str:
    """``vehicles.csv``: vehicle 1 on the first parking place, 2 on the second, ..., facing into it."""
    rows = [f"{number},{segment},forward,forward" for number, segment in enumerate(layout.parking[:count], start=1)]
    return "vehicle_id,start_segment_id,segment_orientation,progress_direction\n" + "".join(f"{r}\n" for r in rows)


_TASKS_CSV = (
    "# Trips of one's own (vehicle, goal segment or station name such as pick-3); the suite's order stream\n"
    "# gives the shift its work.\n"
    "vehicle_id,goal_segment_id,goal_progress_direction\n"
)


def suite_text(options: WarehouseOptions, layout: WarehouseLayout, map_name: str) -> str:
    """The suite file: the vehicle type, and one scenario running the folder as a shift of orders."""
    site = "one-way" if options.one_way else "two-way"
    counts = {name: len(layout.stations[name]) for name in (PICK, DROP, PARK)}
    size = (
        f"{options.aisles} {site} aisles of {_number(options.aisle_length)} m, "
        f"{_number(options.aisle_spacing)} m apart; "
        f"{counts[PICK]} pick and {counts[DROP]} drop stations, {counts[PARK]} parking places, "
        f"{options.vehicles} vehicles"
    )
    agv = (
        f"{{length: {_number(options.vehicle_length)}, width: {_number(options.vehicle_width)}, "
        f"height: {DEFAULT_VEHICLE_TYPE.height:g}, max_speed: {DEFAULT_VEHICLE_TYPE.max_speed:g}, "
        f"acceleration: {DEFAULT_VEHICLE_TYPE.acceleration:g}, turn_capability: in_place, "
        f"turn_rate: {DEFAULT_VEHICLE_TYPE.turn_rate:g}}}"
    )
    return (
        f"# Generated by: {command_line(options)}\n"
        "fleetsim: 1\n"
        "name: warehouse\n"
        f"description: {json.dumps(f'A generated warehouse ({map_name}): {size}.')}\n"
        "vehicle_types:\n"
        f"  {VEHICLE_TYPE}: {agv}\n"
        "defaults:\n"
        f"  vehicle_type: {VEHICLE_TYPE}\n"
        "scenarios:\n"
        "  - name: shift\n"
        "    description: An hour of pick-to-drop orders, released at random (Poisson), 60 an hour.\n"
        "    dir: .\n"
        f"    order_stream: {{seed: {options.seed}, arrivals: {{poisson: 60}}, "
        f"stops: [{{from: {PICK}, dwell: 20}}, {{from: {DROP}, dwell: 15}}]}}\n"
        "    shift: {duration: 1h}\n"
        + (f"    dispatcher: {options.dispatcher}\n" if options.dispatcher is not None else "")
    )


def command_line(options: WarehouseOptions) -> str:
    """The command that generates this warehouse again (the options that differ from the defaults)."""
    words = ["fleetsim generate warehouse OUT_DIR"]
    defaults = WarehouseOptions()
    for name in ("aisles", "aisle_length", "aisle_spacing", "vehicles", "pick_stations", "drop_stations"):
        if getattr(options, name) != getattr(defaults, name):
            words.append(f"--{name.replace('_', '-')} {_number(getattr(options, name))}")
    if options.parking is not None:
        words.append(f"--parking {options.parking}")
    if not options.one_way:
        words.append("--two-way")
    for name in ("vehicle_length", "vehicle_width"):
        if getattr(options, name) != getattr(defaults, name):
            words.append(f"--{name.replace('_', '-')} {_number(getattr(options, name))}")
    if options.map_format != defaults.map_format:
        words.append(f"--format {options.map_format}")
    if options.seed != defaults.seed:
        words.append(f"--seed {options.seed}")
    if options.dispatcher != defaults.dispatcher:
        words.append(f"--dispatcher {options.dispatcher}" if options.dispatcher else "--no-dispatcher")
    return " ".join(words)


def _number(value: float) -> str:
    """A number as a person writes it: ``20``, ``4.5``, ``0.6`` (and exactly, never rounded)."""
    return str(int(value)) if float(value).is_integer() else repr(float(value))
