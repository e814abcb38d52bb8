"""A capacity search's curves as inline SVG, drawn as the sweep report draws its plots (no library).

Each plot is one ``<svg>`` with a ``<title>`` and a ``data-plot`` attribute (``capacity-throughput``,
``capacity-service-time``): x is the offered rate (orders per hour), y the figure; each seed's run is a
dot, the mean over seeds a line, the capacity's bracket a shaded band, and the throughput plot has the
demand (y = x) dashed: a fleet that keeps up stays on it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from html import escape

from fleetsim.sweep.plots import PALETTE

__all__ = ["Curve", "curve_plot"]

WIDTH, HEIGHT, LEFT, RIGHT, TOP, BOTTOM = 640, 300, 64, 24, 40, 44


@dataclass(frozen=True, slots=True)
class Curve:
    """One figure against the offered rate: a dot per run (``points``), a line through the means."""

    name: str
    points: Sequence[tuple[float, float]]

    def means(self) -> list[tuple[float, float]]:
        by_rate: dict[float, list[float]] = {}
        for x, y in self.points:
            by_rate.setdefault(x, []).append(y)
        return [(x, sum(ys) / len(ys)) for x, ys in sorted(by_rate.items())]


def _ticks(high: float) -> list[float]:
    """Round ticks from 0 to ``high``: steps of 1, 2 or 5 times a power of ten, four to ten of them."""
    if high <= 0:
        return [0.0]
    power = 10 ** math.floor(math.log10(high / 4))
    step = next(power * m for m in (1, 2, 5, 10) if high / (power * m) <= 10)
    return [step * k for k in range(int(high // step) + 1)]


def curve_plot(
    kind: str,
    title: str,
    y_label: str,
    curves: Sequence[Curve],
    bracket: tuple[float | None, float | None],
    *,
    diagonal: bool = False,
    notes: Mapping[str, str] | None = None,
) -> str:
    """Curves of a figure against the offered rate, the bracket [highest sustained, lowest not) shaded."""
    xs = [x for curve in curves for x, _ in curve.points] or [0.0, 1.0]
    ys = [y for curve in curves for _, y in curve.points] or [0.0, 1.0]
    x_high = max(xs) * 1.05
    y_high = max(max(ys), x_high if diagonal else 0.0) * 1.05 or 1.0

    def px(x: float) -> float:
        return LEFT + x / x_high * (WIDTH - LEFT - RIGHT)

    def py(y: float) -> float:
        return HEIGHT - BOTTOM - y / y_high * (HEIGHT - TOP - BOTTOM)

    body: list[str] = []
    low, high = bracket
    if low is not None or high is not None:
        left, right = px(low or 0.0), px(high if high is not None else x_high)
        body.append(
            f'<rect x="{left:.1f}" y="{TOP}" width="{max(right - left, 1):.1f}" height="{HEIGHT - TOP - BOTTOM}" '
            f'fill="#fdd835" fill-opacity="0.35"><title>capacity bracket</title></rect>'
        )
    body.append(f'<line x1="{LEFT}" y1="{py(0):.1f}" x2="{WIDTH - RIGHT}" y2="{py(0):.1f}" stroke="#999"/>')
    body.append(f'<line x1="{LEFT}" y1="{py(0):.1f}" x2="{LEFT}" y2="{TOP}" stroke="#999"/>')
    for tick in _ticks(x_high):
        body.append(f'<text x="{px(tick):.1f}" y="{py(0) + 14:.1f}" font-size="10" text-anchor="middle" fill="#555">{tick:.4g}</text>')  # fmt: skip
    for tick in _ticks(y_high):
        body.append(f'<text x="{LEFT - 4}" y="{py(tick) + 3:.1f}" font-size="10" text-anchor="end" fill="#555">{tick:.4g}</text>')  # fmt: skip
    body.append(f'<text x="{WIDTH - RIGHT}" y="{HEIGHT - 8}" font-size="11" text-anchor="end">offered rate (orders/h)</text>')  # fmt: skip
    body.append(f'<text x="{LEFT}" y="{TOP - 6}" font-size="11">{escape(y_label)}</text>')
    if diagonal:
        body.append(
            f'<line x1="{px(0):.1f}" y1="{py(0):.1f}" x2="{px(x_high):.1f}" y2="{py(x_high):.1f}" '
            f'stroke="#555" stroke-dasharray="4 3"><title>demand: throughput = offered rate</title></line>'
        )
    for index, curve in enumerate(curves):
        colour = PALETTE[index % len(PALETTE)]
        line = " ".join(f"{px(x):.1f},{py(y):.1f}" for x, y in curve.means())
        body.append(f'<polyline points="{line}" fill="none" stroke="{colour}" stroke-width="2"/>')
        body += [
            f'<circle cx="{px(x):.1f}" cy="{py(y):.1f}" r="2.5" fill="{colour}" fill-opacity="0.6"/>'
            for x, y in curve.points
        ]
        body.append(
            f'<text x="{WIDTH - RIGHT - 4}" y="{TOP + 14 * index + 12}" font-size="11" text-anchor="end" fill="{colour}">{escape(curve.name)}</text>'
        )
    for index, (label, text) in enumerate((notes or {}).items()):
        body.append(f'<text x="{LEFT + 6}" y="{TOP + 14 * index + 12}" font-size="10" fill="#555">{escape(label)}: {escape(text)}</text>')  # fmt: skip
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" data-plot="{escape(kind)}" width="{WIDTH}" height="{HEIGHT}" '
        f'viewBox="0 0 {WIDTH} {HEIGHT}" role="img"><title>{escape(title)}</title>'
        f'<text x="8" y="18" font-size="13" font-weight="bold">{escape(title)}</text>{"".join(body)}</svg>'
    )
