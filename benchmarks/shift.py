"""What transport orders cost the harness: a shift of orders against the same fleet driving the same trips.

    python benchmarks/shift.py [--case shift|shift100|stretch|both] [--hours 8] [--minutes 10] [--repeat 3]
                               [--profile shift|stretch] [--top 25] [--orders-only]
                               [--vs REF [--parallel] [--compiled]]

Two cases (issue 45, point 7), each on a site of ``fleetsim generate warehouse`` (``generate_warehouse``)
run by the reference dispatcher (``NearestVehicleDispatcher``) and planner (``ReservingPlanner``):

* ``shift``: 50 vehicles for ``--hours`` (8) on 24 one-way aisles of 60 m (96 pick, 32 drop stations,
  150 parking places), a Poisson stream of 72 orders an hour, measured after 30 minutes' warm-up. Each
  order is pick (dwell 20 s), drop (dwell 15 s), then a parking place (no dwell): the reference
  dispatcher does not send idle vehicles away, so without the last stop an idle vehicle left on a drop
  station blocks the next order for that station (a stall the diagnosis names ``blocked-by-idle``). The
  site's dock (every drop on one ladder) serves about 85 orders an hour with this fleet and planner; at
  72 the fleet is busy and not overloaded (the script prints the measures to check).
* ``shift100``: the shift with twice the fleet: 100 vehicles on the same site and orders.
  ``--case shift100 --orders-only`` times the orders run alone: the target of issue 46 is an 8-hour shift
  of 100 vehicles in at most 3 minutes.
* ``stretch``: 500 vehicles for ``--minutes`` (10) on the same kind of site ten times the size (80
  aisles, 320 pick and 100 drop stations, 1,000 parking places) and ten times the demand: the first
  minutes of a shift, vehicles leaving their parking places for their first orders.

Each case runs twice per repeat, in alternating order (so that neither always runs first, on a warmer
or a colder machine): with its orders, and as *the same fleet without them*: the same site and
vehicles, with ``tasks.csv`` trips instead of orders: each vehicle gets as tasks the stops of the orders
it served or held at the end of the first orders run, order by order as they were assigned to it. The
motion is the same work (the same trips by the same vehicles), only front-loaded (every trip queued from
the start, no dwell, no waiting for orders), and the run is as long (a shift without orders runs to its
end; the standstill after the last trip, no deadlock, is allowed by a ``deadlock_after`` beyond the
shift). Both runs keep no trace (the hash is computed all the same).

Harness time = the run's wall time − the time inside the planner (``Metrics.planner_wall_time``) − the
time inside the dispatcher (measured here by a wrapper around its ``dispatch``), per vehicle-step
(vehicles × steps). Printed per case: the medians of the repeats for both runs and the added cost (the
median of the repeats' paired ratios − 1); and, measured inside the orders run itself, the dispatch and
order bookkeeping (``Run.dispatch`` less the dispatcher: dwells, releases, the board, checking and
applying answers, idle and standing vehicles; ``Dispatching.reached``; the measures) and, apart, the
shift's stall check (each second; explaining each stall found is a diagnosis of the fleet), each as a
share of the rest of the harness (wrapping those methods adds about a microsecond per step). The two
ways differ: the paired figure also holds what differs in the motion (the trips front-loaded, so more
vehicles drive at once and wait on each other), the inside figure only the bookkeeping. The shift's wall
time is the orders run's. Every repeat of a run must give the same trace hash (the script fails
otherwise).

Target (issue 45): dispatch and order bookkeeping add at most 10 % to the harness per vehicle-step
(judged on the inside figure). The script exits 1 when a target is missed or hashes differ.

``--vs REF`` compares this tree with commit REF instead, side by side in one invocation (the orders run's
wall time, as ``--orders-only``): the case's site is generated once, by this tree, and each of
``--repeat`` rounds runs it in a fresh process in REF (a temporary git worktree, ``benchmarks/compare.py``)
and in this tree, in turn; ``--parallel`` runs the two of a round at once instead, one per core (an
8-hour shift takes minutes: a 2-core machine then gives each tree a core of its own). Printed per tree:
each round's wall time, planner time, harness per vehicle-step and planner calls, their medians, how
many times faster this tree runs the shift, and whether the trace hashes agree (they must: a speed-up
changes no behaviour; the script exits 1 otherwise). REF must have transport orders (issue 45 on).
``--compiled`` also builds this tree's compiled build (``scripts/compiled_copy.py``, about a minute) and
runs it in each round, after REF and this tree, against this tree once more (with ``--parallel``, that
second pair at once too): printed as two more trees, and how many times faster the compiled build runs
the shift than this tree beside it.

``--profile CASE`` runs that case's orders run once more under cProfile and prints the functions with
the most own time in ``fleetsim/dispatch`` and ``fleetsim/sim/dispatching.py`` (cProfile slows pure-Python
code about 2x; read shares, not seconds).
"""

from __future__ import annotations

import argparse
import cProfile
import dataclasses
import json
import os
import pstats
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from compare import column, trees

from fleetsim import load_scenario, load_suite
from fleetsim.compiled import compiled_modules
from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.dispatchers import NearestVehicleDispatcher
from fleetsim.generate import WarehouseOptions, generate_warehouse
from fleetsim.layout.layout import Layout
from fleetsim.orders import Arrivals, Shift, StopDraw
from fleetsim.planners import ReservingPlanner
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Scenario, Task
from fleetsim.sim import loop
from fleetsim.sim.dispatching import Dispatching
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult

TARGET_ADDED = 0.10


@dataclass(frozen=True)
class Case:
    name: str
    site: WarehouseOptions
    rate: float  # orders an hour
    warmup: float  # seconds


CASES = {
    "shift": Case(
        "shift",
        WarehouseOptions(aisles=24, aisle_length=60, vehicles=50, pick_stations=96, drop_stations=32, parking=150),
        rate=72.0,
        warmup=1800.0,
    ),
    "shift100": Case(
        "shift100",
        WarehouseOptions(aisles=24, aisle_length=60, vehicles=100, pick_stations=96, drop_stations=32, parking=150),
        rate=72.0,
        warmup=1800.0,
    ),
    "stretch": Case(
        "stretch",
        WarehouseOptions(aisles=80, aisle_length=60, vehicles=500, pick_stations=320, drop_stations=100, parking=1000),
        rate=720.0,
        warmup=0.0,
    ),
}


class TimedDispatcher:
    """The reference dispatcher, with the wall seconds spent inside it summed."""

    def __init__(self) -> None:
        self.inner = NearestVehicleDispatcher()
        self.seconds = 0.0
        self.calls = 0

    def dispatch(self, board: OrderBoard, fleet: FleetSnapshot, layout: Layout) -> Sequence[Assignment]:
        started = time.perf_counter()
        try:
            return self.inner.dispatch(board, fleet, layout)
        finally:
            self.seconds += time.perf_counter() - started
            self.calls += 1


@contextmanager
def bookkeeping_clocks(spent: dict[str, float]) -> Iterator[None]:
    """Adds the wall time of the loop's order methods to ``spent`` while open."""
    clocked: list[tuple[type, str, Callable[..., Any]]] = []
    methods: tuple[tuple[type, str], ...] = (
        (loop._Run, "dispatch"),
        (loop._Run, "check_stalls"),
        (Dispatching, "reached"),
        (Dispatching, "measures"),
    )
    for owner, method in methods:
        original = getattr(owner, method)
        clocked.append((owner, method, original))

        def timed(*args: Any, _original: Callable[..., Any] = original, _label: str = method, **kwargs: Any) -> Any:
            started = time.perf_counter()
            try:
                return _original(*args, **kwargs)
            finally:
                spent[_label] += time.perf_counter() - started

        setattr(owner, method, timed)
    try:
        yield
    finally:
        for owner, method, original in clocked:
            setattr(owner, method, original)


def orders_scenario(case: Case, folder: Path, seconds: float) -> Scenario:
    """The generated site with its suite's order stream: the case's rate, a parking place as last stop."""
    return with_orders(generate_warehouse(folder, case.site).suite, case, seconds)


def with_orders(suite_file: Path, case: Case, seconds: float) -> Scenario:
    """The generated suite's scenario with the case's order stream and a shift of ``seconds``."""
    suite = load_suite(suite_file)
    scenario = load_scenario(suite.scenarios[0], suite)
    stream = scenario.order_stream
    assert stream is not None
    stream = dataclasses.replace(
        stream, arrivals=Arrivals("poisson", rate=case.rate), stops=(*stream.stops, StopDraw(("park",)))
    )
    shift = Shift(duration=seconds, warmup=min(case.warmup, seconds / 2))
    return dataclasses.replace(scenario, order_stream=stream, shift=shift)


def trips_scenario(scenario: Scenario, result: RunResult) -> Scenario:
    """The same fleet without orders: the stops of the orders each vehicle served or held at the end as its
    tasks, order by order as they were assigned to it (the reference dispatcher gives an idle vehicle one
    order at a time, so that is the order it drove them in)."""
    held: dict[int, list[tuple[float, str, list[int]]]] = defaultdict(list)
    for order in result.orders:
        if order["vehicle"] is not None:
            held[order["vehicle"]].append((order["assigned"], order["id"], order["stops"]))
    tasks: list[Task] = []
    for vehicle in sorted(held):
        for _, _, stops in sorted(held[vehicle]):
            tasks += [Task(id=len(tasks) + i, vehicle_id=vehicle, goal_segment=s) for i, s in enumerate(stops, 1)]
    assert scenario.shift is not None
    settings = dataclasses.replace(scenario.settings, deadlock_after=2 * scenario.shift.duration)
    return dataclasses.replace(
        scenario, orders=(), order_stream=None, dispatcher=None, tasks=tuple(tasks), settings=settings
    )


@dataclass
class Run:
    result: RunResult
    dispatcher: float  # seconds inside the dispatcher
    bookkeeping: float  # seconds of dispatch and order bookkeeping, the dispatcher left out
    stalls: float  # seconds of the shift's stall check (explaining each stall found included)

    @property
    def vehicle_steps(self) -> int:
        return self.result.steps * len(self.result.metrics.distance)

    @property
    def harness(self) -> float:
        m = self.result.metrics
        return m.wall_time - m.planner_wall_time - self.dispatcher

    def per_vehicle_step(self) -> float:
        return self.harness / self.vehicle_steps * 1e6


def run_orders(scenario: Scenario) -> Run:
    spent: dict[str, float] = defaultdict(float)
    dispatcher = TimedDispatcher()
    with bookkeeping_clocks(spent):
        result = run_scenario(scenario, ReservingPlanner(), keep_trace=False, dispatcher=dispatcher)
    stalls = spent.pop("check_stalls", 0.0)  # (none with the compiled loop, which the clocks do not reach)
    return Run(result, dispatcher.seconds, sum(spent.values()) - dispatcher.seconds, stalls)


def run_trips(scenario: Scenario) -> Run:
    return Run(run_scenario(scenario, ReservingPlanner(), keep_trace=False), 0.0, 0.0, 0.0)


def show_measures(result: RunResult) -> None:
    assert result.measures is not None
    m = result.measures
    service = m.service_time
    # (No service time when no order released in the window was completed in it: shown as "–".)
    median, p95 = (f"{service.median:.0f} s", f"{service.p95:.0f} s") if service else ("–", "–")
    print(
        f"  measures (after {m.window[0]:.0f} s warm-up): {m.released} released, {m.completed} completed, "
        f"{m.orders_per_hour:.1f} orders/h, service median {median}, "
        f"p95 {p95}; utilisation {m.utilisation:.0%} (idle {m.idle_share:.0%}, "
        f"dwelling {m.dwelling_share:.0%}, blocked {m.blocked_share:.0%}); stalls {m.stalls}; "
        f"backlog slope {m.backlog_slope:+.1f}/h, overloaded: {m.overloaded}"
    )


SHIFT_TARGET = 180.0  # seconds of wall time for the 8-hour shift of 100 vehicles (issue 46)


def wall_only(case: Case, seconds: float, repeat: int, folder: Path) -> bool:
    """Run ``case`` with its orders ``repeat`` times; print the wall time (the shift-in-minutes target)."""
    scenario = orders_scenario(case, folder, seconds)
    print(f"\n{case.name}: {len(scenario.vehicles)} vehicles, {seconds / 3600:g} h simulated, orders only", flush=True)
    runs = []
    for _ in range(repeat):
        runs.append(run_orders(scenario))
        r, m = runs[-1].result, runs[-1].result.metrics
        print(
            f"  wall {m.wall_time:8.1f} s  planner {m.planner_wall_time:7.1f} s  dispatcher {runs[-1].dispatcher:6.2f} s  "
            f"harness {runs[-1].per_vehicle_step():6.2f} µs/vs  calls {m.planner_calls}  {r.trace_hash[:12]}  "
            f"ended {r.ended} at {r.sim_time:.0f} s",
            flush=True,
        )
    show_measures(runs[0].result)
    wall = statistics.median(run.result.metrics.wall_time for run in runs)
    judged = case.name == "shift100" and seconds == 8 * 3600.0  # the target is the whole 8-hour shift
    verdict = ("met" if wall <= SHIFT_TARGET else "MISSED") if judged else "not judged: not the 8-hour shift100"
    print(
        f"  wall time: {wall:.1f} s, median of {repeat} ({seconds / wall:.0f}x realtime) "
        f"[target <= {SHIFT_TARGET:.0f} s for 8 h of 100: {verdict}]"
    )
    return len({run.result.trace_hash for run in runs}) == 1 and (not judged or wall <= SHIFT_TARGET)


def measure(case: Case, seconds: float, repeat: int, folder: Path) -> bool:
    """Run ``case``; print its figures; True when its target is met and its hashes agree."""
    scenario = orders_scenario(case, folder, seconds)
    vehicles = len(scenario.vehicles)
    print(
        f"\n{case.name}: {vehicles} vehicles, {seconds / 3600:g} h simulated, {len(scenario.layout.segments)} segments, "
        f"{case.rate:g} orders/h",
        flush=True,
    )
    orders: list[Run] = []
    trips: list[Run] = []
    twin: Scenario | None = None
    for number in range(repeat):
        for kind in ("orders", "trips") if number % 2 == 0 else ("trips", "orders"):
            if kind == "orders":
                orders.append(run_orders(scenario))
                twin = twin or trips_scenario(scenario, orders[-1].result)  # the first repeat runs orders first
            else:
                assert twin is not None
                trips.append(run_trips(twin))
            last = orders[-1] if kind == "orders" else trips[-1]
            r, m = last.result, last.result.metrics
            print(
                f"  {kind:<6} wall {m.wall_time:8.1f} s  planner {m.planner_wall_time:7.1f} s  "
                f"dispatcher {last.dispatcher:6.2f} s  harness {last.per_vehicle_step():6.2f} µs/vs  "
                f"tasks {r.tasks_completed}/{r.tasks_total}  {r.ended}",
                flush=True,
            )
    ok = True
    for kind, runs in (("orders", orders), ("trips", trips)):
        if len({run.result.trace_hash for run in runs}) != 1:
            print(f"  {kind} runs gave different trace hashes: not deterministic")
            ok = False
    show_measures(orders[0].result)
    with_orders = statistics.median(run.per_vehicle_step() for run in orders)
    without = statistics.median(run.per_vehicle_step() for run in trips)
    paired = statistics.median(
        a.per_vehicle_step() / b.per_vehicle_step() - 1 for a, b in zip(orders, trips, strict=False)
    )
    inside = statistics.median(run.bookkeeping / (run.harness - run.bookkeeping - run.stalls) for run in orders)
    booked = statistics.median(run.bookkeeping / run.vehicle_steps * 1e6 for run in orders)
    stalls = statistics.median(run.stalls / (run.harness - run.bookkeeping - run.stalls) for run in orders)
    stalled = statistics.median(run.stalls / run.vehicle_steps * 1e6 for run in orders)
    wall = statistics.median(run.result.metrics.wall_time for run in orders)
    realtime = seconds / wall
    print(
        f"  harness µs per vehicle-step (medians of {repeat}): with orders {with_orders:.2f}, the same trips "
        f"without {without:.2f}: {paired:+.1%} (median of paired ratios)\n"
        f"  inside the orders run: dispatch and order bookkeeping {booked:.2f} µs/vs, {inside:+.1%} of the rest "
        f"of the harness [target <= {TARGET_ADDED:.0%}]; the stall check {stalled:.2f} µs/vs, {stalls:+.1%}\n"
        f"  wall time of the {case.name} with orders: {wall:.1f} s ({realtime:.0f}x realtime; median of {repeat})"
    )
    return ok and inside <= TARGET_ADDED


def profile(case: Case, seconds: float, folder: Path, top: int) -> None:
    scenario = orders_scenario(case, folder, seconds)
    profiler = cProfile.Profile()
    profiler.runcall(
        run_scenario, scenario, ReservingPlanner(), keep_trace=False, dispatcher=NearestVehicleDispatcher()
    )
    stats = pstats.Stats(profiler)
    entries = stats.stats  # type: ignore[attr-defined]  # {(file, line, name): (cc, nc, tt, ct, callers)}
    total = sum(tt for _, _, tt, _, _ in entries.values())
    ours = [
        (key, value)
        for key, value in entries.items()
        if "/fleetsim/dispatch/" in key[0] or key[0].endswith("/fleetsim/sim/dispatching.py")
    ]
    own = sum(value[2] for _, value in ours)
    print(f"\nprofiled {case.name} (under cProfile, {total:.1f} s own time in all): {own / total:.1%} in dispatch")
    print(f"top {top} functions of fleetsim/dispatch and sim/dispatching.py by own time (calls, own s, share):")
    for (filename, line, name), (_, calls, tt, _, _) in sorted(ours, key=lambda item: -item[1][2])[:top]:
        where = filename.rsplit("/fleetsim/", 1)[-1]
        print(f"  {calls:>9} {tt:8.2f} {tt / total:6.1%}  {name} ({where}:{line})")


# -- this tree against another commit ------------------------------------------------------------------


def run_child(suite_file: Path, case: Case, seconds: float) -> None:
    """One orders run of the generated suite (in whichever tree's fleetsim is importable): one JSON line."""
    scenario = with_orders(suite_file, case, seconds)
    dispatcher = TimedDispatcher()
    result = run_scenario(scenario, ReservingPlanner(), keep_trace=False, dispatcher=dispatcher)
    m = result.metrics
    harness = m.wall_time - m.planner_wall_time - dispatcher.seconds
    print(json.dumps({
        "hash": result.trace_hash,
        "wall": m.wall_time,
        "planner": m.planner_wall_time,
        "harness": harness / (result.steps * len(scenario.vehicles)) * 1e6,
        "calls": m.planner_calls,
        "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }))  # fmt: skip


def run_in(tree: Path, suite_file: Path, case: Case, seconds: float) -> subprocess.Popen[str]:
    """The child of :func:`run_child` started in ``tree`` (its fleetsim first on the path)."""
    command = [sys.executable, str(Path(__file__).resolve()), "--child", str(suite_file), "--case", case.name]
    command += ["--child-seconds", repr(seconds)]
    env = {**os.environ, "PYTHONPATH": str(tree)}
    return subprocess.Popen(command, cwd=tree, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def finished(tree: Path, child: subprocess.Popen[str]) -> dict[str, Any]:
    out, err = child.communicate()
    if child.returncode != 0:
        raise SystemExit(f"the shift in {tree} failed:\n{err}")
    figures: dict[str, Any] = json.loads(out.splitlines()[-1])
    return figures


AGAIN = "this tree, again"  # this tree once more, beside the compiled build


def versus(
    ref: str, case: Case, seconds: float, repeat: int, parallel: bool, folder: Path, compiled: bool = False
) -> bool:
    """``case`` in REF and this tree, ``repeat`` rounds (with ``compiled``, then this tree's compiled build
    and this tree again); True when every run gives the same trace hash."""
    suite_file = generate_warehouse(folder, case.site).suite
    how = "at once, one per core" if parallel else "in turn"
    print(
        f"\n{case.name}: {case.site.vehicles} vehicles, {seconds / 3600:g} h simulated, {repeat} rounds, the trees {how}"
    )
    with trees(ref, compiled) as found:
        names = list(found)
        pairs = [(names[0], names[1])]  # (run first, and the tree whose speed-up over it is printed)
        if compiled:
            pairs.append((AGAIN, names[2]))
        tree_of = {**found, AGAIN: found[names[1]]}
        rounds: dict[str, list[dict[str, Any]]] = {name: [] for pair in pairs for name in pair}
        for _ in range(repeat):
            for pair in pairs:
                if parallel:
                    children = {name: run_in(tree_of[name], suite_file, case, seconds) for name in pair}
                    for name, child in children.items():
                        rounds[name].append(finished(tree_of[name], child))
                else:
                    for name in pair:
                        rounds[name].append(finished(tree_of[name], run_in(tree_of[name], suite_file, case, seconds)))
            print("  " + "   ".join(f"{name}: {r[-1]['wall']:.1f} s" for name, r in rounds.items()), flush=True)
    for name, runs in rounds.items():
        print(f"  {name}")
        for label, key, form in VERSUS_FIGURES:
            print(f"    {label:<18} {column(runs, key, form)}")
    walls = {name: statistics.median(float(run["wall"]) for run in runs) for name, runs in rounds.items()}
    for slower, faster in pairs:
        print(f"  {faster} runs the shift {walls[slower] / walls[faster]:.2f}x as fast as {slower}")
    hashes = {str(run["hash"]) for runs in rounds.values() for run in runs}
    print("  trace hashes agree" if len(hashes) == 1 else f"  trace hashes DIFFER: {sorted(h[:12] for h in hashes)}")
    return len(hashes) == 1


# (label, key, format) of each figure printed per tree with --vs.
VERSUS_FIGURES = (
    ("wall s", "wall", "{:8.1f}"),
    ("planner s", "planner", "{:8.1f}"),
    ("harness µs/vs", "harness", "{:8.2f}"),
    ("planner calls", "calls", "{:8.0f}"),
    ("peak MiB", "peak_mib", "{:8.0f}"),
)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--case", choices=("shift", "shift100", "stretch", "both"), default="both")
    parser.add_argument("--orders-only", action="store_true", help="only the orders run's wall time (no twin)")
    parser.add_argument("--hours", type=float, default=8.0, help="the shift's simulated hours")
    parser.add_argument("--minutes", type=float, default=10.0, help="the stretch's simulated minutes")
    parser.add_argument("--repeat", type=int, default=3, help="paired runs per case")
    parser.add_argument("--profile", choices=("shift", "stretch"), help="profile that case's orders run")
    parser.add_argument("--top", type=int, default=25, help="functions listed with --profile")
    parser.add_argument("--vs", metavar="REF", help="compare the orders run with commit REF side by side instead")
    parser.add_argument("--parallel", action="store_true", help="with --vs: run the two trees at once, a core each")
    parser.add_argument("--compiled", action="store_true", help="with --vs: also this tree's compiled build")
    # (--vs: one run of a generated suite, in the tree whose fleetsim is on the path)
    parser.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--child-seconds", type=float, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child is not None:
        run_child(args.child, CASES[args.case], args.child_seconds)
        return 0
    seconds = {"shift": args.hours * 3600.0, "shift100": args.hours * 3600.0, "stretch": args.minutes * 60.0}
    if args.repeat < 1:
        parser.error(f"--repeat={args.repeat} must be at least 1")
    if not args.hours > 0 or not args.minutes > 0:
        parser.error(f"--hours={args.hours} and --minutes={args.minutes} must be > 0")
    if args.parallel and args.vs is None:
        parser.error("--parallel runs the two trees of --vs at once: give --vs REF")
    if args.compiled and args.vs is None:
        parser.error("--compiled adds this tree's compiled build to --vs: give --vs REF")
    if not args.orders_only and "fleetsim.sim.loop" in compiled_modules():
        parser.error("the bookkeeping figures time the loop's methods from outside, which the compiled build's loop "
                     "does not let them: with it, use --orders-only (the wall time)")  # fmt: skip
    ok = True
    with tempfile.TemporaryDirectory() as tmp:
        if args.profile is not None:
            profile(CASES[args.profile], seconds[args.profile], Path(tmp) / "profile", args.top)
            return 0
        for name in ("shift", "stretch") if args.case == "both" else (args.case,):
            if args.vs is not None:
                if not versus(
                    args.vs, CASES[name], seconds[name], args.repeat, args.parallel, Path(tmp) / name, args.compiled
                ):
                    return 1
                continue
            how = wall_only if args.orders_only else measure
            ok = how(CASES[name], seconds[name], args.repeat, Path(tmp) / name) and ok
    if args.vs is not None:
        return 0
    print("\ntarget met" if ok else "\nTARGET MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
