"""The transport orders in a still picture (issue 45): who waits where, who carries what, a stalled vehicle.

Drawn over :mod:`fleetsim.recording.picture`'s fleet from the orders at the pictured step
(:mod:`fleetsim.recording.orders`): an amber diamond with a count at each station where orders wait (their
first stop's segment), each vehicle's order as a label in its colour beside it (a dark load on its body
once it has picked the order up, a ring while it dwells at a stop) and, for a stall, the stalled vehicle
in a red dashed ring with ``STALLED`` and the orders it holds up.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from xml.sax.saxutils import escape

from fleetsim.enums import Traverse
from fleetsim.recording.colours import CYCLE, hex_colour
from fleetsim.recording.orders import OrderState
from fleetsim.recording.replay import Frame
from fleetsim.recording.svg import _Frame
from fleetsim.scenario import Scenario

__all__ = ["ORDERS_LEGEND", "STALL_LEGEND", "orders_svg", "stall_svg"]

_WAITING, _WAITING_EDGE, _INK = "#ffb300", "#7a4f00", "#111111"
_RED = hex_colour(CYCLE)
ORDERS_LEGEND = (
    "amber diamond: orders waiting at a station (how many) \u00b7 label: the vehicle's order "
    "(dark load: picked up; ring: dwelling at a stop)"
)
STALL_LEGEND = "red dashed ring: the stalled vehicle (STALLED), with the orders it holds up"


def _ink_on(colour: str) -> str:
    """Black or white, whichever reads on ``colour`` (``#rrggbb``)."""
    red, green, blue = (int(colour[k : k + 2], 16) for k in (1, 3, 5))
    return _INK if 0.299 * red + 0.587 * green + 0.114 * blue > 150 else "#ffffff"


def orders_svg(
    scenario: Scenario,
    frame: Frame,
    view: _Frame,
    orders: OrderState,
    colours: Mapping[int, tuple[str, float]],
    font: float,
) -> list[str]:
    """The stations with waiting orders and each vehicle's order, loaded or dwelling."""
    layout = scenario.layout
    parts = ['<g class="orders" font-family="sans-serif">']
    for segment, waiting in orders.waiting.items():
        if segment not in layout.segments or not waiting:
            continue
        x, y, _ = layout.segments[segment].pose_at(layout.segments[segment].length / 2, Traverse.FORWARD)
        cx, cy = view.point((x, y))
        r = 0.45 * view.scale + 0.15 * font * (len(str(len(waiting))) - 1)
        diamond = f"{cx:.2f},{cy - r:.2f} {cx + r:.2f},{cy:.2f} {cx:.2f},{cy + r:.2f} {cx - r:.2f},{cy:.2f}"
        parts += [
            f'<g class="waiting" data-segment="{segment}" data-count="{len(waiting)}" data-orders="{escape(" ".join(waiting))}">',
            f'<polygon points="{diamond}" fill="{_WAITING}" stroke="{_WAITING_EDGE}" stroke-width="{0.04 * view.scale:.2f}"/>',
            f'<text x="{cx:.2f}" y="{cy:.2f}" font-size="{0.8 * font:.1f}" font-weight="bold" text-anchor="middle" '
            f'dominant-baseline="central" fill="{_INK}">{len(waiting)}</text>',
            "</g>",
        ]
    vehicles = {v.id: v for v in scenario.vehicles}
    for vid, carry in orders.carry.items():
        pose = frame.poses.get(vid)
        if pose is None or not carry.orders:
            continue
        kind = vehicles[vid].type
        colour = colours[vid][0]
        parts.append(
            f'<g class="carry" data-vehicle="{vid}" data-order="{escape(carry.orders[0])}" data-loaded="{int(carry.loaded)}">'
        )
        x, y = view.point((pose.x, pose.y))
        if carry.loaded:
            side = 0.45 * min(kind.length, kind.width) * view.scale
            angle = -math.degrees(pose.heading)
            parts.append(
                f'<rect class="loaded" x="{x - side / 2:.2f}" y="{y - side / 2:.2f}" width="{side:.2f}" height="{side:.2f}" '
                f'fill="{_INK}" transform="rotate({angle:.2f} {x:.2f} {y:.2f})"/>'
            )
        if carry.dwell is not None:
            parts.append(
                f'<circle class="dwelling" cx="{x:.2f}" cy="{y:.2f}" r="{(kind.swept_radius + 0.2) * view.scale:.2f}" '
                f'fill="none" stroke="{colour}" stroke-width="{0.08 * view.scale:.2f}"/>'
            )
        # The order on the vehicle's right (its id is on its left): [s12 2/2]
        text = carry.orders[0] + (f" {carry.stop + 1}/{carry.stops}" if carry.stops else "")
        text += f" +{len(carry.orders) - 1}" if len(carry.orders) > 1 else ""
        side = 0.5 * kind.width + 0.9 * font / view.scale
        lx, ly = view.point((pose.x + side * math.sin(pose.heading), pose.y - side * math.cos(pose.heading)))
        width, height = 0.62 * 0.8 * font * len(text) + 0.6 * font, 1.2 * font
        parts += [
            f'<rect class="order-badge" x="{lx - width / 2:.2f}" y="{ly - height / 2:.2f}" width="{width:.2f}" height="{height:.2f}" '
            f'rx="{0.2 * font:.2f}" fill="{colour}" stroke="{_INK}" stroke-width="{0.06 * font:.2f}"/>',
            f'<text class="order-label" x="{lx:.2f}" y="{ly:.2f}" font-size="{0.8 * font:.1f}" font-weight="bold" '
            f'text-anchor="middle" dominant-baseline="central" fill="{_ink_on(colour)}">{escape(text)}</text>',
            "</g>",
        ]
    parts.append("</g>")
    return parts


def stall_svg(
    scenario: Scenario, frame: Frame, view: _Frame, vehicle: int, held: Sequence[str], font: float
) -> list[str]:
    """A red dashed ring round the stalled vehicle, ``STALLED`` and the orders it holds up below it."""
    pose = frame.poses.get(vehicle)
    kind = next((v.type for v in scenario.vehicles if v.id == vehicle), None)
    if pose is None or kind is None:
        return []
    x, y = view.point((pose.x, pose.y))
    r = (kind.swept_radius + 0.45) * view.scale
    words = "STALLED" + (f": {', '.join(held)}" if held else "")
    return [
        f'<g class="stalled" data-vehicle="{vehicle}" data-orders="{escape(" ".join(held))}">',
        f'<circle cx="{x:.2f}" cy="{y:.2f}" r="{r:.2f}" fill="none" stroke="{_RED}" stroke-width="{0.1 * view.scale:.2f}" '
        f'stroke-dasharray="{0.25 * view.scale:.2f} {0.15 * view.scale:.2f}"/>',
        f'<text class="stalled-label" x="{x:.2f}" y="{y + r + 0.9 * font:.2f}" font-family="sans-serif" font-size="{0.8 * font:.1f}" '
        f'font-weight="bold" text-anchor="middle" fill="{_RED}" stroke="#ffffff" stroke-width="{0.2 * font:.2f}" '
        f'paint-order="stroke">{escape(words)}</text>',
        "</g>",
    ]
