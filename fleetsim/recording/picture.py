"""A still SVG picture of one moment of a run (SPEC §11 ★): map, plans, vehicles, alerts, caption.

A reviewer of a failed CI run should see at a glance what went wrong without installing RViz: the
failure picture is the frame (from :mod:`fleetsim.recording.replay`) of the step where the first
failure happened, with the segments of the collision alerts in force in orange, every vehicle's plan
in its colour (fixed legs thick, planned legs dashed) and the failure as the caption. The drawing is
deterministic (fixed order, fixed number formats), so pictures of the same run are byte-identical.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any
from xml.sax.saxutils import escape

from fleetsim.enums import Progress, Traverse
from fleetsim.layout.segment import Point
from fleetsim.recording.colours import (
    ALERT,
    CONTESTED,
    CYCLE,
    DISTURBED,
    MAP,
    REJECTED,
    WAITS,
    hex_colour,
    svg_colour,
    vehicle_colours,
)
from fleetsim.recording.order_svg import ORDERS_LEGEND, STALL_LEGEND, orders_svg, stall_svg
from fleetsim.recording.orders import OrderState, frame_and_orders_at
from fleetsim.recording.replay import Frame, Pose, frame_at
from fleetsim.recording.stuck import contested_segments, stuck_relations
from fleetsim.recording.svg import _arrow, _document, _Frame, _frame, _point_at, _segment_labels, _segment_svg
from fleetsim.scenario import Scenario, Vehicle
from fleetsim.sim.report import first_line
from fleetsim.sim.result import MOMENTLESS, Failure, RunResult

__all__ = [
    "failure_caption",
    "failure_picture",
    "failure_step",
    "picture_overlays",
    "render_frame_svg",
    "stuck_details",
]

_MAP = hex_colour(MAP)
_ALERT = hex_colour(ALERT)
_INK = "#111111"
_LEGEND = "thick: fixed legs \u00b7 dashed: planned legs \u00b7 orange: segments with a collision alert"
_WAITS = hex_colour(WAITS)
_DISTURBED = hex_colour(DISTURBED)  # the outline and label of a vehicle a disturbance stops or slows
_DISTURBED_LEGEND = "magenta dashed outline: a disturbance stops (STOP) or slows (SLOW) the vehicle"
_CYCLE = hex_colour(CYCLE)
_CONTESTED = hex_colour(CONTESTED)
_REJECTED = hex_colour(REJECTED)
_REJECTED_LEGEND = "magenta, dashed: the rejected plan (red outline: the leg that failed the check)"
_CONTACT_LEGEND = "red outlines: the two footprints at the moment they touched \u00b7 red ring: where"
_STUCK_KINDS = ("deadlock", "timeout", "interrupted")  # failures that explain who waits for whom
_MIN_WIDTH = 480.0  # user units: room for a readable caption on the smallest maps
_STUCK_LEGEND = (
    "arrow: waits for (red: in a wait-for cycle; dotted: plans to drive near its free next leg) \u00b7 "
    "red ring: root cause \u00b7 purple: contested segments"
)


def render_frame_svg(
    scenario: Scenario,
    frame: Frame,
    *,
    caption: str,
    pixels_per_metre: float = 40.0,
    stuck: Mapping[str, Any] | None = None,
    rejected: Mapping[str, Any] | None = None,
    contact: Mapping[str, Any] | None = None,
    orders: OrderState | None = None,
    stall: Mapping[str, Any] | None = None,
) -> str:
    """Draw ``frame`` of a run of ``scenario`` as an SVG document with ``caption`` on top.

    The picture is as wide as the map (at least :data:`_MIN_WIDTH`); the caption and legends wrap to it.
    ``stuck``: the details of a deadlock or timeout failure (``vehicles``, ``cycles``, ``roots``, as in
    ``result.json``); who waits for whom is drawn over the fleet. ``rejected``: the details of a
    rejection (its ``plan`` and ``leg_index``); the refused plan is drawn with its offending leg marked.
    ``contact``: a contact at its moment (:func:`contact_moment`): both footprints then, and the place.
    ``orders``: a run's transport orders at the frame (:mod:`fleetsim.recording.orders`): waiting stations
    and each vehicle's order. ``stall``: a stall's details (``vehicle``, ``orders``): the vehicle ringed.
    """
    font = 0.4 * pixels_per_metre
    legends = [
        _LEGEND,
        *([_STUCK_LEGEND] if stuck else []),
        *([_REJECTED_LEGEND] if rejected and rejected.get("plan") else []),
        *([_CONTACT_LEGEND] if contact else []),
    ]
    legends += [_DISTURBED_LEGEND] if frame.disturbed else []
    legends += [ORDERS_LEGEND] if orders is not None else []
    legends += [STALL_LEGEND] if stall else []
    view = _frame(scenario.layout, margin=1.5, pixels_per_metre=pixels_per_metre)
    width = max(view.width, _MIN_WIDTH)
    # About 0.6 em per character of sans-serif: lines as long as the picture is wide.
    caption_lines = [part for line in caption.splitlines() for part in _wrap(line, width - 2 * font, font)]
    legend_lines = [part for legend in legends for part in _wrap(legend, width - 2 * font, 0.7 * font)]
    top = (0.8 + 1.25 * len(caption_lines) + 0.95 * len(legend_lines) + 0.6) * font
    # Centre the map when the picture is wider than it.
    view = replace(
        view, min_x=view.min_x - (width - view.width) / 2 / view.scale, width=width, height=view.height + top, top=top
    )
    colours = {vid: svg_colour(rgba) for vid, rgba in vehicle_colours(scenario).items()}
    y = 0.8 * font
    text = ['<g class="caption" font-family="sans-serif">']
    for line in caption_lines:
        y += 1.25 * font
        text.append(
            f'<text class="caption-text" x="{font:.1f}" y="{y - 0.25 * font:.1f}" font-size="{font:.1f}" fill="{_INK}">{escape(line)}</text>'
        )
    for line in legend_lines:
        y += 0.95 * font
        text.append(
            f'<text class="legend" x="{font:.1f}" y="{y:.1f}" font-size="{0.7 * font:.1f}" fill="#555555">{escape(line)}</text>'
        )
    text.append("</g>")
    body = [
        *_alerts_svg(scenario, frame, view),
        *(_contested_svg(scenario, view, stuck) if stuck else []),
        *_map_svg(scenario, view),
        *_plans_svg(scenario, frame, view, colours),
        *(_rejected_svg(scenario, view, rejected) if rejected and rejected.get("plan") else []),
        *_labels_svg(scenario, view),
        *_vehicles_svg(scenario, frame, view, colours, font * 0.8),
        *(_waits_svg(scenario, frame, view, stuck) if stuck else []),
        *(_contact_svg(scenario, view, contact) if contact else []),
        *(orders_svg(scenario, frame, view, orders, colours, font * 0.8) if orders is not None else []),
        *(
            stall_svg(scenario, frame, view, int(stall["vehicle"]), [str(o) for o in stall.get("orders", ())], font)
            if stall
            else []
        ),
        *text,
    ]
    return _document(view, f"{scenario.name}: step {frame.step}", body)


def _wrap(text: str, width: float, font: float) -> list[str]:
    """``text`` in lines of at most ``width`` user units at ``font`` size (about 0.6 em a character)."""
    return textwrap.wrap(" ".join(text.split()), width=max(20, int(width / (0.6 * font))), break_on_hyphens=False) or [
        ""
    ]


def _rejected_svg(scenario: Scenario, view: _Frame, rejected: Mapping[str, Any]) -> list[str]:
    """The refused plan in magenta, dashed, its legs numbered; the leg that failed the check outlined in red."""
    layout = scenario.layout
    width = 0.12 * view.scale
    offending = rejected.get("leg_index")
    parts = [
        f'<g class="rejected-plan" data-vehicle="{int(rejected.get("vehicle", 0))}" data-code="{escape(str(rejected.get("code", "")))}" fill="none">'
    ]
    for index, leg in enumerate(rejected.get("plan", ())):
        segment = layout.segments.get(int(leg["segment"]))
        if segment is None:
            continue  # an unknown-segment rejection names a segment the map lacks
        if index == offending:
            parts.append(
                f'<polyline class="rejected-leg" data-leg="{index}" data-segment="{segment.id}" points="{view.points(segment.waypoints)}" '
                f'stroke="{_CYCLE}" stroke-width="{3 * width:.2f}" stroke-opacity="0.6" stroke-linecap="round" stroke-linejoin="round"/>'
            )
        parts.append(
            f'<polyline class="rejected-leg-path" data-leg="{index}" data-segment="{segment.id}" points="{view.points(segment.waypoints)}" '
            f'stroke="{_REJECTED}" stroke-width="{width:.2f}" stroke-dasharray="{2 * width:.2f} {width:.2f}" stroke-linecap="round"/>'
        )
        tip, heading = _point_at(segment, 0.5)
        if leg.get("traverse") == Traverse.BACKWARD.value:
            heading += math.pi
        parts.append(_arrow(view, tip, heading, 0.3, _REJECTED, 'class="rejected-arrow"'))
    parts.append("</g>")
    return parts


def _alerts_svg(scenario: Scenario, frame: Frame, view: _Frame) -> list[str]:
    """Orange bands under the map for every segment that carries an alert in force."""
    parts = ['<g class="alerts">']
    for sid in sorted({alert.segment for alert in frame.alerts}):
        parts.append(
            f'<polyline class="alert" data-segment="{sid}" points="{view.points(scenario.layout.segments[sid].waypoints)}" '
            f'fill="none" stroke="{_ALERT}" stroke-opacity="0.85" stroke-width="{0.5 * view.scale:.2f}" '
            'stroke-linecap="round" stroke-linejoin="round"/>'
        )
    parts.append("</g>")
    return parts


def _contested_svg(scenario: Scenario, view: _Frame, stuck: Mapping[str, Any]) -> list[str]:
    """Purple bands under the map for the segments waiting vehicles need and others hold."""
    parts = ['<g class="contested">']
    for sid in contested_segments(stuck):
        if sid in scenario.layout.segments:
            parts.append(
                f'<polyline class="contested-segment" data-segment="{sid}" points="{view.points(scenario.layout.segments[sid].waypoints)}" '
                f'fill="none" stroke="{_CONTESTED}" stroke-opacity="0.45" stroke-width="{0.55 * view.scale:.2f}" '
                'stroke-linecap="round" stroke-linejoin="round"/>'
            )
    parts.append("</g>")
    return parts


def _waits_svg(scenario: Scenario, frame: Frame, view: _Frame, stuck: Mapping[str, Any]) -> list[str]:
    """An arrow from each waiting vehicle to each vehicle it waits for, red in a cycle; rings round root causes."""
    radius = {v.id: v.type.swept_radius for v in scenario.vehicles}
    parts = ['<g class="wait-for">']
    for source, target, waits, cycle in stuck_relations(stuck):
        if source not in frame.poses or target not in frame.poses:
            continue
        colour = _CYCLE if cycle else _WAITS
        kind = "wait-for" if waits else "planned-near"
        parts.append(
            _relation_arrow(
                view,
                frame.poses[source],
                frame.poses[target],
                radius[source],
                radius[target],
                colour,
                kind,
                cycle,
                source,
                target,
            )
        )
    for root in stuck.get("roots", ()):
        for vid in root.get("vehicles", ()):
            pose = frame.poses.get(int(vid))
            if pose is None:
                continue
            x, y = view.point((pose.x, pose.y))
            parts.append(
                f'<circle class="root-cause" data-vehicle="{int(vid)}" data-kind="{escape(str(root.get("kind", "")))}" cx="{x:.2f}" cy="{y:.2f}" '
                f'r="{(radius[int(vid)] + 0.25) * view.scale:.2f}" fill="none" stroke="{_CYCLE}" stroke-width="{0.1 * view.scale:.2f}"/>'
            )
    parts.append("</g>")
    return parts


def _relation_arrow(
    view: _Frame,
    a: Pose,
    b: Pose,
    from_radius: float,
    to_radius: float,
    colour: str,
    kind: str,
    cycle: bool,
    source: int,
    target: int,
) -> str:
    """A line from vehicle ``a``'s edge to vehicle ``b``'s edge with a head at ``b``."""
    dx, dy = b.x - a.x, b.y - a.y
    length = math.hypot(dx, dy)
    if length <= from_radius + to_radius:
        ux, uy, start, end = 1.0, 0.0, (a.x, a.y), (b.x, b.y)
    else:
        ux, uy = dx / length, dy / length
        start = (a.x + ux * from_radius, a.y + uy * from_radius)
        end = (b.x - ux * to_radius, b.y - uy * to_radius)
    width = (0.08 if kind == "wait-for" else 0.05) * view.scale
    dash = "" if kind == "wait-for" else f' stroke-dasharray="{width:.2f} {2 * width:.2f}"'
    head = _arrow(view, end, math.atan2(uy, ux), 0.45, colour, f'class="{kind}-head"')
    (x1, y1), (x2, y2) = view.point(start), view.point(end)
    return (
        f'<g class="{kind}{" cycle" if cycle else ""}" data-from="{source}" data-to="{target}">'
        f'<line x1="{x1:.2f}" y1="{y1:.2f}" x2="{x2:.2f}" y2="{y2:.2f}" stroke="{colour}" stroke-width="{width:.2f}"{dash}/>'
        f"{head}</g>"
    )


def _map_svg(scenario: Scenario, view: _Frame) -> list[str]:
    layout = scenario.layout
    parts = ['<g class="map">']
    for sid in sorted(layout.segments):
        parts.extend(_segment_svg(view, layout.segments[sid], _MAP, 0.05 * view.scale, arrow=0.25))
    parts.append("</g>")
    return parts


def _labels_svg(scenario: Scenario, view: _Frame) -> list[str]:
    """Segment labels (ids, and the site's names), drawn over the plans so an alert's segment can be read off."""
    return [
        '<g class="segment-labels" font-family="sans-serif" fill="#555555">',
        *_segment_labels(view, scenario.layout, 0.3 * view.scale),
        "</g>",
    ]


def _plans_svg(scenario: Scenario, frame: Frame, view: _Frame, colours: dict[int, tuple[str, float]]) -> list[str]:
    """Each vehicle's plan in its colour: fixed legs thick, planned legs thin and dashed."""
    layout = scenario.layout
    thick, thin = 0.2 * view.scale, 0.07 * view.scale
    parts: list[str] = []
    for vid in sorted(frame.plans):
        colour, opacity = colours[vid]
        parts.append(
            f'<g class="plan" data-vehicle="{vid}" stroke="{colour}" stroke-opacity="{opacity:.3f}" fill="none">'
        )
        for index, leg in enumerate(frame.plans[vid].legs):
            segment = layout.segments[leg.segment]
            kind = "fixed" if leg.fixed else "planned"
            style = (
                f'stroke-width="{thick:.2f}"'
                if leg.fixed
                else f'stroke-width="{thin:.2f}" stroke-dasharray="{3 * thin:.2f} {2 * thin:.2f}"'
            )
            parts.append(
                f'<polyline class="leg {kind}" data-segment="{leg.segment}" data-leg="{index}" '
                f'points="{view.points(segment.waypoints)}" {style} stroke-linecap="round" stroke-linejoin="round"/>'
            )
            # The traverse: an arrow in the middle of the leg, pointing the way the vehicle will drive.
            tip, heading = _point_at(segment, 0.5)
            if leg.traverse is Traverse.BACKWARD:
                heading += math.pi
            parts.append(_arrow(view, tip, heading, 0.3, colour, f'class="leg-arrow" fill-opacity="{opacity:.3f}"'))
        parts.append("</g>")
    return parts


def _vehicles_svg(
    scenario: Scenario, frame: Frame, view: _Frame, colours: dict[int, tuple[str, float]], font: float
) -> list[str]:
    """Rotated rectangles (length along the heading) with a white triangle at the nose and the id."""
    parts = ['<g class="vehicles" font-family="sans-serif">']
    for vehicle in sorted(scenario.vehicles, key=lambda v: v.id):
        pose = frame.poses[vehicle.id]
        colour, opacity = colours[vehicle.id]
        body, nose = _vehicle_outline(vehicle, pose)
        # The id beside the vehicle, on its left: never on the path ahead or behind it.
        side = 0.5 * vehicle.type.width + 0.9 * font / view.scale
        label_x, label_y = view.point((pose.x - side * math.sin(pose.heading), pose.y + side * math.cos(pose.heading)))
        parts += [
            f'<g class="vehicle" data-vehicle="{vehicle.id}" data-segment="{pose.segment}">',
            f'<polygon class="vehicle-body" points="{view.points(body)}" fill="{colour}" fill-opacity="{opacity:.3f}" '
            f'stroke="{_INK}" stroke-width="{0.03 * view.scale:.2f}"/>',
            f'<polygon class="vehicle-nose" points="{view.points(nose)}" fill="#ffffff"/>',
            f'<text class="vehicle-label" x="{label_x:.2f}" y="{label_y:.2f}" font-size="{font:.1f}" '
            f'font-weight="bold" text-anchor="middle" dominant-baseline="middle" fill="{_INK}" stroke="#ffffff" stroke-width="{0.25 * font:.2f}" '
            f'paint-order="stroke">{vehicle.id}</text>',
            *_disturbed_svg(vehicle, pose, view, font, frame.disturbed.get(vehicle.id)),
            "</g>",
        ]
    parts.append("</g>")
    return parts


def _contact_svg(scenario: Scenario, view: _Frame, contact: Mapping[str, Any]) -> list[str]:
    """Both footprints at the moment of contact in red outline, and a red ring where they first touched."""
    vehicles = {v.id: v for v in scenario.vehicles}
    parts = [
        f'<g class="contact" data-vehicles="{" ".join(str(f["vehicle"]) for f in contact["footprints"])}" fill="none">'
    ]
    for footprint in contact["footprints"]:
        pose = Pose(0, Traverse.FORWARD, Progress.FORWARD, footprint["x"], footprint["y"], footprint["heading"], 0.0)
        body, _ = _vehicle_outline(vehicles[footprint["vehicle"]], pose)
        parts.append(
            f'<polygon class="contact-footprint" data-vehicle="{footprint["vehicle"]}" points="{view.points(body)}" '
            f'stroke="{_CYCLE}" stroke-width="{0.06 * view.scale:.2f}"/>'
        )
    cx, cy = view.point((contact["x"], contact["y"]))
    parts += [
        f'<circle class="contact-place" cx="{cx:.2f}" cy="{cy:.2f}" r="{0.35 * view.scale:.2f}" stroke="{_CYCLE}" '
        f'stroke-width="{0.08 * view.scale:.2f}"/>',
        "</g>",
    ]
    return parts


def contact_moment(failure: Failure, frame: Frame, before: Frame | None) -> dict[str, Any] | None:
    """For a ``contact`` failure pictured at ``frame`` (the end of the step it began in; ``before``: the
    frame of the step before, None at the first step): the place and both footprints at the failure's
    moment, the poses interpolated between the two frames as the contact check does (centre along the
    straight line, heading along the shorter turn). None for any other failure."""
    if failure.kind != "contact":
        return None
    details = failure.details
    ids = [int(v) for v in details["vehicles"]]
    span = frame.time - before.time if before is not None else 0.0
    tau = 1.0 if before is None or span <= 0 else min(max((failure.time - before.time) / span, 0.0), 1.0)
    footprints = []
    for vid in ids:
        end = frame.poses[vid]
        start = before.poses[vid] if before is not None else end
        turn = math.remainder(end.heading - start.heading, math.tau)
        footprints.append(
            {
                "vehicle": vid,
                "x": start.x + tau * (end.x - start.x),
                "y": start.y + tau * (end.y - start.y),
                "heading": start.heading + tau * turn,
            }
        )
    return {"x": float(details["x"]), "y": float(details["y"]), "vehicles": ids, "footprints": footprints}


def _disturbed_svg(vehicle: Vehicle, pose: Pose, view: _Frame, font: float, kind: str | None) -> list[str]:
    """A dashed outline round a disturbed vehicle and ``STOP``/``SLOW`` on its right (the id is on its left)."""
    if kind is None:
        return []
    grown = replace(vehicle.type, length=vehicle.type.length + 0.5, width=vehicle.type.width + 0.5)
    outline, _ = _vehicle_outline(replace(vehicle, type=grown), pose)
    side = 0.5 * grown.width + 0.9 * font / view.scale
    x, y = view.point((pose.x + side * math.sin(pose.heading), pose.y - side * math.cos(pose.heading)))
    return [
        f'<polygon class="vehicle-disturbed" data-disturbed="{kind}" points="{view.points(outline)}" fill="none" stroke="{_DISTURBED}" '
        f'stroke-width="{0.08 * view.scale:.2f}" stroke-dasharray="{0.2 * view.scale:.2f} {0.1 * view.scale:.2f}"/>',
        f'<text class="vehicle-disturbed-label" x="{x:.2f}" y="{y:.2f}" font-size="{0.8 * font:.1f}" font-weight="bold" '
        f'text-anchor="middle" dominant-baseline="middle" fill="{_DISTURBED}" stroke="#ffffff" stroke-width="{0.2 * font:.2f}" '
        f'paint-order="stroke">{kind.upper()}</text>',
    ]


def _vehicle_outline(vehicle: Vehicle, pose: Pose) -> tuple[list[Point], list[Point]]:
    """The body's corners and the nose triangle's, in world metres, for ``pose``."""
    half_length, half_width = 0.5 * vehicle.type.length, 0.5 * vehicle.type.width
    ax, ay = math.cos(pose.heading), math.sin(pose.heading)  # along the nose
    nx, ny = -ay, ax  # to the vehicle's left

    def at(along: float, left: float) -> Point:
        return (pose.x + along * ax + left * nx, pose.y + along * ay + left * ny)

    body = [
        at(half_length, half_width),
        at(-half_length, half_width),
        at(-half_length, -half_width),
        at(half_length, -half_width),
    ]
    depth = min(0.6 * half_length, 1.2 * half_width)
    nose = [at(half_length, 0.0), at(half_length - depth, 0.7 * half_width), at(half_length - depth, -0.7 * half_width)]
    return body, nose


# -- the moment of failure ------------------------------------------------------------------------


def _step_of(failure: Failure, time_step: float, last_step: int) -> int:
    # Every event is stamped with the end of the step it happened in (the loop's convention).
    return min(max(round(failure.time / time_step) - 1, 0), last_step)


def failure_step(failures: Sequence[Failure], time_step: float, last_step: int) -> tuple[int, Failure] | None:
    """The step (0..``last_step``) of the earliest failure that has a moment, and that failure.

    A failure at time t belongs to the step that ended at t (step ``t / time_step - 1``). Hash failures
    have no moment: when they are all there is, the picture is of the last step. Ties go to the failure
    listed first. An interrupted run is pictured at its last step, the moment it was stopped at (what
    was happening then is what its user wanted to see). None without failures.
    """
    for failure in failures:
        if failure.kind == "interrupted":
            return last_step, failure
    timed = [(_step_of(f, time_step, last_step), index) for index, f in enumerate(failures) if f.kind not in MOMENTLESS]
    if timed:
        step, index = min(timed)
        return step, failures[index]
    return (last_step, failures[0]) if failures else None


def _lead(kind: str, text: str) -> str:
    """``kind: text``, or ``text`` alone when it already says what kind of failure it is."""
    return text if kind[:6].lower() in text[:40].lower() else f"{kind}: {text}"


def failure_caption(failure: Failure, failures: Sequence[Failure] = (), *, at: float | None = None) -> str:
    """``t = 12.30 s — <the failure's first line>``, then a line per hash failure among ``failures``.

    ``at``: the time of the picture, for a failure without a moment of its own (a hash failure).
    """
    when = failure.time if failure.kind not in MOMENTLESS or at is None else at
    lines = [f"t = {when:.2f} s \u2014 {_lead(failure.kind, first_line(failure.message) or failure.kind)}"]
    for other in failures:
        if other is not failure and other.kind in MOMENTLESS:
            lines.append(f"also {other.kind}: {first_line(other.message)}")
    return "\n".join(lines)


def picture_overlays(failure: Failure) -> tuple[Mapping[str, Any] | None, Mapping[str, Any] | None]:
    """What a failure adds to its picture: who waits for whom (``stuck``) and the refused plan (``rejected``)."""
    rejected = failure.details if failure.kind == "rejection" and failure.details.get("plan") else None
    return stuck_details(failure), rejected


def failure_picture(scenario: Scenario, result: RunResult) -> tuple[int, str] | None:
    """The step of ``result``'s first failure with a moment and its picture; None for a passed run or no kept trace."""
    if result.passed or result.trace is None or len(result.trace.lines) < 2:
        return None
    lines = result.trace.lines
    found = failure_step(result.failures, scenario.settings.time_step, last_step=len(lines) - 2)
    if found is None:
        return None
    step, failure = found
    frame, orders = frame_and_orders_at(scenario, lines, step)
    caption = failure_caption(failure, result.failures, at=frame.time)
    stuck, rejected = picture_overlays(failure)
    before = frame_at(scenario, lines, step - 1) if failure.kind == "contact" and step > 0 else None
    contact = contact_moment(failure, frame, before)
    stall = failure.details if failure.kind == "stall" and "vehicle" in failure.details else None
    if stall is not None and "held up" not in caption.splitlines()[0]:
        held = ", ".join(str(o) for o in stall.get("orders", ())) or "none"
        caption += f"\norders held up: {held}"
    return step, render_frame_svg(
        scenario, frame, caption=caption, stuck=stuck, rejected=rejected, contact=contact, orders=orders, stall=stall
    )


def stuck_details(failure: Failure) -> Mapping[str, Any] | None:
    """Who waits for whom, when ``failure`` is a deadlock, timeout or interruption that explains it; else None."""
    return failure.details if failure.kind in _STUCK_KINDS and "vehicles" in failure.details else None
