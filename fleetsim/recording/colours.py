"""One colour per vehicle, shared by every recording (MCAP markers, URDF, SVG pictures).

A vehicle type's ``color`` wins; otherwise vehicles get a fixed palette by their position in id order,
so the same scenario is drawn in the same colours in RViz, Foxglove and the failure picture, on every
machine. The palette leaves out orange (collision alerts) and grey (the plain map), so a vehicle is
never mistaken for either.
"""

from __future__ import annotations

import colorsys

from fleetsim.scenario import RGBA, Scenario

__all__ = ["palette_colour", "svg_colour", "vehicle_colours"]

# Tableau 10 without its orange and grey: well-separated hues that print and project well.
_PALETTE: tuple[RGBA, ...] = (
    (0.122, 0.467, 0.706, 1.0),  # blue
    (0.173, 0.627, 0.173, 1.0),  # green
    (0.839, 0.153, 0.157, 1.0),  # red
    (0.580, 0.404, 0.741, 1.0),  # purple
    (0.549, 0.337, 0.294, 1.0),  # brown
    (0.890, 0.467, 0.761, 1.0),  # pink
    (0.737, 0.741, 0.133, 1.0),  # olive
    (0.090, 0.745, 0.812, 1.0),  # cyan
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
    # Beyond the fixed list: golden-ratio hue steps, alternating brightness so neighbours differ twice.
    hue = (0.6 + extra * _GOLDEN) % 1.0
    value = 0.85 if extra % 2 == 0 else 0.6
    r, g, b = colorsys.hsv_to_rgb(hue, 0.7, value)
    return (round(r, 3), round(g, 3), round(b, 3), 1.0)


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
