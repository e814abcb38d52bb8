"""The sweep report as one self-contained HTML page: inline CSS and SVG, no script, nothing fetched.

A Content-Security-Policy (``default-src 'none'``) makes the browser refuse any request the page might
make, so it opens the same offline, from a CI artifact, or from a mail attachment. Run folders,
pictures and MCAP files are links (relative to the page), opened only when clicked.
"""

from __future__ import annotations

from collections import defaultdict
from html import escape

from fleetsim.sweep.plots import differences_plot, distribution_plot, fleet_size_plot
from fleetsim.sweep.report import Report, comparison_table, orders_table, paced_note, short, summary_table
from fleetsim.sweep.stats import METRICS

__all__ = ["html_page"]

_STYLE = """
body{font:14px/1.4 system-ui,sans-serif;margin:24px;color:#222;max-width:1100px}
h1{font-size:22px}h2{font-size:18px;margin-top:28px;border-bottom:1px solid #ddd}
table{border-collapse:collapse;margin:8px 0}th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}
th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}
.worse{color:#b71c1c;font-weight:bold}.better{color:#1b5e20;font-weight:bold}
.plots{display:flex;flex-wrap:wrap;gap:12px}.plots svg{border:1px solid #eee;background:#fff}
.fail{color:#b71c1c}.ok{color:#1b5e20}code{font-size:12px}
"""
_CSP = "default-src 'none'; style-src 'unsafe-inline'; img-src data:"


def _table(head: list[str], body: list[list[str]], css_id: str) -> str:
    cells = "".join(f"<th>{escape(h)}</th>" for h in head)
    rows = []
    for row in body:
        tds = "".join(
            f'<td class="{escape(c)}">{escape(c)}</td>' if c in ("worse", "better") else f"<td>{escape(c)}</td>"
            for c in row
        )
        rows.append(f"<tr>{tds}</tr>")
    return f'<table id="{css_id}"><thead><tr>{cells}</tr></thead><tbody>{"".join(rows)}</tbody></table>'


def _distributions(report: Report) -> list[str]:
    plots = []
    for name in ("throughput", "makespan", "waiting_share", *(("orders_per_hour",) if report.orders else ())):
        metric = METRICS[name]
        groups = {
            short(s.planner): [
                v for v in map(metric.read, (r for r in report.rows if r["planner"] == s.planner)) if v is not None
            ]
            for s in report.summaries
        }
        plots.append(distribution_plot(f"{metric.label} ({metric.unit}) per run", groups))
    return plots


def _fleet_size(report: Report) -> str:
    sums: dict[str, dict[int, list[float]]] = defaultdict(lambda: defaultdict(list))
    for row in report.rows:
        value = METRICS["throughput"].read(row)
        if value is not None and row.get("vehicles"):
            sums[short(str(row["planner"]))][int(row["vehicles"])].append(value)
    series = {
        planner: {size: sum(vs) / len(vs) for size, vs in sorted(sizes.items())} for planner, sizes in sums.items()
    }
    return fleet_size_plot("mean throughput (tasks/h) by fleet size (vehicles)", series)


def _worst(report: Report, candidate: str) -> str:
    items = []
    for w in report.worst[candidate]:
        links = " ".join(f'<a href="{escape(path)}">{kind}</a>' for kind, path in w.links.items())
        failure = f"<br><small>{escape(w.failure[:200])}</small>" if w.failure else ""
        items.append(
            f"<li><code>{escape(w.id)}</code>: {escape(w.status)}, throughput {w.difference:+.4g} tasks/h {links}{failure}</li>"
        )
    return f'<ul class="worst">{"".join(items)}</ul>' if items else "<p>No scenario where it is worse.</p>"


def html_page(report: Report) -> str:
    parts = [
        f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        f'<meta http-equiv="Content-Security-Policy" content="{_CSP}">'
        f"<title>Sweep report: {escape(report.title)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>Sweep report: {escape(report.title)}</h1>",
        f"<p>{len(report.rows)} runs; baseline <b>{escape(short(report.baseline))}</b> (<code>{escape(report.baseline)}</code>).</p>",
    ]
    if report.verdicts:
        lines = "".join(f'<li class="{"fail" if v.holds else "ok"}">{escape(v.line())}</li>' for v in report.verdicts)
        parts.append(f'<h2>Gate</h2><ul id="gate">{lines}</ul>')
    parts += ["<h2>Planners</h2>", _table(*summary_table(report), "planners")]
    parts += ["<h2>Orders</h2>", _table(*orders_table(report), "orders")] if report.orders else []
    note = paced_note(report)
    parts += [] if note is None else [f'<p id="paced">{escape(note)}</p>']
    parts += ['<h2>Distributions</h2><div class="plots">', *_distributions(report), _fleet_size(report), "</div>"]
    for index, candidate in enumerate(report.candidates):
        parts.append(f"<h2>{escape(short(candidate))} against {escape(short(report.baseline))}</h2>")
        parts.append(
            "<p>Paired by scenario; 95% percentile bootstrap interval of the mean difference (2000 resamples, fixed seed).</p>"
        )
        parts.append(_table(*comparison_table(report, candidate), f"comparison-{index}"))
        throughput = next(c for c in report.comparisons[candidate] if c.metric == "throughput")
        parts.append('<div class="plots">')
        parts.append(
            differences_plot(
                f"throughput difference per scenario (tasks/h), {short(candidate)} - baseline",
                throughput.differences,
                throughput.low,
                throughput.high,
            )
        )
        parts.append("</div><h3>Where it does worst</h3>")
        parts.append(_worst(report, candidate))
    parts.append("</body></html>")
    return "\n".join(parts)
