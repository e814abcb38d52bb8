"""The ``fleetsim`` subcommands. Each takes parsed arguments and returns the exit status."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from fleetsim.cli.run import UsageError
from fleetsim.enums import ConflictModel
from fleetsim.errors import LoadError, UnreachableTaskError
from fleetsim.exec.protocol import encode_layout
from fleetsim.layout.layout import Layout, build_layout
from fleetsim.load.scenario import load_scenario
from fleetsim.load.scenario_files import did_you_mean
from fleetsim.load.suite import discover_suites, load_suite
from fleetsim.load.text import json_problem, write_text_atomically
from fleetsim.load.map_options import MapOptions, SiteMap
from fleetsim.load.site_map import load_site_map
from fleetsim.recording.artifacts import RESULT_FILE, TRACE_FILE
from fleetsim.recording.picture import failure_caption, failure_step, picture_overlays, render_frame_svg
from fleetsim.recording.replay import Frame, TraceError, frame_at
from fleetsim.recording.svg import render_layout_svg
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario
from fleetsim.sim.result import Failure

__all__ = ["convert", "inspect", "render", "validate"]


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
            if spec.generate is not None:
                from fleetsim.gating.generated import check_generate_block  # Hypothesis only when needed

                g = spec.generate
                try:
                    check_generate_block(spec, suite)
                except LoadError as error:
                    print(f"  FAIL {spec.name}\n       {error}")
                    failed += 1
                    continue
                loaded += 1
                print(
                    f"  ok   {spec.name}: generated ({g.layout} layouts of size {g.size[0]}-{g.size[1]}, "
                    f"{g.vehicles[0]}-{g.vehicles[1]} vehicles, {g.tasks[0]}-{g.tasks[1]} tasks each, {g.examples} examples)"
                )
                continue
            try:
                scenario = load_scenario(spec, suite)
            except LoadError as error:
                print(f"  FAIL {spec.name}\n       {error}")
                failed += 1
                notes = list(error.notes) if isinstance(error, UnreachableTaskError) else []
            else:
                loaded += 1
                layout = scenario.layout
                print(
                    f"  ok   {spec.name}: {len(layout.segments)} segments, {len(layout.connections)} connections, "
                    f"{len(scenario.vehicles)} vehicles, {len(scenario.tasks)} tasks"
                )
                notes = [*scenario.warnings, *_lint_notes(layout, scenario.vehicle_length)]
            warnings += len(notes)
            for note in notes:
                print(f"       {note}")
    print(f"{len(paths)} suite(s): {loaded} scenario(s) valid, {failed} failed, {warnings} lint warning(s)")
    return 1 if failed else 0


def _lint_notes(layout: Layout, vehicle_length: float) -> list[str]:
    return [f"{f.severity} {f.code}: {f.message}" for f in layout.lint(vehicle_length)]


def map_options(args: argparse.Namespace) -> MapOptions:
    """The map options given on the command line (``--layout``, ``--robot-type``, ``--level``, ``--graph``)."""
    return MapOptions(layout=args.layout, robot_type=args.robot_type, level=args.level, graph=args.graph)


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
    encoded = encode_layout(layout)  # the layout part of a planner process's init message, too
    for segment in encoded["segments"]:  # plus what the site calls each segment
        segment["names"] = list(layout.segments[segment["id"]].names)
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


def inspect(args: argparse.Namespace) -> int:
    """Print a map's segments, connections with joint kinds, conflicts per segment and lint."""
    tiled_map, layout = _layout_from_args(args)
    if args.json:
        print(json.dumps(layout_document(tiled_map, layout), indent=2))
    else:
        _print_layout(tiled_map, layout)
    return 0


def convert(args: argparse.Namespace) -> int:
    """Write any map fleetsim loads as a Tiled map or as a LIF 1.0 file; the format follows OUT's name.

    OUT ending in .lif.json is LIF 1.0 (one layout; two-way segments as an edge each way); .json, .tmj or
    .tmx is a Tiled map (free-form segments as polylines of class path) that the Tiled editor opens.
    """
    from fleetsim.load.convert import convert_map  # only this command writes maps

    site, written = convert_map(Path(args.map), Path(args.output), map_options(args),
                                connection_tolerance=args.connection_tolerance)
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
        return _render_step(args)
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


# -- render --trace: one step of a recorded run ---------------------------------------------------


def _render_step(args: argparse.Namespace) -> int:
    trace_path, result_path = _run_files(Path(args.trace))
    document = _read_result(result_path) if result_path is not None else {}
    scenario = _recorded_scenario(args.suite, document, result_path or trace_path)
    lines = _read_text(trace_path).splitlines()
    last_step = len(lines) - 2  # a header line, then one line per step
    if last_step < 0:
        raise UsageError(f"{trace_path}: the trace has no steps")
    found = None
    failures: list[Failure] = []
    if document.get("status") == "failed":
        failures = _failures(document, result_path)
        found = failure_step(failures, scenario.settings.time_step, last_step)
    if args.step is None:
        step = found[0] if found is not None else last_step
    elif 0 <= args.step <= last_step:
        step = args.step
    else:
        raise UsageError(f"{trace_path}: --step={args.step!r} must be between 0 and {last_step} (the run's last step)")
    try:
        frame = frame_at(scenario, lines, step)
        _check_segments(scenario, frame)
    except TraceError as error:  # a trace of another scenario, or not a trace at all
        raise UsageError(f"{trace_path}: {error}") from None
    except KeyError as error:  # an id the scenario does not have: the trace is of another scenario
        msg = (
            f"{trace_path}: the trace names id {error.args[0]!r}, which scenario {scenario.name!r} does not have; "
            "name the run's scenario with --suite SUITE::SCENARIO"
        )
        raise UsageError(msg) from None
    stuck = rejected = None
    if found is not None and found[0] == step:
        caption = failure_caption(found[1], failures, at=frame.time)
        stuck, rejected = picture_overlays(found[1])
    else:
        caption = f"t = {frame.time:.2f} s \u2014 {scenario.name}, step {step} of {last_step}"
    output = Path(args.output)
    write_text_atomically(output, render_frame_svg(scenario, frame, caption=caption, stuck=stuck, rejected=rejected))
    print(f"wrote {output} ({scenario.name}, step {step} of {last_step}, t = {frame.time:.2f} s)")
    return 0


def _check_segments(scenario: Scenario, frame: Frame) -> None:
    """Raise KeyError for the first segment of a pose or plan that the scenario's map lacks."""
    segments = scenario.layout.segments
    used = {pose.segment for pose in frame.poses.values()}
    used.update(leg.segment for plan in frame.plans.values() for leg in plan.legs)
    for sid in sorted(used):
        if sid not in segments:
            raise KeyError(sid)


def _run_files(path: Path) -> tuple[Path, Path | None]:
    """The trace and, when there is one beside it, the result.json of a run folder or trace file."""
    if not path.exists():
        raise UsageError(f"{path}: no such file or directory")
    if path.is_dir():
        trace = path / TRACE_FILE
        if not trace.is_file():
            raise UsageError(f"{path}: no {TRACE_FILE} in this folder (the run did not keep its trace)")
    else:
        trace = path
    result = trace.parent / RESULT_FILE
    return trace, result if result.is_file() else None


def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        raise UsageError(f"{path}: not a text file (byte {error.start} is not UTF-8)") from None


def _read_result(path: Path) -> dict[str, Any]:
    try:
        document = json.loads(_read_text(path))
    except json.JSONDecodeError as error:
        raise UsageError(f"{path}:{error.lineno}:{error.colno}: {json_problem(error)}") from None
    if not isinstance(document, dict):
        raise UsageError(f"{path}: must hold a JSON object (a run's result), not {type(document).__name__}")
    return document


def _failures(document: dict[str, Any], path: Path | None) -> list[Failure]:
    try:
        return [
            Failure(str(f["kind"]), float(f["time"]), str(f["message"]), {k: v for k, v in f.items() if k not in ("kind", "time", "message")})
            for f in document.get("failures", [])
        ]
    except (KeyError, TypeError, ValueError):
        msg = f"{path}: failures={document.get('failures')!r} must be a list of {{kind, time, message}} objects"
        raise UsageError(msg) from None


def _recorded_scenario(selector: str | None, document: dict[str, Any], source: Path) -> Scenario:
    """The scenario the run was of: ``--suite SUITE::SCENARIO`` if given, else what result.json names."""
    if selector is not None:
        suite_text, separator, name = selector.rpartition("::")
        if not (separator and suite_text and name):
            raise UsageError(f"--suite={selector!r} must be SUITE::SCENARIO, e.g. suites/demo.fleetsim.yaml::crossing")
        where = "--suite"
    else:
        recorded_suite, recorded_name = document.get("suite"), document.get("scenario")
        if not isinstance(recorded_suite, str) or not isinstance(recorded_name, str):
            raise UsageError(f"{source}: does not name the run's suite and scenario; name them with --suite SUITE::SCENARIO")
        suite_text, name, where = recorded_suite, recorded_name, str(source)
    suite_path = Path(suite_text)
    if not suite_path.is_file():
        raise UsageError(f"{suite_path}: no such suite file (named by {where})")
    suite = load_suite(suite_path)
    spec = next((spec for spec in suite.scenarios if spec.name == name), None)
    if spec is None:
        names = [spec.name for spec in suite.scenarios]
        msg = f"{suite_path} has no scenario {name!r} (named by {where}; its scenarios: {', '.join(names)}){did_you_mean(name, names)}"
        raise UsageError(msg)
    return load_scenario(spec, suite)
