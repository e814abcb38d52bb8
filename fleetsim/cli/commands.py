"""The ``fleetsim`` subcommands. Each takes parsed arguments and returns the exit status."""

from __future__ import annotations

import argparse
import json
import os
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

from fleetsim.cli.recorded import render_step
from fleetsim.cli.run import UsageError
from fleetsim.enums import ConflictModel
from fleetsim.errors import LoadError, UnreachableTaskError
from fleetsim.exec.protocol import encode_layout
from fleetsim.layout.layout import Layout, build_layout
from fleetsim.load.common.map_options import MapOptions, SiteMap
from fleetsim.load.common.text import write_text_atomically
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.load.suites.scenario import load_scenario, load_scenario_dir
from fleetsim.load.suites.suite import SUITE_SUFFIX, ScenarioSpec, Suite, discover_suites, load_suite
from fleetsim.load.tables.scenario_files import MAP_FILE_NAMES, VEHICLES_FILE_NAME, map_candidates
from fleetsim.recording.svg import render_layout_svg
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario

__all__ = ["convert", "inspect", "render", "validate"]


def validate(args: argparse.Namespace) -> int:
    """Load every scenario of every suite completely (map, layout, CSVs) and print layout lint.

    A folder that holds no suite but is a scenario folder (a map, ``vehicles.csv``, ``tasks.csv``) is
    validated as one, every vehicle of the default type; a folder that is neither is a usage error, so
    a mistyped path is never a silent pass. A League of Robot Runners problem file (.json) is validated
    as a suite of one scenario. Exit status 1 when any suite or scenario fails to load;
    each failure is printed with its location.
    """
    paths, folders = _validation_targets(args.suites)
    tally = _Tally()
    for path in paths:
        try:
            suite = load_suite(path)
        except LoadError as error:
            print(f"FAIL {path}\n{_indent(error, 5)}")
            tally.failed += 1
            continue
        print(f"{path}: suite {suite.name!r}, {len(suite.scenarios)} scenario(s)")
        for spec in suite.scenarios:
            if spec.generate is not None:
                _check_generated(spec, suite, tally)
            else:
                _check_scenario(spec.name, partial(load_scenario, spec, suite), tally)
    for folder in folders:
        print(f"{folder}: a scenario folder without a suite (every vehicle of the default type)")
        _check_scenario(folder.resolve().name, partial(load_scenario_dir, folder), tally)
    held = f"{len(paths)} suite(s)" + (f", {len(folders)} scenario folder(s)" if folders else "")
    print(f"{held}: {tally.loaded} scenario(s) valid, {tally.failed} failed, {tally.warnings} lint warning(s)")
    return 1 if tally.failed else 0


class _Tally:
    def __init__(self) -> None:
        self.loaded = self.failed = self.warnings = 0


def _validation_targets(arguments: list[str]) -> tuple[list[Path], list[Path]]:
    """The suite files to validate, and the scenario folders that hold no suite."""
    suites: list[Path] = []
    folders: list[Path] = []
    for path in map(Path, arguments):
        found = discover_suites([path])
        if found or not path.is_dir():
            suites += [file for file in found if file not in suites]
        elif map_candidates(path) or (path / VEHICLES_FILE_NAME).exists():
            folders.append(path)
        else:
            msg = f"{path}: no *{SUITE_SUFFIX} files in this folder, and it is no scenario folder (a map, vehicles.csv, tasks.csv)"
            raise UsageError(msg)
    return suites, folders


def _check_generated(spec: ScenarioSpec, suite: Suite, tally: _Tally) -> None:
    from fleetsim.gating.generated import check_generate_block  # Hypothesis only when needed

    g = spec.generate
    assert g is not None
    try:
        check_generate_block(spec, suite)
    except LoadError as error:
        print(f"  FAIL {spec.name}\n{_indent(error, 7)}")
        tally.failed += 1
        return
    tally.loaded += 1
    print(
        f"  ok   {spec.name}: generated ({g.layout} layouts of size {g.size[0]}-{g.size[1]}, "
        f"{g.vehicles[0]}-{g.vehicles[1]} vehicles, {g.tasks[0]}-{g.tasks[1]} tasks each, {g.examples} examples)"
    )


def _check_scenario(name: str, load: Callable[[], Scenario], tally: _Tally) -> None:
    try:
        scenario = load()
    except LoadError as error:
        print(f"  FAIL {name}\n{_indent(error, 7)}")
        tally.failed += 1
        notes = list(error.notes) if isinstance(error, UnreachableTaskError) else []
    else:
        tally.loaded += 1
        layout = scenario.layout
        orders = f", {len(scenario.orders)} orders" if scenario.orders_path is not None or scenario.orders else ""
        stream = ", an order stream" if scenario.order_stream is not None else ""
        lorr = scenario.lorr
        league = (
            f" (League {lorr.edition} problem: {lorr.task_pool} tasks revealed at a time, {lorr.horizon} timesteps)"
            if lorr is not None
            else ""
        )
        print(
            f"  ok   {name}: {len(layout.segments)} segments, {len(layout.connections)} connections, "
            f"{len(scenario.vehicles)} vehicles, {len(scenario.tasks)} tasks{orders}{stream}{league}"
        )
        for note in lorr.not_mapped if lorr is not None else ():
            print(f"       note: {note}")
        notes = [*scenario.warnings, *_lint_notes(layout, scenario.vehicle_length)]
    tally.warnings += len(notes)
    for note in notes:
        print(f"       {note}")


def _indent(error: LoadError, width: int) -> str:
    """The error's text indented by ``width``, every line of it (several errors are a list)."""
    return "\n".join(" " * width + line for line in str(error).splitlines())


def _lint_notes(layout: Layout, vehicle_length: float) -> list[str]:
    return [f"{f.severity} {f.code}: {f.message}" for f in layout.lint(vehicle_length)]


def map_options(args: argparse.Namespace) -> MapOptions:
    """The map options given on the command line (``--layout``, ``--robot-type``, ``--level``, ``--graph``,
    ``--cell-size``)."""
    return MapOptions(
        layout=args.layout, robot_type=args.robot_type, level=args.level, graph=args.graph, cell_size=args.cell_size
    )


def _layout_from_args(args: argparse.Namespace) -> tuple[SiteMap, Layout]:
    tiled_map = load_site_map(args.map, map_options(args))
    layout = build_layout(
        tiled_map.segments,
        vehicle_radius=args.radius,
        connection_tolerance=args.connection_tolerance,
        joint_angle_tolerance=args.joint_angle_tolerance,
        safety_margin=args.safety_margin,
        conflict_model=ConflictModel(args.conflict_model),
        source=tiled_map.path,
    )
    return tiled_map, layout


def layout_document(tiled_map: SiteMap, layout: Layout) -> dict[str, Any]:
    """The ``inspect --json`` document: segments, connections, conflicts per segment, lint (SPEC §14)."""
    encoded = encode_layout(layout)  # exactly a planner process's init layout
    return {
        "map": str(tiled_map.path),
        "format": tiled_map.format,
        "part": tiled_map.part,
        "meters_per_pixel": tiled_map.meters_per_pixel,
        **encoded,
        "lint": [
            {"code": f.code, "severity": f.severity, "segments": list(f.segments), "message": f.message}
            for f in layout.lint(DEFAULT_VEHICLE_TYPE.length)
        ],
        "warnings": list(tiled_map.warnings),
        "stations": {
            name: [{"segment": st.segment, "weight": st.weight, "name": st.name} for st in members]
            for name, members in tiled_map.stations.items()
        },
    }


def _print_layout(tiled_map: SiteMap, layout: Layout) -> None:
    part = f" ({tiled_map.part})" if tiled_map.part else ""
    print(
        f"{tiled_map.path}{part}: {len(layout.segments)} segments, {len(layout.connections)} connections "
        f"(connection tolerance {layout.connection_tolerance:g} m, joint angle tolerance {layout.joint_angle_tolerance:g}°)"
    )
    print(
        f"conflicts: {layout.conflict_model.value} model, vehicle radius {layout.vehicle_radius:.3f} m, "
        f"safety margin {layout.safety_margin:g} m"
    )
    width = max((len(" / ".join(seg.names)) for seg in layout.segments.values()), default=0)
    width = max(width, len("name"))
    print(f"\nsegments\n  id  {'name':<{width}}  shape     direction  length  from -> to (points)")
    for seg in layout.segments.values():
        (x0, y0), (x1, y1) = seg.first, seg.last
        name = " / ".join(seg.names) or "-"
        print(
            f"{seg.id:>4}  {name:<{width}}  {seg.shape.value:<8}  {seg.direction.value:<9} {seg.length:>7.3f}  "
            f"({x0:.3f}, {y0:.3f}) -> ({x1:.3f}, {y1:.3f}) ({len(seg.waypoints)})"
        )
    _print_stations(tiled_map)
    print("\nconnections")
    for c in layout.connections:
        print(f"  {c.from_segment} {c.from_traverse.value} -> {c.to_segment} {c.to_traverse.value}: {c.joint.value}")
    print("\nconflicts")
    for sid in layout.segments:
        others = sorted(layout.conflicts(sid) - {sid})
        print(f"  {sid}: {', '.join(map(str, others)) if others else '-'}")
    notes = [*tiled_map.warnings, *_lint_notes(layout, DEFAULT_VEHICLE_TYPE.length)]
    print("\nlint" + ("" if notes else ": clean"))
    for note in notes:
        print(f"  {note}")


def _print_stations(tiled_map: SiteMap) -> None:
    """The map's station sets, each with its segments (and their weights, where not 1); nothing without."""
    if not tiled_map.stations:
        return
    print("\nstation sets")
    for name, members in tiled_map.stations.items():
        listed = [f"{st.segment}" + (f" (weight {st.weight:g})" if st.weight != 1.0 else "") for st in members]
        print(f"  {name}: {', '.join(listed)}")


def inspect(args: argparse.Namespace) -> int:
    """Print a map's segments, connections with joint kinds, conflicts per segment and lint.

    MAP is a map file or a scenario folder holding one map (``map.json``, ...). A folder or a suite
    file is a usage error that lists the maps below it (or that the suite's scenarios drive on), each
    as the command that inspects it.
    """
    args.map = str(_map_file(Path(args.map)))
    tiled_map, layout = _layout_from_args(args)
    if args.json:
        print(json.dumps(layout_document(tiled_map, layout), indent=2))
    else:
        _print_layout(tiled_map, layout)
    return 0


MAPS_LISTED = 10
_MAP_KINDS = (
    "a map file (Tiled .json, .tmj or .tmx; LIF .lif.json; RMF .building.yaml) or a scenario folder with one map"
)


def _map_file(path: Path) -> Path:
    """The map ``inspect`` reads for ``path``: the file itself, or a scenario folder's one map file."""
    if path.is_dir():
        here = map_candidates(path)
        if len(here) == 1:
            return here[0]
        if here:
            listed = ", ".join(_shown(p) for p in here)
            msg = f"{_shown(path)}: a scenario folder with {len(here)} maps ({listed}); inspect one of them"
            raise UsageError(msg)
        msg = f"{_shown(path)}: a folder, not a map; inspect reads {_MAP_KINDS}. {_maps_below(path)}"
        raise UsageError(msg)
    if path.name.endswith(SUITE_SUFFIX):
        msg = f"{_shown(path)}: a suite, not a map; inspect reads {_MAP_KINDS}. {_maps_below(path)}"
        raise UsageError(msg)
    return path


def _maps_below(path: Path) -> str:
    """The maps of the scenario folders below ``path`` and of its suites' scenarios (those that load),
    each as the command that inspects it."""
    found: dict[Path, Path] = {}
    folder = path if path.is_dir() else None
    if folder is not None:  # scenario folders' maps, and files no other kind of file is named like
        for pattern in (*MAP_FILE_NAMES, "*.tmx", "*.tmj", "*.lif.json", "*.building.yaml"):
            for candidate in sorted(folder.rglob(pattern)):
                if candidate.is_file() and not any(p.startswith(".") for p in candidate.relative_to(folder).parts):
                    found.setdefault(candidate.resolve(), candidate)
    for suite_path in discover_suites([path]):
        try:
            specs = load_suite(suite_path).scenarios
        except LoadError:
            continue  # fleetsim validate says what is wrong with it
        for spec in specs:
            if spec.generate is None and spec.map_path.is_file():
                found.setdefault(spec.map_path.resolve(), spec.map_path)
    if not found:
        where = "below this folder" if folder is not None else "in this suite"
        return f"There is no map {where}."
    maps = sorted(_shown(p) for p in found.values())
    lines = [f"The maps {'below it' if folder is not None else 'its scenarios drive on'} ({len(maps)}):"]
    lines += [f"  fleetsim inspect {shown}" for shown in maps[:MAPS_LISTED]]
    if len(maps) > MAPS_LISTED:
        lines.append(f"  ... and {len(maps) - MAPS_LISTED} more")
    return "\n".join(lines)


def _shown(path: Path) -> str:
    """``path`` as the reader should type it: relative to the working folder when below it."""
    relative = os.path.relpath(path)
    return Path(path if relative.startswith("..") else relative).as_posix()


def convert(args: argparse.Namespace) -> int:
    """Write any map fleetsim loads as a Tiled map or as a LIF 1.0 file; the format follows OUT's name.

    OUT ending in .lif.json is LIF 1.0 (one layout; two-way segments as an edge each way); .json, .tmj or
    .tmx is a Tiled map (free-form segments as polylines of class path) that the Tiled editor opens.
    """
    from fleetsim.load.maps.convert import convert_map  # only this command writes maps

    site, written = convert_map(
        Path(args.map), Path(args.output), map_options(args), connection_tolerance=args.connection_tolerance
    )
    for warning in site.warnings:
        print(warning)
    part = f" ({site.part})" if site.part else ""
    print(f"wrote {written} ({len(site.segments)} segments from {site.path}{part})")
    return 0


def render(args: argparse.Namespace) -> int:
    """Draw a map, or one step of a recorded run, as SVG.

    fleetsim render MAP -o OUT.svg [--highlight ID]
      the map with segment ids and direction arrows; with --highlight ID, that segment yellow, the
      segments it leads to green, its conflicts grey.
    fleetsim render --trace RUN -o OUT.svg [--step N] [--suite SUITE::SCENARIO]
      the fleet at the end of step N of a recorded run: plans, vehicles, collision alerts in orange.
      RUN is an artifact folder (result.json and trace.jsonl) or a trace.jsonl. The scenario is the
      one result.json names, or --suite's. Without --step: the first failure's step, else the last.
    """
    if args.trace is not None:
        if args.map is not None or args.highlight is not None:
            msg = f"--trace={args.trace!r} draws a recorded run; leave out MAP and --highlight (they draw a map)"
            raise UsageError(msg)
        return render_step(args)
    if args.map is None:
        raise UsageError("render needs a MAP to draw, or --trace RUN_FOLDER to draw a step of a recorded run")
    if args.step is not None or args.suite is not None:
        raise UsageError("--step and --suite choose what to draw of a recorded run; use them with --trace")
    _, layout = _layout_from_args(args)
    svg = render_layout_svg(layout, highlight=args.highlight)
    output = Path(args.output)
    write_text_atomically(output, svg)
    print(f"wrote {output} ({len(layout.segments)} segments)")
    return 0
