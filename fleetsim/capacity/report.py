"""A capacity search reported from its results document: a Markdown summary (printed for CI logs) and a
self-contained HTML page with the curves of throughput and service time against the offered rate.

The page is built as the sweep report's is: inline CSS and SVG, no script, and a Content-Security-Policy
that refuses every request, so it opens the same offline, from a CI artifact.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from html import escape
from typing import Any

from fleetsim.capacity.gate import CapacityVerdict
from fleetsim.capacity.plots import Curve, curve_plot

__all__ = ["headline", "html_page", "markdown", "rate_table", "rules"]

_CSP = "default-src 'none'; style-src 'unsafe-inline'; img-src data:"
_STYLE = """
body{font:14px/1.4 system-ui,sans-serif;margin:24px;color:#222;max-width:1100px}
h1{font-size:22px}h2{font-size:18px;margin-top:28px;border-bottom:1px solid #ddd}
table{border-collapse:collapse;margin:8px 0}th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}
th{background:#f3f3f3}td:last-child,th:last-child{text-align:left}
.plots{display:flex;flex-wrap:wrap;gap:12px}.plots svg{border:1px solid #eee;background:#fff}
.fail{color:#b71c1c}.ok{color:#1b5e20}.capacity{font-size:18px}
"""
_HEAD = [
    "rate (orders/h)", "sustained", "seeds sustaining", "throughput (orders/h)", "arrivals (orders/h)",
    "service median (s)", "service p95 (s)", "backlog slope (orders/h)", "why not",
]  # fmt: skip


def _g(value: float | None) -> str:
    return "–" if value is None else f"{value:.4g}"


def _mean(values: Sequence[float | None]) -> float | None:
    known = [v for v in values if v is not None]
    return sum(known) / len(known) if known else None


def headline(document: Mapping[str, Any]) -> str:
    """The capacity and its bracket in a sentence."""
    low, high = document["sustained"], document["unsustained"]
    seeds = ", ".join(map(str, document["seeds"]))
    if low is None:
        return f"capacity below {high:g} orders/h: no rate tried was sustained by every seed ({seeds})"
    if high is None:
        return f"capacity at least {low:g} orders/h: every rate tried was sustained by every seed ({seeds})"
    return f"capacity {low:g} orders/h: sustained by every seed ({seeds}) at {low:g}, not at {high:g} orders/h"


def _spread(document: Mapping[str, Any]) -> str:
    parts = []
    for bracket in document["seed_brackets"]:
        up_to = "nothing" if bracket["sustained"] is None else f"{bracket['sustained']:g}"
        not_at = "" if bracket["unsustained"] is None else f" (not {bracket['unsustained']:g})"
        parts.append(f"seed {bracket['seed']} up to {up_to}{not_at}")
    return "; ".join(parts)


def rules(document: Mapping[str, Any]) -> str:
    """The criteria a run was judged by, in a sentence."""
    c = document["criteria"]
    service = "" if c["max_service_p95"] is None else f", service time p95 at most {c['max_service_p95']:g} s"
    return (
        f"A run sustains its rate when it does not fail, no vehicle stalls, its backlog is not overloaded, and it "
        f"completes all but {c['tolerance'] * 100:g} % (or one per vehicle) of the orders released after the "
        f"warm-up{service}; a rate is sustained when every seed's run sustains it."
    )


def rate_table(document: Mapping[str, Any]) -> tuple[list[str], list[list[str]]]:
    """One row per rate tried, by rate: means over its seeds' runs, and the first reason a seed failed."""
    body = []
    for rate in document["rates"]:
        runs = rate["runs"]
        failed = next((run for run in runs if not run["sustained"]), None)
        body.append([
            f"{rate['rate']:g}", "yes" if rate["sustained"] else "no",
            f"{sum(run['sustained'] for run in runs)}/{len(runs)}",
            _g(_mean([run["orders_per_hour"] for run in runs])), _g(_mean([run["arrivals_per_hour"] for run in runs])),
            _g(_mean([run["service_time_median"] for run in runs])), _g(_mean([run["service_time_p95"] for run in runs])),
            _g(_mean([run["backlog_slope"] for run in runs])),
            "" if failed is None else f"seed {failed['seed']}: {failed['reason']}",
        ])  # fmt: skip
    return _HEAD, body


def markdown(document: Mapping[str, Any], verdicts: Sequence[CapacityVerdict] = ()) -> str:
    """The summary printed after a search (and written with ``--markdown``)."""
    dispatcher = "" if document["dispatcher"] is None else f", dispatcher `{document['dispatcher']}`"
    head, body = rate_table(document)
    lines = [
        f"# Capacity: {document['scenario']}",
        "",
        f"**{headline(document)}**.",
        "",
        f"Planner `{document['planner']}`{dispatcher}; {document['runs']} runs. Stopped: {document['why']}.",
        "",
        f"Per seed: {_spread(document)}.",
        "",
        rules(document),
        "",
        "| " + " | ".join(head) + " |",
        "| " + " | ".join("---" for _ in head) + " |",
        *("| " + " | ".join(row) + " |" for row in body),
    ]
    if verdicts:
        lines += ["", "## Gate", "", *(f"- {v.line()}" for v in verdicts)]
    return "\n".join(lines) + "\n"


def _plots(document: Mapping[str, Any]) -> list[str]:
    bracket = (document["sustained"], document["unsustained"])
    rates = document["rates"]

    def points(figure: str) -> list[tuple[float, float]]:
        return [(r["rate"], run[figure]) for r in rates for run in r["runs"] if run[figure] is not None]

    throughput = curve_plot(
        "capacity-throughput", "throughput against offered rate", "throughput (orders/h)",
        [Curve("throughput", points("orders_per_hour")), Curve("arrivals", points("arrivals_per_hour"))],
        bracket, diagonal=True, notes={"bracket": f"{_g(bracket[0])} .. {_g(bracket[1])} orders/h"},
    )  # fmt: skip
    service = curve_plot(
        "capacity-service-time", "service time against offered rate", "service time (s)",
        [Curve("median", points("service_time_median")), Curve("p95", points("service_time_p95"))], bracket,
    )  # fmt: skip
    return [throughput, service]


def _table(head: Sequence[str], body: Sequence[Sequence[str]]) -> str:
    cells = "".join(f"<th>{escape(h)}</th>" for h in head)
    rows = "".join("<tr>" + "".join(f"<td>{escape(c)}</td>" for c in row) + "</tr>" for row in body)
    return f'<table id="rates"><thead><tr>{cells}</tr></thead><tbody>{rows}</tbody></table>'


def html_page(document: Mapping[str, Any], verdicts: Sequence[CapacityVerdict] = ()) -> str:
    """The report as one self-contained page."""
    title = f"Capacity: {document['scenario']}"
    dispatcher = "" if document["dispatcher"] is None else f", dispatcher <code>{escape(document['dispatcher'])}</code>"
    parts = [
        f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        f'<meta http-equiv="Content-Security-Policy" content="{_CSP}">'
        f"<title>{escape(title)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>{escape(title)}</h1>",
        f'<p class="capacity" id="capacity"><b>{escape(headline(document))}</b>.</p>',
        f"<p>Planner <code>{escape(document['planner'])}</code>{dispatcher}; {document['runs']} runs. "
        f"Stopped: {escape(document['why'])}.</p>",
        f"<p>Per seed: {escape(_spread(document))}.</p>",
        f"<p>{escape(rules(document))}</p>",
    ]
    if verdicts:
        items = "".join(f'<li class="{"fail" if v.holds else "ok"}">{escape(v.line())}</li>' for v in verdicts)
        parts.append(f'<h2>Gate</h2><ul id="gate">{items}</ul>')
    parts += ["<h2>Curves</h2>", '<div class="plots">', *_plots(document), "</div>"]
    parts += ["<h2>Rates tried</h2>", _table(*rate_table(document)), "</body></html>"]
    return "\n".join(parts)
