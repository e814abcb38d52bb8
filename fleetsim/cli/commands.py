"""The ``fleetsim`` subcommands. Each takes parsed arguments and returns the exit status."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from fleetsim.enums import ConflictModel
from fleetsim.errors import LoadError
from fleetsim.layout.layout import Layout, build_layout
from fleetsim.load.scenario import load_scenario
from fleetsim.load.suite import discover_suites, load_suite
from fleetsim.load.text import write_text_atomically
from fleetsim.load.tiled import TiledMap, load_map
from fleetsim.recording.svg import render_layout_svg

__all__ = ["inspect", "render", "validate"]


def validate(args: argparse.Namespace) -> int:
    """Load every scenario of every suite completely (map, layout, CSVs) and print layout lint.

    Exit status 1 when any suite or scenario fails to load; each failure is printed with its location.
    """
    paths = discover_suites([Path(p) for p in args.suites])
    loaded = failed = warnings = 0
    for path in paths:
        try:
            suite = load_suite(path)
        except LoadError as error:
            print(f"FAIL {path}\n     {error}")
            failed += 1
            continue
        print(f"{path}: suite {suite.name!r}, {len(suite.scenarios)} scenario(s)")
        for spec in suite.scenarios:
            try:
                scenario = load_scenario(spec, suite)
            except LoadError as error:
                print(f"  FAIL {spec.name}\n       {error}")
                failed += 1
                continue
            loaded += 1
            layout = scenario.layout
            print(
                f"  ok   {spec.name}: {len(layout.segments)} segments, {len(layout.connections)} connections, "
                f"{len(scenario.vehicles)} vehicles, {len(scenario.tasks)} tasks"
            )
            notes = [*scenario.warnings, *(f"{f.severity} {f.code}: {f.message}" for f in layout.lint())]
            warnings += len(notes)
            for note in notes:
                print(f"       {note}")
    print(f"{len(paths)} suite(s): {loaded} scenario(s) valid, {failed} failed, {warnings} lint warning(s)")
    return 1 if failed else 0


def _layout_from_args(args: argparse.Namespace) -> tuple[TiledMap, Layout]:
    tiled_map = load_map(args.map)
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


def layout_document(tiled_map: TiledMap, layout: Layout) -> dict[str, Any]:
    """The ``inspect --json`` document: segments, connections, conflicts per segment, lint (SPEC §14)."""
    return {
        "map": str(tiled_map.path),
        "meters_per_pixel": tiled_map.meters_per_pixel,
        "settings": {
            "vehicle_radius": layout.vehicle_radius,
            "safety_margin": layout.safety_margin,
            "conflict_model": layout.conflict_model.value,
            "connection_tolerance": layout.connection_tolerance,
            "joint_angle_tolerance": layout.joint_angle_tolerance,
        },
        "segments": [
            {
                "id": seg.id,
                "shape": seg.shape.value,
                "direction": seg.direction.value,
                "length": seg.length,
                "waypoints": [list(p) for p in seg.waypoints],
            }
            for seg in layout.segments.values()
        ],
        "connections": [
            {
                "from": [c.from_segment, c.from_traverse.value],
                "to": [c.to_segment, c.to_traverse.value],
                "joint": c.joint.value,
            }
            for c in layout.connections
        ],
        "conflicts": [{"segment": sid, "conflicts": sorted(layout.conflicts(sid))} for sid in layout.segments],
        "lint": [
            {"code": f.code, "severity": f.severity, "segments": list(f.segments), "message": f.message}
            for f in layout.lint()
        ],
        "warnings": list(tiled_map.warnings),
    }


def _print_layout(tiled_map: TiledMap, layout: Layout) -> None:
    print(
        f"{tiled_map.path}: {len(layout.segments)} segments, {len(layout.connections)} connections "
        f"(connection tolerance {layout.connection_tolerance:g} m, joint angle tolerance {layout.joint_angle_tolerance:g}°)"
    )
    print(
        f"conflicts: {layout.conflict_model.value} model, vehicle radius {layout.vehicle_radius:.3f} m, "
        f"safety margin {layout.safety_margin:g} m"
    )
    print("\nsegments\n  id  shape     direction  length  from -> to (points)")
    for seg in layout.segments.values():
        (x0, y0), (x1, y1) = seg.first, seg.last
        print(
            f"{seg.id:>4}  {seg.shape.value:<8}  {seg.direction.value:<9} {seg.length:>7.3f}  "
            f"({x0:.3f}, {y0:.3f}) -> ({x1:.3f}, {y1:.3f}) ({len(seg.waypoints)})"
        )
    print("\nconnections")
    for c in layout.connections:
        print(f"  {c.from_segment} {c.from_traverse.value} -> {c.to_segment} {c.to_traverse.value}: {c.joint.value}")
    print("\nconflicts")
    for sid in layout.segments:
        others = sorted(layout.conflicts(sid) - {sid})
        print(f"  {sid}: {', '.join(map(str, others)) if others else '-'}")
    notes = [*tiled_map.warnings, *(f"{f.severity} {f.code}: {f.message}" for f in layout.lint())]
    print("\nlint" + ("" if notes else ": clean"))
    for note in notes:
        print(f"  {note}")


def inspect(args: argparse.Namespace) -> int:
    """Print a map's segments, connections with joint kinds, conflicts per segment and lint."""
    tiled_map, layout = _layout_from_args(args)
    if args.json:
        print(json.dumps(layout_document(tiled_map, layout), indent=2))
    else:
        _print_layout(tiled_map, layout)
    return 0


def render(args: argparse.Namespace) -> int:
    """Draw a map as SVG with segment ids and direction arrows.

    With --highlight ID: that segment yellow, the segments it leads to green, its conflicts grey.
    """
    _, layout = _layout_from_args(args)
    svg = render_layout_svg(layout, highlight=args.highlight)
    output = Path(args.output)
    write_text_atomically(output, svg)
    print(f"wrote {output} ({len(layout.segments)} segments)")
    return 0
