"""Simulated steps per second, realtime factor and planner vs harness share of wall time, per fleet size.

    python benchmarks/simulation.py [--sizes 10,100,1000] [--time-limit 60] [--large-time-limit 5]
                                    [--planning-period 0.1] [--seed 1] [--repeat 1] [--phases]
                                    [--profile 100:ReservingPlanner] [--top 30] [--site warehouse]
                                    [--vs REF [--rounds 3] [--compiled]]

Targets (issue): 100 vehicles with ReservingPlanner run at >= 20x realtime with the harness's own share
of wall time <= 25 %, and 1000 vehicles run at all.

Each fleet gets a generated warehouse lattice with about four aisles per vehicle, vehicles on
non-conflicting aisles and 2-3 tasks each to aisles a few junctions away (``warehouse.write_fleet_scenario``;
seeded). The scenario folder is loaded like any other, with ``stop_on`` empty (BFS runs go on after
alerts) and a fixed ``time_limit`` so every run simulates comparable time; fleets of 1000 or more use
``--large-time-limit`` (each of their steps takes about a second). Every other setting is the default
(``--planning-period`` excepted, for exploring). Both reference planners run on each fleet, without a
trace kept. The planner share is the time inside planner calls (the guard's measure,
``Metrics.planner_wall_time``, which includes the guard's own per-call cost of arming the timeout); the
harness share is the rest of the run's wall time. ``µs/call`` is the planner's time per call and
``harness µs/vs`` the harness's time per vehicle-step (vehicles × steps): the share is set by these two
figures, whatever the machine's speed (a call per busy vehicle per step at the default planning period).

``--repeat N`` runs each case N times and keeps the run with the least wall time (this VM's speed varies
by tens of per cent from minute to minute). ``--phases`` splits the target case's harness time by the
loop's steps (SPEC §9), timing the loop's own step methods from outside: planning less the time inside
the planner (the call overhead: task lookup, snapshot, guard, checking and applying responses), the
reservation check, motion, and the trace (encoding and hashing the step); "rest" is bookkeeping and the
loop itself.

``--site congestion`` runs the site where the whole fleet queues at a dozen stations instead
(``warehouse.write_congestion_scenario``: the reference planner at its slowest).

``--vs REF`` compares this tree with commit REF instead, side by side in one invocation: for each size,
ReservingPlanner on the chosen site in both trees in alternating fresh processes, ``--rounds`` rounds of
the fastest of ``--repeat`` runs (``benchmarks/compare.py``): real-time factor, planner and harness time
per vehicle-step, planner time per call, calls, peak memory, the speed-up and whether the hashes agree.
``--compiled`` adds this tree's optional compiled build (mypyc) as a third tree.

``--profile SIZE:PLANNER`` runs that case once more under cProfile and prints its own time by module
and the functions with the most own time (cProfile slows pure-Python code about 2x; read shares, not
seconds).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))

from compare import SITES, Case, compare_cases

from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning.protocol import Planner
from fleetsim.scenario import Scenario, ScenarioSettings
from fleetsim.sim import loop
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult
from fleetsim.sim.trace import Trace

PLANNERS: dict[str, type[Planner]] = {"BFSPlanner": BFSPlanner, "ReservingPlanner": ReservingPlanner}
LARGE_FLEET = 1000
TARGET_SIZE, TARGET_PLANNER, TARGET_REALTIME, TARGET_HARNESS = 100, "ReservingPlanner", 20.0, 0.25
HEADER = (
    f"{'vehicles':>8} {'planner':<16} {'sim s':>6} {'steps':>6} {'wall s':>8} {'steps/s':>8} {'realtime':>8} "
    f"{'planner':>7} {'harness':>7} {'calls':>7} {'µs/call':>7} {'harness µs/vs':>13} {'tasks':>11} {'alerts':>6}  ended"
)
# The loop's step methods timed by --phases, with the names they are reported under.
PHASES = {"plan": "planning", "check_reservations": "reservation check", "move": "motion"}


def fleet_scenario(folder: Path, vehicles: int, settings: ScenarioSettings, seed: int, site: str) -> Scenario:
    SITES[site](folder, vehicles, seed=seed)
    return load_scenario_dir(folder, settings=settings)


def row(vehicles: int, planner: str, result: RunResult) -> str:
    m = result.metrics
    planner_share = m.planner_wall_time / m.wall_time
    per_call = m.planner_wall_time / max(m.planner_calls, 1) * 1e6
    per_vehicle_step = (m.wall_time - m.planner_wall_time) / (result.steps * vehicles) * 1e6
    tasks = f"{result.tasks_completed}/{result.tasks_total}"
    return (
        f"{vehicles:>8} {planner:<16} {result.sim_time:>6.1f} {result.steps:>6} {m.wall_time:>8.2f} "
        f"{result.steps / m.wall_time:>8.1f} {m.realtime_factor or 0.0:>7.2f}x {planner_share:>7.1%} "
        f"{1 - planner_share:>7.1%} {m.planner_calls:>7} {per_call:>7.1f} {per_vehicle_step:>13.2f} "
        f"{tasks:>11} {len(result.collisions):>6}  {result.ended}"
    )


def best_run(scenario: Scenario, planner: type[Planner], name: str, repeat: int) -> RunResult:
    """The run with the least wall time of ``repeat`` (the same behaviour each time: the hash says so)."""
    runs = [run_scenario(scenario, planner(), planner_name=name, keep_trace=False) for _ in range(repeat)]
    if len({run.trace_hash for run in runs}) != 1:
        raise SystemExit(f"{name} gave different trace hashes on the same scenario: the run is not deterministic")
    return min(runs, key=lambda run: run.metrics.wall_time)


@contextmanager
def phase_clocks(spent: dict[str, float]) -> Iterator[None]:
    """Adds the wall time of each of the loop's step methods (and the trace's) to ``spent`` while open."""
    originals: list[tuple[type, str, Callable[..., Any]]] = []

    def timed(owner: type, method: str, label: str) -> None:
        original = getattr(owner, method)
        originals.append((owner, method, original))

        def clocked(*args: Any, **kwargs: Any) -> Any:
            started = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                spent[label] += time.perf_counter() - started

        setattr(owner, method, clocked)

    for method, label in PHASES.items():
        timed(loop._Run, method, label)
    timed(Trace, "record", "trace")
    try:
        yield
    finally:
        for owner, method, original in originals:
            setattr(owner, method, original)


def show_phases(scenario: Scenario, vehicles: int, name: str, repeat: int) -> None:
    """The harness's time by the loop's steps, per vehicle-step, from the run with the least harness time."""
    best: tuple[float, dict[str, float], RunResult] | None = None
    for _ in range(repeat):
        spent: dict[str, float] = defaultdict(float)
        with phase_clocks(spent):
            result = run_scenario(scenario, PLANNERS[name](), planner_name=name, keep_trace=False)
        harness = result.metrics.wall_time - result.metrics.planner_wall_time
        if best is None or harness < best[0]:
            best = (harness, spent, result)
    assert best is not None
    harness, spent, result = best
    m = result.metrics
    parts = {
        "planner call overhead": spent["planning"] - m.planner_wall_time,
        "reservation check": spent["reservation check"],
        "motion": spent["motion"],
        "trace": spent["trace"],
    }
    parts["rest (bookkeeping, the loop)"] = harness - sum(parts.values())
    vehicle_steps = result.steps * vehicles
    print(
        f"\nharness time by step of the loop, {vehicles} vehicles, {name} (least harness time of {repeat}; "
        f"timing the phases adds its own small cost):"
    )
    print(
        f"  {'inside the planner':<30} {m.planner_wall_time:7.3f} s {m.planner_wall_time / max(m.planner_calls, 1) * 1e6:7.2f} µs/call"
    )
    for label, seconds in parts.items():
        print(
            f"  {label:<30} {seconds:7.3f} s {seconds / vehicle_steps * 1e6:7.2f} µs/vehicle-step {seconds / harness:6.1%}"
        )
    print(
        f"  {'harness in all':<30} {harness:7.3f} s {harness / vehicle_steps * 1e6:7.2f} µs/vehicle-step "
        f"(share {harness / m.wall_time:.1%})"
    )


def _area(filename: str) -> str:
    """A profile entry's module, relative to the package (``fleetsim/sim/loop.py``), or a coarse bucket."""
    path = filename.replace("\\", "/")
    if "/fleetsim/" in path:
        return "fleetsim/" + path.rsplit("/fleetsim/", 1)[1]
    if filename.startswith(("~", "<")):
        return "builtins (C functions: dict, tuple, numpy, json, ...)"
    return "other: " + path.rsplit("/", 2)[-2] + "/" + path.rsplit("/", 1)[-1]


def show_profile(profile: cProfile.Profile, top: int) -> None:
    stats = pstats.Stats(profile)
    entries = stats.stats  # type: ignore[attr-defined]  # {(file, line, name): (cc, nc, tt, ct, callers)}
    total = sum(tt for _, _, tt, _, _ in entries.values())
    by_area: dict[str, float] = defaultdict(float)
    for (filename, _, _), (_, _, tt, _, _) in entries.items():
        by_area[_area(filename)] += tt
    print(f"\nown time by module (total {total:.2f} s under the profiler):")
    for area, seconds in sorted(by_area.items(), key=lambda item: -item[1]):
        if seconds / total >= 0.005:
            print(f"  {seconds / total:6.1%} {seconds:8.2f} s  {area}")
    print(f"\ntop {top} functions by own time (calls, own s, share, cumulative s):")
    ranked = sorted(entries.items(), key=lambda item: -item[1][2])[:top]
    for (filename, line, name), (_, calls, tt, ct, _) in ranked:
        where = "builtin" if filename.startswith(("~", "<")) else f"{_area(filename)}:{line}"
        print(f"  {calls:>9} {tt:8.2f} {tt / total:6.1%} {ct:8.2f}  {name} ({where})")


def parse_sizes(text: str) -> list[int]:
    sizes = [part.strip() for part in text.split(",")]
    if not all(size.isdigit() and int(size) > 0 for size in sizes):
        msg = f"--sizes={text!r} must be positive fleet sizes separated by commas, e.g. 10,100,1000"
        raise argparse.ArgumentTypeError(msg)
    return [int(size) for size in sizes]


def parse_profile(text: str) -> tuple[int, str]:
    size, _, planner = text.partition(":")
    if planner not in PLANNERS or not size.isdigit():
        msg = f"--profile={text!r} must be SIZE:PLANNER with PLANNER one of {', '.join(PLANNERS)}"
        raise argparse.ArgumentTypeError(msg)
    return int(size), planner


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=parse_sizes, default=[10, 100, 1000])
    parser.add_argument("--time-limit", type=float, default=60.0, help="simulated seconds per run")
    parser.add_argument(
        "--large-time-limit", type=float, default=5.0, help=f"simulated seconds for fleets of {LARGE_FLEET} or more"
    )
    parser.add_argument("--planning-period", type=float, default=ScenarioSettings().planning_period)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--repeat", type=int, default=1, help="runs per case; the one with the least wall time is shown"
    )
    parser.add_argument(
        "--phases", action="store_true", help=f"split the harness time of {TARGET_SIZE}:{TARGET_PLANNER} by loop step"
    )
    parser.add_argument("--profile", type=parse_profile, metavar="SIZE:PLANNER")
    parser.add_argument("--top", type=int, default=30, help="functions listed with --profile")
    parser.add_argument("--site", choices=SITES, default="warehouse")
    parser.add_argument("--vs", metavar="REF", help="compare with commit REF side by side instead")
    parser.add_argument(
        "--compiled", action="store_true", help="with --vs: also run this tree's compiled build (mypyc)"
    )
    parser.add_argument("--rounds", type=int, default=3, help="alternating rounds per size with --vs")
    args = parser.parse_args()
    if args.repeat < 1:
        parser.error(f"--repeat={args.repeat} must be at least 1")
    if args.vs is not None:
        cases = [
            Case(size, args.large_time_limit if size >= LARGE_FLEET else args.time_limit, TARGET_PLANNER,
                 args.site, args.seed, args.repeat)
            for size in args.sizes
        ]  # fmt: skip
        compare_cases(args.vs, cases, args.rounds, args.compiled)
        return 0

    def settings(size: int) -> ScenarioSettings:
        time_limit = args.large_time_limit if size >= LARGE_FLEET else args.time_limit
        return ScenarioSettings(time_limit=time_limit, stop_on=(), planning_period=args.planning_period)

    results: dict[tuple[int, str], RunResult] = {}
    print(HEADER)
    with tempfile.TemporaryDirectory() as tmp:
        for size in args.sizes:
            scenario = fleet_scenario(Path(tmp) / f"{args.site}-{size}", size, settings(size), args.seed, args.site)
            for name, planner in PLANNERS.items():
                result = best_run(scenario, planner, name, args.repeat if size < LARGE_FLEET else 1)
                results[size, name] = result
                print(row(size, name, result), flush=True)
        if args.phases:
            scenario = fleet_scenario(
                Path(tmp) / f"phases-{TARGET_SIZE}", TARGET_SIZE, settings(TARGET_SIZE), args.seed, args.site
            )
            show_phases(scenario, TARGET_SIZE, TARGET_PLANNER, args.repeat)
        if args.profile is not None:
            size, name = args.profile
            scenario = fleet_scenario(Path(tmp) / f"profile-{size}", size, settings(size), args.seed, args.site)
            profile = cProfile.Profile()
            result = profile.runcall(run_scenario, scenario, PLANNERS[name](), planner_name=name, keep_trace=False)
            print(f"\nprofiled (under cProfile):\n{HEADER}\n{row(size, name, result)}")
            show_profile(profile, args.top)

    print()
    target = results.get((TARGET_SIZE, TARGET_PLANNER))
    large = [result for (size, _), result in results.items() if size >= LARGE_FLEET]
    if target is None or not large:
        print(f"targets not checked: --sizes must include {TARGET_SIZE} and {LARGE_FLEET}")
        return 0
    m = target.metrics
    realtime = m.realtime_factor or 0.0
    harness = 1 - m.planner_wall_time / m.wall_time
    print(
        f"{TARGET_SIZE} vehicles, {TARGET_PLANNER}: realtime {realtime:.1f}x [target >= {TARGET_REALTIME:g}x], "
        f"harness share {harness:.1%} [target <= {TARGET_HARNESS:.0%}]"
    )
    print(
        f"{LARGE_FLEET}+ vehicles: {len(large)} runs finished ({', '.join(r.ended for r in large)}) [target: run at all]"
    )
    ok = realtime >= TARGET_REALTIME and harness <= TARGET_HARNESS
    print("targets met" if ok else "TARGETS MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
