"""Compare the speed of this tree with another commit's, in alternating runs on one scenario.

    python benchmarks/compare.py REF [--rounds 4] [--vehicles 100] [--planner ReservingPlanner]
                                     [--seconds 60] [--seed 1] [--site warehouse|congestion] [--best-of 3]
                                     [--compiled]

A shared machine's speed drifts by tens of per cent within minutes, so two figures taken at different
times cannot tell a change of a few per cent from the drift. This script checks ``REF`` out into a
temporary git worktree and runs the same generated scenario in both trees in turn, ``--rounds`` times,
each round a fresh process per tree keeping the fastest of ``--best-of`` runs. It prints, per tree, the
real-time factor (simulated seconds per wall second), the planner's time per call and per vehicle-step
(calls differ where a planner's quiet hint lets vehicles rest), the harness's time per vehicle-step, the
harness share, the calls made and the process's peak memory, every round and their medians; then how
many times faster this tree simulates than REF (the ratio of the median real-time factors), and whether
the two trees' trace hashes agree (a pure speed-up leaves behaviour, and so the hash, unchanged). The
scenario is generated once, by this tree's ``warehouse.py`` (``--site``: the lattice with tasks a few
junctions away, or the congestion site where the fleet queues at a dozen stations), and loaded by both.

``--compiled`` adds a third tree: this tree's optional compiled build (``scripts/compiled_copy.py``, mypyc),
built in a temporary folder first, so one invocation shows REF, this tree and its compiled build.

``benchmarks/simulation.py --vs REF`` and ``benchmarks/scale.py --vs REF`` run the same comparison for
each of their fleet sizes (:func:`side_by_side`).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import write_congestion_scenario, write_fleet_scenario

# Site generators: (folder, vehicles, seed=...) -> the folder written.
SITES: dict[str, Callable[..., Path]] = {"warehouse": write_fleet_scenario, "congestion": write_congestion_scenario}
HERE = Path(__file__).resolve().parent.parent

# Run inside each tree: the fastest of N runs of the scenario, as one JSON line.
CHILD = """
import json, resource, sys
from pathlib import Path
from fleetsim import planners
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.scenario import ScenarioSettings
from fleetsim.sim.loop import run_scenario
folder, planner, seconds, vehicles, best_of = Path(sys.argv[1]), sys.argv[2], float(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
scenario = load_scenario_dir(folder, settings=ScenarioSettings(time_limit=seconds, stop_on=()))
runs = [run_scenario(scenario, getattr(planners, planner)(), keep_trace=False) for _ in range(best_of)]
if len({run.trace_hash for run in runs}) != 1:
    raise SystemExit("the same scenario gave different trace hashes: the run is not deterministic")
best = min(runs, key=lambda run: run.metrics.wall_time)
m = best.metrics
print(json.dumps({
    "hash": best.trace_hash,
    "realtime": best.sim_time / m.wall_time,
    "per_call": m.planner_wall_time / max(m.planner_calls, 1) * 1e6,
    "planner_per_vehicle_step": m.planner_wall_time / (best.steps * vehicles) * 1e6,
    "per_vehicle_step": (m.wall_time - m.planner_wall_time) / (best.steps * vehicles) * 1e6,
    "share": 1.0 - m.planner_wall_time / m.wall_time,
    "calls": m.planner_calls,
    "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
}))
"""

# (label, key, format) of each figure printed per tree.
FIGURES = (
    ("real time x", "realtime", "{:7.1f}"),
    ("planner µs/call", "per_call", "{:7.1f}"),
    ("planner µs/vs", "planner_per_vehicle_step", "{:7.2f}"),
    ("harness µs/vs", "per_vehicle_step", "{:7.2f}"),
    ("harness share", "share", "{:7.1%}"),
    ("planner calls", "calls", "{:7.0f}"),
    ("peak MiB", "peak_mib", "{:7.0f}"),
)

Results = dict[str, list[dict[str, float | str]]]  # tree name -> one figure set per round


@dataclass(frozen=True)
class Case:
    """One scenario to compare on."""

    vehicles: int
    seconds: float
    planner: str = "ReservingPlanner"
    site: str = "warehouse"
    seed: int = 1
    best_of: int = 3


@contextmanager
def trees(ref: str, compiled: bool = False) -> Iterator[dict[str, Path]]:
    """``REF`` checked out in a temporary worktree, beside this tree (and with ``compiled`` this tree's
    compiled build, ``scripts/compiled_copy.py``): name -> folder."""
    commit = subprocess.run(
        ["git", "rev-parse", "--verify", f"{ref}^{{commit}}"], cwd=HERE, capture_output=True, text=True
    )
    if commit.returncode != 0:
        raise SystemExit(f"ref={ref!r} is not a commit of {HERE}: {commit.stderr.strip()}")
    sha = commit.stdout.strip()
    with tempfile.TemporaryDirectory() as tmp:
        worktree = Path(tmp) / "ref"
        subprocess.run(["git", "worktree", "add", "--detach", "-q", str(worktree), sha], cwd=HERE, check=True)
        try:
            both = {f"{ref} ({sha[:10]})": worktree, "this tree": HERE}
            if compiled:
                sys.path.append(str(HERE))  # scripts/, after any fleetsim on PYTHONPATH
                from scripts.compiled_copy import build_compiled_copy

                print("building this tree's compiled build (mypyc, about a minute) ...", flush=True)
                both["this tree, compiled"] = build_compiled_copy(Path(tmp) / "compiled")
            yield both
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(worktree)], cwd=HERE, check=False)


def run_in(tree: Path, folder: Path, case: Case) -> dict[str, float | str]:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    arguments = [str(folder), case.planner, str(case.seconds), str(case.vehicles), str(case.best_of)]
    done = subprocess.run(
        [sys.executable, "-c", CHILD, *arguments], cwd=tree, env=env, capture_output=True, text=True, check=False
    )
    if done.returncode != 0:
        raise SystemExit(f"the run in {tree} failed:\n{done.stderr}")
    result: dict[str, float | str] = json.loads(done.stdout.splitlines()[-1])
    return result


def side_by_side(both: dict[str, Path], case: Case, rounds: int) -> Results:
    """``rounds`` alternating rounds of ``case`` in each of ``both`` trees."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "scenario"
        SITES[case.site](folder, case.vehicles, seed=case.seed)
        results: Results = {name: [] for name in both}
        for _ in range(rounds):
            for name, tree in both.items():
                results[name].append(run_in(tree, folder, case))
    return results


def compare_cases(ref: str, cases: Iterable[Case], rounds: int, compiled: bool = False) -> None:
    """Each of ``cases`` side by side in ``ref`` and this tree (and its compiled build), reported one after
    the other."""
    with trees(ref, compiled) as both:
        for case in cases:
            report(side_by_side(both, case, rounds), case, rounds)
            print()


def column(results: list[dict[str, float | str]], key: str, form: str) -> str:
    """One figure of every round, then their median."""
    values = [float(result[key]) for result in results]
    return " ".join(form.format(v) for v in values) + "  median " + form.format(statistics.median(values))


def report(results: Results, case: Case, rounds: int) -> float:
    """Print the comparison: each later tree's median real-time factor against the first's (REF); returns
    that ratio for the last tree."""
    print(
        f"{case.site} site, {case.vehicles} vehicles, {case.planner}, {case.seconds:g} s simulated; "
        f"{rounds} alternating rounds, fastest of {case.best_of} runs each"
    )
    for name, figures in results.items():
        print(f"  {name}")
        for label, key, form in FIGURES:
            print(f"    {label:<22} {column(figures, key, form)}")
    medians = {name: statistics.median(float(r["realtime"]) for r in figures) for name, figures in results.items()}
    first, *later = medians
    for name in later:
        print(f"  {name} simulates {medians[name] / medians[first]:.2f}x as fast as {first}")
    hashes = {str(r["hash"]) for figures in results.values() for r in figures}
    print("  trace hashes agree" if len(hashes) == 1 else f"  trace hashes DIFFER: {sorted(h[:12] for h in hashes)}")
    return medians[later[-1]] / medians[first]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("ref", help="the commit to compare with (anything git rev-parse accepts)")
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--vehicles", type=int, default=100)
    parser.add_argument(
        "--planner", choices=["BFSPlanner", "GreedyPlanner", "ReservingPlanner"], default="ReservingPlanner"
    )
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--site", choices=SITES, default="warehouse")
    parser.add_argument("--best-of", type=int, default=3)
    parser.add_argument("--compiled", action="store_true", help="also run this tree's compiled build (mypyc)")
    args = parser.parse_args()
    case = Case(args.vehicles, args.seconds, args.planner, args.site, args.seed, args.best_of)
    compare_cases(args.ref, [case], args.rounds, args.compiled)
    return 0


if __name__ == "__main__":
    sys.exit(main())
