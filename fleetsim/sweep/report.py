"""What a sweep report says, computed once for both forms (HTML page, Markdown summary).

Rows are taken in key order, so the report is the same whatever order the runs finished in or which
worker ran them; only wall-clock figures (planner time per call) vary between sweeps, and every figure of
a planner that paces its runs by a wall clock (a ``vda5050:`` master control: the result's ``paced``),
whose runs do not repeat to the step. The report says which planners those are.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fleetsim.exec.spec import EXEC_PREFIX, VDA5050_PREFIX
from fleetsim.sweep.gate import Verdict
from fleetsim.sweep.stats import METRICS, ORDER_METRICS, Paired, PlannerSummary, paired, summarise, throughput

__all__ = ["COMPARED", "Report", "Worst", "build_report", "markdown", "orders_table", "paced_note", "short"]

COMPARED = (
    "success",
    "throughput",
    "makespan",
    "waiting_share",
    "alerts",
    "contacts",
    "clearance",
    "rejections",
    "deadlocks",
    "planner_time_per_call",
)
WORST_SHOWN = 5


@dataclass(frozen=True, slots=True)
class Worst:
    """A scenario where a candidate does worst against the baseline, with links to its run."""

    id: str
    candidate: str
    difference: float  # throughput, candidate - baseline (tasks/h)
    status: str
    failure: str
    links: Mapping[str, str]  # folder, view, picture, mcap: paths relative to the report, for those that exist


@dataclass(frozen=True, slots=True)
class Report:
    title: str
    baseline: str
    candidates: tuple[str, ...]
    rows: tuple[Mapping[str, Any], ...]  # key order
    summaries: tuple[PlannerSummary, ...]
    comparisons: Mapping[str, tuple[Paired, ...]]  # candidate -> one per metric of COMPARED
    worst: Mapping[str, tuple[Worst, ...]]
    verdicts: tuple[Verdict, ...]
    paced: Mapping[str, float]  # planner -> the multiple of real time its runs were paced at (a wall clock's)
    orders: bool = False  # some run had transport orders: the report adds their measures (ORDER_METRICS)


def build_report(
    title: str, rows: Sequence[Mapping[str, Any]], baseline: str, verdicts: Sequence[Verdict], where: Path
) -> Report:
    """``where``: the folder the report is written to (links are relative to it)."""
    ordered = tuple(sorted(rows, key=lambda r: str(r["key"])))
    summaries = tuple(summarise(ordered))
    candidates = tuple(s.planner for s in summaries if s.planner != baseline)
    orders = any(r.get("measures") is not None for r in ordered)
    compared = COMPARED + (ORDER_METRICS if orders else ())
    comparisons = {c: tuple(paired(ordered, metric, c, baseline) for metric in compared) for c in candidates}
    worst = {c: _worst(ordered, c, baseline, where) for c in candidates}
    paced = {str(r["planner"]): float(r["paced"]) for r in ordered if r.get("paced") is not None}
    return Report(title, baseline, candidates, ordered, summaries, comparisons, worst, tuple(verdicts), paced, orders)


def paced_note(report: Report) -> str | None:
    """What the report says of planners whose runs a wall clock paced: their figures are judged as any,
    but a sweep run again gives other ones (their trace hashes differ too, which says nothing)."""
    if not report.paced:
        return None
    named = ", ".join(f"{short(planner)} ({speed:g}x real time)" for planner, speed in sorted(report.paced.items()))
    return (
        f"Paced by a wall clock: {named}. A master control in another process makes such runs unrepeatable "
        "to the step, so their figures (and trace hashes) differ from sweep to sweep; the intervals judge "
        "the runs as they came out."
    )


def _worst(rows: Sequence[Mapping[str, Any]], candidate: str, baseline: str, where: Path) -> tuple[Worst, ...]:
    """The candidate's runs ranked by how much worse than the baseline they are: failing where the
    baseline passed first, then by throughput lost; ties by id."""
    base = {r["id"]: r for r in rows if r["planner"] == baseline}
    ranked = []
    for row in rows:
        other = base.get(row["id"])
        if row["planner"] != candidate or other is None:
            continue
        lost_pass = other["status"] == "passed" and row["status"] != "passed"
        difference = (throughput(row) or 0.0) - (throughput(other) or 0.0)
        ranked.append((not lost_pass, difference, str(row["id"]), row))
    ranked.sort(key=lambda entry: entry[:3])
    shown = [entry for entry in ranked if not entry[0] or entry[1] < 0][:WORST_SHOWN]
    return tuple(
        Worst(
            str(row["id"]),
            candidate,
            difference,
            str(row["status"]),
            _first_failure(row),
            _links(row, where),
        )
        for _, difference, _, row in shown
    )


def _first_failure(row: Mapping[str, Any]) -> str:
    failures = row["failures"]
    return f"{failures[0]['kind']}: {failures[0]['message']}" if failures else ""


def _links(row: Mapping[str, Any], where: Path) -> dict[str, str]:
    links = {}
    for kind, path in (row.get("artifacts") or {}).items():
        if kind in ("folder", "view", "picture", "mcap") and Path(path).exists():
            links[kind] = Path(os.path.relpath(path, where)).as_posix()
    return links


def short(planner: str) -> str:
    """``fleetsim.planners:ReservingPlanner`` -> ``ReservingPlanner``; ``exec:`` and ``vda5050:`` specs as
    they are (their colons are not a module's: the command, the options, the broker's port)."""
    return planner if planner.startswith((EXEC_PREFIX, VDA5050_PREFIX)) else planner.rpartition(":")[2]


def figure(value: float | None, digits: int = 4) -> str:
    return "–" if value is None else f"{value:.{digits}g}"


def _labelled(metric: str) -> str:
    """A metric's label with its unit: ``makespan (s)``."""
    found = METRICS[metric]
    return found.label + (f" ({found.unit})" if found.unit else "")


def summary_table(report: Report) -> tuple[list[str], list[list[str]]]:
    head = [
        "planner",
        "runs",
        "errors",
        *(("least " if m == "clearance" else "") + _labelled(m) for m in COMPARED),
    ]
    body = []
    for s in report.summaries:
        cells = [short(s.planner), str(s.runs), str(s.errors)]
        for metric in COMPARED:
            if metric == "clearance":  # for safety the closest call counts, not the average one
                cells.append(figure(s.least_clearance))
            else:
                cells.append(f"{s.totals[metric]:.0f}" if metric in s.totals else figure(s.means[metric]))
        body.append(cells)
    return head, body


def orders_table(report: Report) -> tuple[list[str], list[list[str]]]:
    """Per planner, the measures of its runs with transport orders: means, deadline misses and stalls
    summed; ``–`` where none of its runs has the figure."""
    head = ["planner", "runs with orders", *(_labelled(m) for m in ORDER_METRICS)]
    body = []
    for s in report.summaries:
        mine = [r for r in report.rows if r["planner"] == s.planner and r.get("measures") is not None]
        cells = [short(s.planner), str(len(mine))]
        for metric in ORDER_METRICS:
            total = s.totals.get(metric)
            counted = total is not None and s.means[metric] is not None
            cells.append(f"{total:.0f}" if counted else figure(s.means[metric]))
        body.append(cells)
    return head, body


def comparison_table(report: Report, candidate: str) -> tuple[list[str], list[list[str]]]:
    head = ["metric", "n", "baseline mean", "mean difference", "95% CI", "relative", "verdict"]
    body = []
    for c in report.comparisons[candidate]:
        metric = METRICS[c.metric]
        if c.n == 0:
            body.append([metric.label, "0", "–", "–", "–", "–", "no pairs"])
            continue
        relative = c.relative(c.mean)
        verdict = _verdict(c)
        body.append([
            _labelled(c.metric), str(c.n), figure(c.baseline_mean),
            f"{c.mean:+.4g}", f"{c.low:+.4g} .. {c.high:+.4g}", "–" if relative is None else f"{relative * 100:+.1f}%", verdict,
        ])  # fmt: skip
    return head, body


def _verdict(c: Paired) -> str:
    """Worse or better beyond doubt (the whole interval on one side of zero), else no clear difference."""
    below, above = c.high < 0, c.low > 0
    if not (below or above):
        return "no clear difference"
    return "better" if (above if METRICS[c.metric].better == "higher" else below) else "worse"


def _markdown_table(head: list[str], body: list[list[str]]) -> list[str]:
    rows = [head, ["---"] * len(head), *body]
    return ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |" for row in rows]


def markdown(report: Report) -> str:
    """The summary for CI logs and job summaries (GitHub's $GITHUB_STEP_SUMMARY renders it)."""
    lines = [
        f"# Sweep report: {report.title}",
        "",
        f"{len(report.rows)} runs; baseline **{short(report.baseline)}**.",
        "",
    ]
    lines += ["## Planners", "", *_markdown_table(*summary_table(report)), ""]
    if report.orders:
        lines += ["## Orders", "", *_markdown_table(*orders_table(report)), ""]
    note = paced_note(report)
    lines += [note, ""] if note is not None else []
    for candidate in report.candidates:
        lines += [f"## {short(candidate)} against {short(report.baseline)}", "",
                  "Paired by scenario; 95% percentile bootstrap interval of the mean difference (2000 resamples, fixed seed).", ""]  # fmt: skip
        lines += [*_markdown_table(*comparison_table(report, candidate)), ""]
        worst = report.worst[candidate]
        if worst:
            lines += ["Where it does worst:", ""]
            for w in worst:
                link = f" ([run]({w.links['folder']}))" if "folder" in w.links else ""
                link += f" ([watch it]({w.links['view']}))" if "view" in w.links else ""
                lines.append(
                    f"- `{w.id}`: {w.status}, throughput {w.difference:+.4g} tasks/h{link}"
                    + (f" — {w.failure[:120]}" if w.failure else "")
                )
            lines.append("")
    if report.verdicts:
        lines += ["## Gate", "", *(f"- {v.line()}" for v in report.verdicts), ""]
    return "\n".join(lines)
