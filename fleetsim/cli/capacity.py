"""``fleetsim capacity SUITE::NAME --planner P``: the highest arrival rate of the entry's order stream that
the fleet sustains, searched over several order stream seeds on the sweep's Dask machinery.

Exit status: 0 when the search ended (whatever it found), 1 when a ``--fail-if`` condition holds, 2 when
it could not start or go on (a mistake on the command line, an entry without a Poisson order stream, a
suite that does not load, a planner no run could load), 130 after Ctrl-C (the runs done so far stay in
the runs file; ``--resume`` goes on from them).
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from fleetsim.errors import FleetsimError

if TYPE_CHECKING:
    from fleetsim.capacity.criteria import Criteria, Judgement
    from fleetsim.capacity.search import SearchSettings

__all__ = ["add_capacity_arguments", "capacity"]

_MAX_RUNS = 60
_RANGE = 64  # --min-rate and --max-rate default to the entry's rate over and times this


def add_capacity_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "scenario", metavar="SUITE::NAME", help="a suite entry with an order stream of Poisson arrivals"
    )
    parser.add_argument("--planner", required=True, metavar="SPEC", help="the planner, as for fleetsim run")
    parser.add_argument("--dispatcher", metavar="SPEC", help="a dispatcher in place of the entry's own")
    search = parser.add_argument_group("the search")
    search.add_argument("--seeds", default="1,2,3", metavar="S,S,...", help="order stream seeds each rate is run with; a rate is sustained when every seed's run sustains it (default: %(default)s)")  # fmt: skip
    search.add_argument("--resolution", default="2%", metavar="R", help="stop when the bracket is this narrow: percent of its low end (2%%) or orders/h (5) (default: %(default)s)")  # fmt: skip
    search.add_argument("--tolerance", default="10%", metavar="PERCENT", help="of the orders released after the warm-up, the share a sustaining run may leave uncompleted (at least one per vehicle) (default: %(default)s)")  # fmt: skip
    search.add_argument("--max-service-p95", metavar="SECONDS", help="also require the service times' 95th percentile to be at most this")  # fmt: skip
    search.add_argument("--min-rate", metavar="ORDERS/H", help=f"halving stops here (default: the entry's rate / {_RANGE})")  # fmt: skip
    search.add_argument("--max-rate", metavar="ORDERS/H", help=f"doubling stops here (default: the entry's rate x {_RANGE})")  # fmt: skip
    search.add_argument("--max-runs", type=int, default=_MAX_RUNS, metavar="N", help="runs at most (default: %(default)s)")  # fmt: skip
    search.add_argument("--planner-timeout", type=float, default=10.0, metavar="SECONDS", help="per planner call; 0: none (default: %(default)g)")  # fmt: skip
    where = parser.add_argument_group("where it runs and what it writes")
    where.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (default: a local cluster)")
    where.add_argument("--workers", type=int, metavar="N", help="local cluster: worker processes (default: one per core)")  # fmt: skip
    where.add_argument("-o", "--output", default="fleetsim-capacity/capacity.json", metavar="OUT.json", help="the results file (default: %(default)s); the runs go beside it in OUT.runs.jsonl, the page in OUT.html")  # fmt: skip
    where.add_argument("--html", metavar="OUT.html", help="where to write the page (default: OUT.json with .html)")
    where.add_argument("--markdown", metavar="OUT.md", help="also write the summary here (it is printed either way)")
    where.add_argument("--resume", action="store_true", help="keep the runs OUT.runs.jsonl holds and run only the missing ones")  # fmt: skip
    gate = parser.add_argument_group("gating")
    gate.add_argument("--baseline", metavar="FILE|ORDERS/H", help="an earlier search's results file, or a capacity in orders/h")  # fmt: skip
    gate.add_argument("--fail-if", action="append", default=[], metavar="CONDITION", help="e.g. 'capacity < baseline - 5%%': exit 1 when it holds over the whole bracket")  # fmt: skip


def capacity(args: argparse.Namespace) -> int:
    """Search the capacity of a suite entry's fleet: the highest order arrival rate it sustains.

    The search starts at the entry's own rate, doubles or halves it until a sustained and an unsustained
    rate bracket the capacity, then bisects the bracket to --resolution; every rate runs once per seed.
    It prints a Markdown summary and writes OUT.json (a baseline for --baseline), OUT.html (the curves of
    throughput and service time against the offered rate) and OUT.runs.jsonl (the runs, a sweep results
    file). Exit status: 0 when the search ended, 1 when a --fail-if condition holds, 2 when it could not
    start or go on (see docs/capacity.md).
    """
    from fleetsim.cli.run import UsageError

    try:
        return _capacity(args)
    except UsageError:
        raise
    except FleetsimError as error:  # a suite, baseline or runs file that stops the search before its end
        raise UsageError(str(error)) from None


def _usage(message: str) -> FleetsimError:
    """A usage error (exit status 2); ``fleetsim.cli.run`` is imported only when one is made, so that
    ``fleetsim --help`` stays quick."""
    from fleetsim.cli.run import UsageError

    return UsageError(message)


def _capacity(args: argparse.Namespace) -> int:
    from fleetsim.capacity.gate import judge_capacity, parse_baseline, parse_gate
    from fleetsim.capacity.report import html_page, markdown
    from fleetsim.capacity.results import capacity_document, write_capacity
    from fleetsim.capacity.runs import Runner, RunsFile, load_target
    from fleetsim.capacity.search import search
    from fleetsim.sweep.execute import dask_client

    conditions = tuple(parse_gate(text) for text in args.fail_if)
    if conditions and args.baseline is None:
        raise _usage("--fail-if needs --baseline: an earlier search's results file, or a capacity in orders/h")
    baseline = None if args.baseline is None else parse_baseline(args.baseline)
    if args.workers is not None and args.workers < 1:
        raise _usage(f"--workers={args.workers} must be >= 1")
    timeout = _timeout(args.planner_timeout)
    criteria = _criteria(args)
    suite_path, name = _scenario_argument(args.scenario)
    _check_specs(args.planner, args.dispatcher, timeout, remote=args.scheduler is not None)
    target = load_target(suite_path, name, args.dispatcher)
    settings = _settings(args, target.rate)
    output = Path(args.output)
    runs_path = output.with_suffix(".runs.jsonl")
    about = {"scenario": target.id, "dispatcher": target.scenario.dispatcher, "planner_timeout": timeout}
    header = {"name": f"capacity {target.id}", "spec": target.where, "planners": [args.planner], "baseline": args.planner, "capacity": about}  # fmt: skip
    print(f"capacity of {target.id}: from {target.rate:g} orders/h, seeds {_seeds_text(settings.seeds)}", file=sys.stderr)  # fmt: skip
    started = time.monotonic()
    with RunsFile(runs_path, header, resume=args.resume) as runs, contextlib.ExitStack() as stack:

        def open_client() -> object:
            return stack.enter_context(dask_client(args.scheduler, args.workers))

        runner = Runner(target, args.planner, settings.seeds, criteria, runs, open_client, timeout, _show_rate)
        result = search(settings, runner)
    document = capacity_document(target, args.planner, criteria, result, runs_path.name)
    write_capacity(output, document)
    verdicts = [] if baseline is None else judge_capacity(conditions, baseline, result.sustained, result.unsustained)
    html_path = Path(args.html) if args.html else output.with_suffix(".html")
    html_path.parent.mkdir(parents=True, exist_ok=True)
    html_path.write_text(html_page(document, verdicts), encoding="utf-8")
    text = markdown(document, verdicts)
    if args.markdown:
        Path(args.markdown).write_text(text, encoding="utf-8")
    print(text, flush=True)  # before the lines on stderr that follow it
    print(f"{result.runs} runs in {time.monotonic() - started:.0f} s; results in {output}", file=sys.stderr)
    print(f"report: {html_path}", file=sys.stderr)
    return 1 if any(v.holds for v in verdicts) else 0


def _scenario_argument(text: str) -> tuple[Path, str]:
    path_text, _, name = text.rpartition("::")
    if not path_text or not name:
        raise _usage(f"{text!r} must name one suite entry: SUITE.fleetsim.yaml::NAME")
    path = Path(path_text)
    if not path.is_file():
        raise _usage(f"{path_text}: no such suite file")
    return path, name


def _check_specs(planner: str, dispatcher: str | None, timeout: float | None, *, remote: bool) -> None:
    """The planner and dispatcher load here, as on a local cluster's workers; a remote cluster's workers may
    have what this machine lacks, so there only the specs' form is the workers' business."""
    from fleetsim.exec.spec import load_planner_factory
    from fleetsim.specs.dispatcher import DispatcherSpecError, import_dispatcher_factory

    if remote:
        return
    load_planner_factory(planner, call_timeout=timeout)  # a PlannerSpecError is a usage error (exit 2)
    if dispatcher is not None:
        try:
            import_dispatcher_factory(dispatcher)
        except DispatcherSpecError as error:
            raise _usage(str(error)) from None


def _timeout(seconds: float) -> float | None:
    if seconds < 0:
        raise _usage(f"--planner-timeout={seconds:g} must be >= 0 (0: none)")
    return seconds or None


def _percent(name: str, text: str) -> float:
    try:
        value = float(text.strip().removesuffix("%"))
    except ValueError:
        value = -1.0
    if not 0 <= value < 100:
        raise _usage(f"{name}={text!r} must be a percentage from 0 to below 100, e.g. 10%")
    return value / 100


def _criteria(args: argparse.Namespace) -> Criteria:
    from fleetsim.capacity.criteria import Criteria

    bound = None
    if args.max_service_p95 is not None:
        try:
            bound = float(args.max_service_p95)
        except ValueError:
            bound = -1.0
        if not bound > 0:
            raise _usage(f"--max-service-p95={args.max_service_p95!r} must be a number of seconds > 0")
    return Criteria(_percent("--tolerance", args.tolerance), bound)


def _settings(args: argparse.Namespace, start: float) -> SearchSettings:
    from fleetsim.capacity.search import Resolution, SearchSettings, rate_value

    low = rate_value("--min-rate", args.min_rate) if args.min_rate else max(round(start / _RANGE, 2), 0.01)
    high = rate_value("--max-rate", args.max_rate) if args.max_rate else start * _RANGE
    return SearchSettings(start, _seeds(args.seeds), Resolution.parse(args.resolution), low, high, args.max_runs)


def _seeds(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(part) for part in text.split(","))
    except ValueError:
        raise _usage(f"--seeds={text!r} must be whole numbers separated by commas, e.g. 1,2,3") from None


def _seeds_text(seeds: tuple[int, ...]) -> str:
    return ",".join(map(str, seeds))


def _show_rate(rate: float, runs: Mapping[int, Judgement]) -> None:
    sustaining = sum(run.sustained for run in runs.values())
    failed = next(((seed, run) for seed, run in runs.items() if not run.sustained), None)
    why = "" if failed is None else f" (seed {failed[0]}: {failed[1].reason})"
    word = "sustained" if failed is None else "not sustained"
    print(f"  {rate:g} orders/h: {word}, {sustaining}/{len(runs)} seeds{why}", file=sys.stderr, flush=True)
