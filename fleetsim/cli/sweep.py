"""``fleetsim sweep SPEC.yaml`` runs planners × scenarios on Dask; ``fleetsim sweep report RESULTS``
compares them (``--compare BASE.jsonl``: with another sweep's runs, a baseline).

Exit status of a sweep: 0 when every run has its row in the results file (runs that fail are results,
not errors), 1 for a located error in the spec or its suites, 2 for a usage error, 130 after Ctrl-C
(the rows written so far stay; ``--resume`` goes on). Of a report: 0, or 1 when a ``--fail-if``
condition holds, 2 for a condition that does not parse.
"""

from __future__ import annotations

import argparse
import shutil
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, TextIO

from fleetsim.cli.run import UsageError
from fleetsim.sweep.execute import Progress, run_items
from fleetsim.sweep.gate import GateError, judge, parse_condition
from fleetsim.sweep.items import expand
from fleetsim.sweep.report import build_report, markdown
from fleetsim.sweep.report_html import html_page
from fleetsim.sweep.results import ResultsFile, read_results, relabelled
from fleetsim.sweep.spec import load_sweep_spec

__all__ = ["sweep"]


def _sweep_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fleetsim sweep", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "spec", metavar="SPEC.yaml", help="the sweep spec: planners, sources (suites, generate blocks), repetitions"
    )
    parser.add_argument("-o", "--output", default="fleetsim-sweep/results.jsonl", metavar="RESULTS",
                        help="the results file, JSON lines (default: %(default)s); failing runs' folders go beside it, in RESULTS.runs/")  # fmt: skip
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="a running Dask scheduler, e.g. tcp://host:8786 (default: a local cluster)",
    )
    parser.add_argument(
        "--workers", type=int, metavar="N", help="local cluster: worker processes (default: one per core)"
    )
    parser.add_argument(
        "--resume", action="store_true", help="keep the rows RESULTS holds and run only what is missing"
    )
    return parser


def _report_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fleetsim sweep report", description="Compare the planners of a sweep's results."
    )
    parser.add_argument("results", metavar="RESULTS", help="a results file written by fleetsim sweep")
    parser.add_argument(
        "--baseline",
        metavar="PLANNER",
        help="the planner spec the others are compared with (default: the sweep's baseline; with --compare, BASE's)",
    )
    parser.add_argument(
        "--compare",
        metavar="BASE.jsonl",
        help="compare every planner of RESULTS with the --baseline planner's runs in another sweep's results "
        "(a baseline sweep, from the main branch say), paired by scenario",
    )
    parser.add_argument("--html", metavar="OUT.html", help="where to write the page (default: RESULTS with .html)")
    parser.add_argument(
        "--markdown", metavar="OUT.md", help="also write the Markdown summary here (it is printed either way)"
    )
    parser.add_argument("--fail-if", action="append", default=[], metavar="CONDITION",
                        help="e.g. 'throughput < baseline - 2%%': exit 1 when it holds beyond the 95%% bootstrap interval")  # fmt: skip
    return parser


def sweep(args: argparse.Namespace) -> int:
    """Run a sweep (``fleetsim sweep SPEC.yaml``) or report on one (``fleetsim sweep report RESULTS``)."""
    argv: Sequence[str] = args.arguments
    if argv and argv[0] == "report":
        return report(_report_parser().parse_args(argv[1:]))
    return run_sweep(_sweep_parser().parse_args(argv))


def run_sweep(args: argparse.Namespace) -> int:
    spec = load_sweep_spec(args.spec)
    output = Path(args.output)
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers={args.workers} must be >= 1")
    items = expand(spec, output.with_name(output.name + ".runs"))
    header = {"name": spec.name, "spec": str(spec.path), "planners": list(spec.planners), "baseline": spec.baseline}
    header |= {"dispatcher": spec.dispatcher} if spec.dispatcher is not None else {}  # the rows do not say it
    with ResultsFile(output, header, resume=args.resume) as results:
        before = len(results.done & {item["key"] for item in items})
        print(
            f"sweep {spec.name!r}: {len(items)} runs ({len(spec.planners)} planners), {before} done already",
            file=sys.stderr,
        )
        bar = _Bar(sys.stderr)
        progress = run_items(items, results, scheduler=args.scheduler, workers=args.workers, on_progress=bar.show)
        bar.close()
    print(f"{progress.done} run(s) done, {progress.failing} failing; results in {output}", file=sys.stderr)
    print(f"report: fleetsim sweep report {output}", file=sys.stderr)
    return 0


def report(args: argparse.Namespace) -> int:
    try:
        conditions = [parse_condition(text) for text in args.fail_if]
    except GateError as error:
        raise UsageError(str(error)) from None
    path = Path(args.results)
    header, rows = read_results(path)
    planners = _planners(rows)
    title = str(header.get("name", path.stem))
    if args.compare is not None:  # another sweep's runs of one planner are the baseline of every planner here
        base_path = Path(args.compare)
        base_header, base_rows = read_results(base_path)
        chosen = args.baseline or base_header.get("baseline") or next(iter(_planners(base_rows)), "")
        if chosen not in _planners(base_rows):
            found = ", ".join(_planners(base_rows)) or "none"
            raise UsageError(f"--baseline={chosen!r} ran no run in {base_path}; its planners: {found}")
        baseline = f"{chosen} @ {base_path.name}"
        rows = [*rows, *relabelled(base_rows, chosen, baseline)]
        candidates, title = planners, f"{title} against {base_path.name}"
    else:
        baseline = args.baseline or header.get("baseline") or (planners[0] if planners else "")
        if rows and baseline not in planners:
            raise UsageError(f"--baseline={baseline!r} ran no run in {path}; its planners: {', '.join(planners)}")
        candidates = [p for p in planners if p != baseline]
    html_path = Path(args.html) if args.html else path.with_suffix(".html")
    verdicts = judge(rows, conditions, baseline, candidates)
    built = build_report(title, rows, baseline, verdicts, html_path.parent)
    html_path.parent.mkdir(parents=True, exist_ok=True)
    html_path.write_text(html_page(built), encoding="utf-8")
    text = markdown(built)
    if args.markdown:
        Path(args.markdown).write_text(text, encoding="utf-8")
    print(text)
    print(f"report: {html_path}", file=sys.stderr)
    return 1 if any(v.holds for v in verdicts) else 0


def _planners(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The planners of a sweep's rows, in key order of their first run."""
    return list(dict.fromkeys(str(r["planner"]) for r in sorted(rows, key=lambda r: str(r["key"]))))


class _Bar:
    """Runs done, failing, time left: one redrawn line on a terminal, a line per 10 % elsewhere."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.live = stream.isatty()
        self.shown = -1

    def show(self, p: Progress) -> None:
        eta = "?" if p.eta is None else f"{int(p.eta) // 60}:{int(p.eta) % 60:02d}"
        width = 30
        filled = width * p.done // max(p.total, 1)
        text = f"[{'#' * filled}{'.' * (width - filled)}] {p.done}/{p.total} runs, {p.failing} failing, ~{eta} left"
        if self.live:
            columns = shutil.get_terminal_size().columns - 1
            self.stream.write("\r" + text[:columns])
            self.stream.flush()
        elif p.done * 10 // max(p.total, 1) != self.shown or p.done == p.total:
            self.shown = p.done * 10 // max(p.total, 1)
            print(text, file=self.stream, flush=True)

    def close(self) -> None:
        if self.live:
            self.stream.write("\n")
