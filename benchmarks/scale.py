"""Does the harness cost the same per vehicle whatever the fleet size? 100, 1,000 and 10,000 vehicles.

    python benchmarks/scale.py [--sizes 100,1000,10000] [--seconds 60] [--repeat 3] [--planner BFSPlanner]
                               [--vs REF [--compiled]]

Each size gets a generated warehouse sized to the fleet (``warehouse.write_fleet_scenario``: about four
aisles per vehicle, 2-3 tasks each, seeded), written once in a process of its own. Each repeat loads it
and simulates ``--seconds`` in a fresh process, as a user's run loads a site written beforehand, so that
its peak memory (the process's maximum resident set) is that of loading and simulating, and no
generator's leftovers share its heap. The planner is a cheap one
(BFSPlanner by default: bounded breadth-first routes, three legs fixed per call) so that the harness's
own cost is what is measured; the harness's time is the run's wall time less the time inside planner
calls. Per size: harness µs per vehicle-step (median of the repeats, and its ratio to the first size's),
planner µs per call, realtime factor, peak memory, and the time to write and to load the scenario. The
trace hash of every repeat of a size must be the same (the script fails otherwise).

``--vs REF`` compares this tree with commit REF instead, side by side in one invocation: each size in
both trees in alternating fresh processes, ``--repeat`` rounds (``benchmarks/compare.py``): harness and
planner time per vehicle-step, peak memory, the speed-up and whether the hashes agree.
``--compiled`` adds this tree's optional compiled build (mypyc) as a third tree.

Targets (issue 18): harness µs per vehicle-step at 1,000 vehicles <= 1.2x the figure at 100, at
10,000 <= 1.5x; a 10,000-vehicle scenario simulates 60 s to the end in under 4 GiB.
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))

from compare import Case, compare_cases
from warehouse import write_fleet_scenario

PLANNERS = ("BFSPlanner", "GreedyPlanner", "ReservingPlanner")


def write_one(vehicles: int, folder: Path) -> float:
    """Generate and write the scenario of a fleet of ``vehicles``; the seconds it took."""
    start = time.perf_counter()
    write_fleet_scenario(folder, vehicles, seed=1)
    return time.perf_counter() - start


def run_one(vehicles: int, folder: Path, seconds: float, planner_name: str) -> dict[str, Any]:
    """Load and simulate one fleet's scenario in this process; its figures."""
    from fleetsim import planners
    from fleetsim.load.suites.scenario import load_scenario_dir
    from fleetsim.scenario import ScenarioSettings
    from fleetsim.sim.loop import run_scenario

    start = time.perf_counter()
    scenario = load_scenario_dir(folder, settings=ScenarioSettings(time_limit=seconds, stop_on=()))
    loaded = time.perf_counter()
    result = run_scenario(scenario, getattr(planners, planner_name)(), keep_trace=False)
    metrics = result.metrics
    vehicle_steps = vehicles * result.steps
    return {
        "vehicles": vehicles,
        "load_s": loaded - start,
        "sim_s": result.sim_time,
        "ended": result.ended,
        "hash": result.trace_hash,
        "harness_us_per_vs": (metrics.wall_time - metrics.planner_wall_time) / vehicle_steps * 1e6,
        "planner_us_per_call": metrics.planner_wall_time / max(metrics.planner_calls, 1) * 1e6,
        "realtime": metrics.realtime_factor,
        "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "tasks": f"{result.tasks_completed}/{result.tasks_total}",
    }


def _in_child(*arguments: str) -> Any:
    """This script run with ``arguments`` in a process of its own: the JSON it printed last."""
    command = [sys.executable, __file__, *arguments]
    output = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    return json.loads(output.strip().splitlines()[-1])


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default="100,1000,10000")
    parser.add_argument("--seconds", type=float, default=60.0, help="simulated seconds per run (default: 60)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--planner", choices=PLANNERS, default="BFSPlanner")
    parser.add_argument("--write", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--folder", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--vs", metavar="REF", help="compare with commit REF side by side instead")
    parser.add_argument(
        "--compiled", action="store_true", help="with --vs: also run this tree's compiled build (mypyc)"
    )
    args = parser.parse_args(argv)
    if args.vs is not None:
        cases = [Case(int(part), args.seconds, args.planner, best_of=1) for part in args.sizes.split(",")]
        compare_cases(args.vs, cases, args.repeat, args.compiled)
        return 0
    if args.write is not None:
        print(json.dumps(write_one(args.write, args.folder)))
        return 0
    if args.child is not None:
        print(json.dumps(run_one(args.child, args.folder, args.seconds, args.planner)))
        return 0
    sizes = [int(size) for size in args.sizes.split(",") if size]
    runs: dict[int, list[dict[str, Any]]] = {size: [] for size in sizes}
    with tempfile.TemporaryDirectory() as tmp:
        folders = {size: Path(tmp) / f"fleet-{size}" for size in sizes}
        written = {size: float(_in_child("--write", str(size), "--folder", str(folders[size]))) for size in sizes}
        for _ in range(args.repeat):  # the sizes in turn, so that each repeat sees the machine's same moments
            for size in sizes:
                child = ("--child", str(size), "--folder", str(folders[size]))
                runs[size].append(_in_child(*child, "--seconds", str(args.seconds), "--planner", args.planner))
    print(
        f"{args.planner}, {args.seconds:g} s simulated, median of {args.repeat} (each run loads the scenario, written beforehand, in a process of its own)"
    )
    print(
        f"{'vehicles':>8} {'harness µs/vs':>14} {'ratio':>6} {'µs/call':>8} {'realtime':>9} {'peak MiB':>9} {'write s':>8} {'load s':>7}  tasks      ended"
    )
    first: float | None = None
    failed = False
    for size in sizes:
        rows = runs[size]
        if len({row["hash"] for row in rows}) != 1:
            print(
                f"{size} vehicles: the repeats' trace hashes differ: {sorted({row['hash'][:12] for row in rows})}",
                file=sys.stderr,
            )
            failed = True
        harness = statistics.median(row["harness_us_per_vs"] for row in rows)
        first = harness if first is None else first
        print(
            f"{size:>8} {harness:>14.2f} {harness / first:>6.2f} {statistics.median(r['planner_us_per_call'] for r in rows):>8.1f} "
            f"{statistics.median(r['realtime'] for r in rows):>8.2f}x {max(r['peak_mib'] for r in rows):>9.0f} "
            f"{written[size]:>8.1f} {statistics.median(r['load_s'] for r in rows):>7.1f}  "
            f"{rows[0]['tasks']:<10} {rows[0]['ended']}"
        )
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
