"""The report's plots as inline SVG, drawn here: no plotting library, no fonts or scripts to fetch.

Each function returns one ``<svg>`` element with a ``<title>`` and a ``data-plot`` attribute naming its
kind (``distribution``, ``paired-differences``, ``fleet-size``), so a reader and a test can find it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from html import escape

import numpy as np

__all__ = ["PALETTE", "differences_plot", "distribution_plot", "fleet_size_plot"]

PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f")
WIDTH, ROW, LEFT, RIGHT, TOP = 640, 34, 200, 24, 36


def _scale(low: float, high: float, width: float) -> tuple[float, float]:
    """(origin, pixels per unit) mapping [low, high] onto [LEFT, LEFT + width]."""
    span = high - low or 1.0
    return low - span * 0.04, width / (span * 1.08)


def _ticks(low: float, high: float) -> list[float]:
    step = (high - low) / 4 if high > low else 1.0
    return [low + step * k for k in range(5)]


def _axis(x0: float, per: float, low: float, high: float, y: float) -> list[str]:
    parts = [f'<line x1="{LEFT}" y1="{y}" x2="{WIDTH - RIGHT}" y2="{y}" stroke="#999"/>']
    for tick in _ticks(low, high):
        x = LEFT + (tick - x0) * per
        parts.append(
            f'<text x="{x:.1f}" y="{y + 14}" font-size="10" text-anchor="middle" fill="#555">{tick:.4g}</text>'
        )
    return parts


def _svg(kind: str, title: str, height: float, body: Sequence[str]) -> str:
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" data-plot="{kind}" width="{WIDTH}" height="{height:.0f}" '
        f'viewBox="0 0 {WIDTH} {height:.0f}" role="img"><title>{escape(title)}</title>'
        f'<text x="8" y="18" font-size="13" font-weight="bold">{escape(title)}</text>{"".join(body)}</svg>'
    )


def distribution_plot(title: str, groups: Mapping[str, Sequence[float]]) -> str:
    """A box plot per group (quartiles, whiskers to min and max, the mean as a dot)."""
    values = [v for vs in groups.values() for v in vs]
    low, high = (min(values), max(values)) if values else (0.0, 1.0)
    x0, per = _scale(low, high, WIDTH - LEFT - RIGHT)
    body: list[str] = []
    for index, (name, vs) in enumerate(groups.items()):
        y = TOP + index * ROW + ROW / 2
        colour = PALETTE[index % len(PALETTE)]
        body.append(
            f'<text x="{LEFT - 6}" y="{y + 4}" font-size="11" text-anchor="end">{escape(name[-30:])} (n={len(vs)})</text>'
        )
        if not vs:
            continue
        q0, q1, q2, q3, q4 = (float(q) for q in np.percentile(vs, [0, 25, 50, 75, 100]))
        px = [LEFT + (q - x0) * per for q in (q0, q1, q2, q3, q4)]
        mean = LEFT + (float(np.mean(vs)) - x0) * per
        body += [
            f'<line x1="{px[0]:.1f}" y1="{y}" x2="{px[4]:.1f}" y2="{y}" stroke="{colour}"/>',
            f'<rect x="{px[1]:.1f}" y="{y - 9}" width="{max(px[3] - px[1], 1):.1f}" height="18" fill="{colour}" fill-opacity="0.3" stroke="{colour}"/>',
            f'<line x1="{px[2]:.1f}" y1="{y - 9}" x2="{px[2]:.1f}" y2="{y + 9}" stroke="{colour}" stroke-width="2"/>',
            f'<circle cx="{mean:.1f}" cy="{y}" r="3" fill="#000"/>',
        ]
    axis_y = TOP + len(groups) * ROW + 4
    body += _axis(x0, per, low, high, axis_y)
    return _svg("distribution", title, axis_y + 24, body)


def differences_plot(title: str, differences: Sequence[float], low: float, high: float) -> str:
    """Per-scenario paired differences, sorted, with zero and the interval of the mean shaded."""
    values = sorted(differences)
    lo, hi = (min([*values, 0.0, low]), max([*values, 0.0, high])) if values else (-1.0, 1.0)
    height = 180
    y0, per_y = _scale(lo, hi, height - TOP - 30)

    def y(v: float) -> float:
        return height - 30 - (v - y0) * per_y

    step = (WIDTH - LEFT - RIGHT) / max(len(values), 1)
    body = [
        f'<rect x="{LEFT}" y="{y(high):.1f}" width="{WIDTH - LEFT - RIGHT}" height="{max(y(low) - y(high), 1):.1f}" fill="#fdd835" fill-opacity="0.35"/>',
        f'<line x1="{LEFT}" y1="{y(0):.1f}" x2="{WIDTH - RIGHT}" y2="{y(0):.1f}" stroke="#555"/>',
        f'<text x="{LEFT - 6}" y="{y(0) + 4:.1f}" font-size="10" text-anchor="end">0</text>',
        f'<text x="{LEFT - 6}" y="{y(hi) + 10:.1f}" font-size="10" text-anchor="end">{hi:.4g}</text>',
        f'<text x="{LEFT - 6}" y="{y(lo):.1f}" font-size="10" text-anchor="end">{lo:.4g}</text>',
        f'<text x="{LEFT}" y="{height - 8}" font-size="10" fill="#555">{len(values)} scenarios, sorted; band: 95% CI of the mean</text>',
    ]
    body += [
        f'<circle cx="{LEFT + step * (k + 0.5):.1f}" cy="{y(v):.1f}" r="2.5" fill="{PALETTE[1] if v < 0 else PALETTE[0]}"/>'
        for k, v in enumerate(values)
    ]
    return _svg("paired-differences", title, height, body)


def fleet_size_plot(title: str, series: Mapping[str, Mapping[int, float]]) -> str:
    """One line per planner: the metric's mean at each fleet size."""
    xs = sorted({x for points in series.values() for x in points})
    ys = [v for points in series.values() for v in points.values()]
    height = 200
    if not xs:
        return _svg("fleet-size", title, 60, ['<text x="8" y="40" font-size="11">no runs</text>'])
    x0, per_x = _scale(xs[0], xs[-1], WIDTH - LEFT - RIGHT)
    y0, per_y = _scale(min(ys), max(ys), height - TOP - 40)
    body: list[str] = []
    for index, (name, points) in enumerate(series.items()):
        colour = PALETTE[index % len(PALETTE)]
        coords = [(LEFT + (x - x0) * per_x, height - 34 - (points[x] - y0) * per_y) for x in xs if x in points]
        path = " ".join(f"{px:.1f},{py:.1f}" for px, py in coords)
        body.append(f'<polyline points="{path}" fill="none" stroke="{colour}" stroke-width="2"/>')
        body += [f'<circle cx="{px:.1f}" cy="{py:.1f}" r="3" fill="{colour}"/>' for px, py in coords]
        body.append(
            f'<text x="8" y="{TOP + 14 * index + 12}" font-size="11" fill="{colour}">{escape(name[-28:])}</text>'
        )
    body.append(
        f'<text x="8" y="{TOP + 14 * len(series) + 12}" font-size="10" fill="#555">y: {min(ys):.4g} .. {max(ys):.4g}</text>'
    )
    body += _axis(x0, per_x, xs[0], xs[-1], height - 30)
    return _svg("fleet-size", title, height, body)
