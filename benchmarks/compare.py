"""Compare the speed of this tree with another commit's, in alternating runs on one scenario.

    python benchmarks/compare.py REF [--rounds 4] [--vehicles 100] [--planner ReservingPlanner]
                                     [--seconds 60] [--seed 1] [--site warehouse|congestion]

A shared machine's speed drifts by tens of per cent within minutes, so two figures taken at different
times cannot tell a change of a few per cent from the drift. This script checks ``REF`` out into a
temporary git worktree and runs the same generated warehouse scenario in both trees in turn, ``--rounds``
times, each round a fresh process per tree keeping the best of three runs. It prints, per tree, the
real-time factor (simulated seconds per wall second), the planner's time per call and per vehicle-step
(calls differ where a planner's quiet hint lets vehicles rest), the harness's time per vehicle-step, the
harness share and the calls made, every round and their medians; then how many times faster this tree
simulates than REF (the ratio of the median real-time factors), and whether the two trees' trace hashes
agree (a pure speed-up leaves behaviour, and so the hash, unchanged). The scenario is generated once, by
this tree's ``warehouse.py`` (``--site``: the lattice with tasks a few junctions away, or the congestion
site where the fleet queues at a dozen stations), and loaded by both.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import write_congestion_scenario, write_fleet_scenario

SITES = {"warehouse": write_fleet_scenario, "congestion": write_congestion_scenario}

# Run inside each tree: the best of three runs of the scenario, as one JSON line.
CHILD = """
import json, sys
from pathlib import Path
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.scenario import ScenarioSettings
from fleetsim.sim.loop import run_scenario
folder, planner, seconds, vehicles = Path(sys.argv[1]), sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
scenario = load_scenario_dir(folder, settings=ScenarioSettings(time_limit=seconds, stop_on=()))
runs = [run_scenario(scenario, {"BFSPlanner": BFSPlanner, "ReservingPlanner": ReservingPlanner}[planner](), keep_trace=False)
        for _ in range(3)]
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
}))
"""


def run_in(tree: Path, folder: Path, args: argparse.Namespace) -> dict[str, float | str]:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    command = [sys.executable, "-c", CHILD, str(folder), args.planner, str(args.seconds), str(args.vehicles)]
    done = subprocess.run(command, cwd=tree, env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"the run in {tree} failed:\n{done.stderr}")
    result: dict[str, float | str] = json.loads(done.stdout.splitlines()[-1])
    return result


def column(results: list[dict[str, float | str]], key: str, form: str) -> str:
    """One figure of every round, then their median."""
    values = [float(result[key]) for result in results]
    return " ".join(form.format(v) for v in values) + "  median " + form.format(statistics.median(values))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("ref", help="the commit to compare with (anything git rev-parse accepts)")
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--vehicles", type=int, default=100)
    parser.add_argument("--planner", choices=["BFSPlanner", "ReservingPlanner"], default="ReservingPlanner")
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--site", choices=SITES, default="warehouse")
    args = parser.parse_args()
    here = Path(__file__).resolve().parent.parent
    commit = subprocess.run(
        ["git", "rev-parse", "--verify", f"{args.ref}^{{commit}}"], cwd=here, capture_output=True, text=True
    )
    if commit.returncode != 0:
        raise SystemExit(f"ref={args.ref!r} is not a commit of {here}: {commit.stderr.strip()}")
    with tempfile.TemporaryDirectory() as tmp:
        worktree, folder = Path(tmp) / "ref", Path(tmp) / "scenario"
        subprocess.run(
            ["git", "worktree", "add", "--detach", "-q", str(worktree), commit.stdout.strip()], cwd=here, check=True
        )
        try:
            SITES[args.site](folder, args.vehicles, seed=args.seed)
            trees = {f"{args.ref} ({commit.stdout.strip()[:10]})": worktree, "this tree": here}
            rounds: dict[str, list[dict[str, float | str]]] = {name: [] for name in trees}
            for _ in range(args.rounds):
                for name, tree in trees.items():
                    rounds[name].append(run_in(tree, folder, args))
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(worktree)], cwd=here, check=False)
    print(
        f"{args.site} site, {args.vehicles} vehicles, {args.planner}, {args.seconds:g} s simulated; "
        f"{args.rounds} alternating rounds, best of 3 runs each"
    )
    for name, results in rounds.items():
        print(f"  {name}")
        print(f"    real time x            {column(results, 'realtime', '{:6.1f}')}")
        print(f"    planner µs/call        {column(results, 'per_call', '{:6.1f}')}")
        print(f"    planner µs/vs          {column(results, 'planner_per_vehicle_step', '{:6.2f}')}")
        print(f"    harness µs/vs          {column(results, 'per_vehicle_step', '{:6.2f}')}")
        print(f"    harness share          {column(results, 'share', '{:6.1%}')}")
        print(f"    planner calls          {column(results, 'calls', '{:6.0f}')}")
    before, after = (statistics.median(float(r["realtime"]) for r in results) for results in rounds.values())
    print(f"  this tree simulates {after / before:.2f}x as fast as {args.ref}")
    hashes = {str(r["hash"]) for results in rounds.values() for r in results}
    print("  trace hashes agree" if len(hashes) == 1 else f"  trace hashes DIFFER: {sorted(h[:12] for h in hashes)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
