"""Every colour a recording gives a meaning to, and one colour per vehicle that never takes one of them.

One place for both, shared by every recording (MCAP markers, URDF, SVG pictures): the colours reserved
for what the pictures point out (collision alerts, wait-for cycles and root causes, contested segments,
rejected plans, disturbed vehicles, who waits for whom, the plain map), and the vehicles' palette, every
colour of which is perceptibly distinct from every reserved one (CIEDE2000 colour difference at least
:data:`MIN_DIFFERENCE`), so a vehicle is never read as an alert or a cycle.

A vehicle type's ``color`` wins (the user chose it, even a reserved one); otherwise vehicles get the
palette by their position in id order, so the same scenario is drawn in the same colours in RViz,
Foxglove and the failure picture, on every machine.
"""

from __future__ import annotations

import colorsys
import itertools
import math
import threading
from collections.abc import Iterator, Mapping

from fleetsim.scenario import RGBA, Scenario

__all__ = [
    "ALERT",
    "CONTESTED",
    "CYCLE",
    "DISTURBED",
    "MAP",
    "MAP_RVIZ",
    "MIN_DIFFERENCE",
    "REJECTED",
    "RESERVED",
    "WAITS",
    "colour_difference",
    "hex_colour",
    "palette_colour",
    "svg_colour",
    "vehicle_colours",
    "with_alpha",
]


def _rgba(text: str) -> RGBA:
    return (int(text[1:3], 16) / 255, int(text[3:5], 16) / 255, int(text[5:7], 16) / 255, 1.0)


ALERT = _rgba("#ff8c00")  # orange: segments with a collision alert in force, and their labels
CYCLE = _rgba("#d0021b")  # red: waits inside a wait-for cycle, root-cause rings, the leg a check refused
CONTESTED = _rgba("#8e44ad")  # purple: segments waiting vehicles need and others hold
REJECTED = _rgba("#d6008f")  # magenta: a rejected plan
DISTURBED = _rgba("#e6007e")  # magenta: the outline of a vehicle a disturbance stops or slows
WAITS = _rgba("#2c3e50")  # dark slate: who waits for whom, outside a cycle
MAP = _rgba("#a8a8a8")  # grey: the plain map in the pictures
MAP_RVIZ = _rgba("#8c94a6")  # bluish grey: the plain map on RViz's dark background
RESERVED: Mapping[str, RGBA] = {
    "collision alert": ALERT,
    "wait-for cycle, root cause": CYCLE,
    "contested segment": CONTESTED,
    "rejected plan": REJECTED,
    "disturbed vehicle": DISTURBED,
    "waits for": WAITS,
    "map": MAP,
    "map (RViz)": MAP_RVIZ,
}
# CIEDE2000 units: about 2 is just noticeable side by side; 20 and more reads as another colour at a glance.
MIN_DIFFERENCE = 20.0

# Tableau 10's blue and green, then hues chosen away from the reserved ones (its red, orange, purple,
# pink and grey are reserved colours or too near them): well separated, and they print and project well.
_PALETTE: tuple[RGBA, ...] = tuple(
    _rgba(text)
    for text in (
        "#1f77b4",  # blue
        "#2ca02c",  # green
        "#8c6d31",  # ochre brown
        "#17becf",  # cyan
        "#bcbd22",  # olive
        "#f7b6d2",  # light pink
        "#006d6f",  # teal
        "#1b5e20",  # dark green
    )
)
_GOLDEN = 0.618033988749895  # hue step that keeps any number of further hues apart


def palette_colour(position: int) -> RGBA:
    """The palette colour of the vehicle at ``position`` (0-based) in id order; alpha 1."""
    if position < 0:
        msg = f"position={position!r} must be >= 0"
        raise ValueError(msg)
    if position < len(_PALETTE):
        return _PALETTE[position]
    extra = position - len(_PALETTE)
    with _LOCK:
        while len(_GENERATED) <= extra:
            _GENERATED.append(next(_FURTHER))
        return _GENERATED[extra]


def _further_colours() -> Iterator[RGBA]:
    """The colours after the fixed list: golden-ratio hue steps, alternating brightness so neighbours
    differ twice, leaving out every candidate too near a reserved colour."""
    for index in itertools.count():
        hue = (0.6 + index * _GOLDEN) % 1.0
        value = 0.85 if index % 2 == 0 else 0.6
        r, g, b = colorsys.hsv_to_rgb(hue, 0.7, value)
        colour = (round(r, 3), round(g, 3), round(b, 3), 1.0)
        if all(colour_difference(colour, reserved) >= MIN_DIFFERENCE for reserved in RESERVED.values()):
            yield colour


# Made once, in order, as far as the largest fleet drawn needs (a cache: the same colours every time).
_FURTHER = _further_colours()
_GENERATED: list[RGBA] = []
_LOCK = threading.Lock()


def vehicle_colours(scenario: Scenario) -> dict[int, RGBA]:
    """Each vehicle's colour (RGBA, 0..1) by id: its type's ``color`` if set, else the palette's."""
    colours: dict[int, RGBA] = {}
    for position, vehicle in enumerate(sorted(scenario.vehicles, key=lambda v: v.id)):
        own = vehicle.type.color
        colours[vehicle.id] = own if own is not None else palette_colour(position)
    return colours


def svg_colour(colour: RGBA) -> tuple[str, float]:
    """``("#rrggbb", opacity)`` for an RGBA colour with 0..1 channels (clamped)."""
    r, g, b, a = (min(max(float(c), 0.0), 1.0) for c in colour)
    return f"#{round(r * 255):02x}{round(g * 255):02x}{round(b * 255):02x}", a


def hex_colour(colour: RGBA) -> str:
    """``#rrggbb`` of ``colour`` (its alpha left out)."""
    return svg_colour(colour)[0]


def with_alpha(colour: RGBA, alpha: float) -> RGBA:
    """``colour`` with opacity ``alpha``."""
    return (colour[0], colour[1], colour[2], alpha)


# -- colour difference ----------------------------------------------------------------------------


def _lab(colour: RGBA) -> tuple[float, float, float]:
    """CIELAB (D65) of an sRGB colour with 0..1 channels."""

    def linear(c: float) -> float:
        return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4

    r, g, b = (linear(min(max(float(c), 0.0), 1.0)) for c in colour[:3])
    x = (0.4124564 * r + 0.3575761 * g + 0.1804375 * b) / 0.95047
    y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b
    z = (0.0193339 * r + 0.1191920 * g + 0.9503041 * b) / 1.08883

    def f(t: float) -> float:
        return t ** (1 / 3) if t > 216 / 24389 else (24389 / 27 * t + 16) / 116

    fx, fy, fz = f(x), f(y), f(z)
    return 116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)


def colour_difference(a: RGBA, b: RGBA) -> float:
    """The CIEDE2000 difference of two colours' RGB (alpha ignored): 0 for equal colours, ~100 black to white."""
    return _ciede2000(_lab(a), _lab(b))


def _ciede2000(first: tuple[float, float, float], second: tuple[float, float, float]) -> float:
    """CIEDE2000 of two CIELAB colours (Sharma, Wu and Dalal 2005, the formulas as numbered there)."""
    (l1, a1, b1), (l2, a2, b2) = first, second
    mean_chroma = (math.hypot(a1, b1) + math.hypot(a2, b2)) / 2
    g = 0.5 * (1 - math.sqrt(mean_chroma**7 / (mean_chroma**7 + 25.0**7)))
    a1, a2 = (1 + g) * a1, (1 + g) * a2
    c1, c2 = math.hypot(a1, b1), math.hypot(a2, b2)
    h1, h2 = math.degrees(math.atan2(b1, a1)) % 360, math.degrees(math.atan2(b2, a2)) % 360
    dh = 0.0 if c1 * c2 == 0 else (h2 - h1 + 180) % 360 - 180
    d_hue = 2 * math.sqrt(c1 * c2) * math.sin(math.radians(dh / 2))
    mean_l, mean_c = (l1 + l2) / 2, (c1 + c2) / 2
    if c1 * c2 == 0:
        mean_h = h1 + h2
    elif abs(h1 - h2) <= 180:
        mean_h = (h1 + h2) / 2
    else:
        mean_h = (h1 + h2 + 360) / 2 if h1 + h2 < 360 else (h1 + h2 - 360) / 2
    t = (
        1
        - 0.17 * math.cos(math.radians(mean_h - 30))
        + 0.24 * math.cos(math.radians(2 * mean_h))
        + 0.32 * math.cos(math.radians(3 * mean_h + 6))
        - 0.20 * math.cos(math.radians(4 * mean_h - 63))
    )
    s_l = 1 + 0.015 * (mean_l - 50) ** 2 / math.sqrt(20 + (mean_l - 50) ** 2)
    s_c = 1 + 0.045 * mean_c
    s_h = 1 + 0.015 * mean_c * t
    rotation = -math.sin(math.radians(60 * math.exp(-(((mean_h - 275) / 25) ** 2)))) * (
        2 * math.sqrt(mean_c**7 / (mean_c**7 + 25.0**7))
    )
    dl, dc, dhh = (l2 - l1) / s_l, (c2 - c1) / s_c, d_hue / s_h
    return math.sqrt(dl**2 + dc**2 + dhh**2 + rotation * dc * dhh)
