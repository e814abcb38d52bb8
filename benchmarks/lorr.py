"""A League of Robot Runners problem imported and run, and a 140 x 500 warehouse map imported (issue 47).

    python benchmarks/lorr.py [--problem PATH] [--horizon 5000] [--short 500] [--repeat 3] [--agents 100]
                              [--tasks 20000] [--seed 47] [--skip-long] [--skip-warehouse]

The issue asks for the League's 2024 ``random-32-32-20`` example with 100 agents, run for 5,000 simulated
seconds with the reference dispatcher (``NearestVehicleDispatcher``) and planner (``ReservingPlanner``).
Give that problem file with ``--problem PATH`` (its map, agent and task files beside it, as the League
ships them). Without it (there is no network here to fetch the League's files), a problem of the same
shape is generated: a 32 x 32 map with 20 % of its cells blocked at random (seeded; like MovingAI's
``random-32-32-20``), 100 agents on free cells of its largest connected part, no two on neighbouring cells
(fleetsim's vehicles stand on segments, so neighbours would start in conflict), and ``--tasks``
pickup,delivery pairs of random free cells, as a 2024 problem with ``numTasksReveal`` 1.

Each problem runs with ``allow_start_conflicts: true`` and ``stop_on: []`` (a real problem's agents may
start side by side; the run goes on and counts its alerts), for a short horizon (``--short``, ``--repeat``
times) and the full one (``--horizon``, once; ``--skip-long`` leaves it out). Printed per horizon, medians
of the repeats:

- import time: from the problem file to a loaded scenario (problem, map, agent and task files, the lane
  graph and its layout, every order's reachability);
- harness time per vehicle-step: the run's wall time less the time inside the planner
  (``Metrics.planner_wall_time``) and inside the dispatcher (a wrapper round its ``dispatch``), over
  vehicles × steps; and the planner's and dispatcher's time beside it;
- the League's counts (tasks finished, sum of cost, makespan), the run's collision alerts and how it
  ended (``shift-end`` at the horizon; a ``deadlock`` ends it early: every robot with a task stood still
  for the scenario's ``deadlock_after``, 30 s).

Then the 140 x 500 warehouse map of ``benchmarks/movingai_import.py`` imported (``load_site_map``) and its
layout built, ``--repeat`` times: target, the import in under 3 s.
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import sys
import tempfile
import time
from collections import deque
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from movingai_import import warehouse_map

from fleetsim.dispatch.protocol import OrderBoard
from fleetsim.dispatchers import NearestVehicleDispatcher
from fleetsim.layout.layout import Layout, build_layout
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.load.movingai.agents import movingai_vehicle_type
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import ReservingPlanner
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario

SIDE = 32
BLOCKED_SHARE = 0.20


def random_map(seed: int) -> list[str]:
    """A 32 x 32 grid with 20 % of its cells blocked, drawn from ``seed``."""
    rng = random.Random(f"lorr-benchmark/{seed}/map")
    cells = [(r, c) for r in range(SIDE) for c in range(SIDE)]
    blocked = set(rng.sample(cells, round(BLOCKED_SHARE * len(cells))))
    return ["".join("@" if (r, c) in blocked else "." for c in range(SIDE)) for r in range(SIDE)]


def largest_part(rows: list[str]) -> list[tuple[int, int]]:
    """The free cells of the largest 4-connected part, in row order."""
    free = {(r, c) for r, row in enumerate(rows) for c, char in enumerate(row) if char == "."}
    best: set[tuple[int, int]] = set()
    seen: set[tuple[int, int]] = set()
    for start in sorted(free):
        if start in seen:
            continue
        part, queue = {start}, deque([start])
        while queue:
            r, c = queue.popleft()
            for cell in ((r, c + 1), (r + 1, c), (r, c - 1), (r - 1, c)):
                if cell in free and cell not in part:
                    part.add(cell)
                    queue.append(cell)
        seen |= part
        best = max(best, part, key=len)
    return sorted(best)


def generate_problem(folder: Path, agents: int, tasks: int, seed: int) -> Path:
    """A problem of the shape of the League's ``random-32-32-20`` example (see the module docstring)."""
    rows = random_map(seed)
    cells = largest_part(rows)
    rng = random.Random(f"lorr-benchmark/{seed}/agents")
    starts: list[tuple[int, int]] = []
    near: set[tuple[int, int]] = set()
    for cell in rng.sample(cells, len(cells)):
        if cell not in near:
            starts.append(cell)
            r, c = cell
            near |= {cell, (r, c + 1), (r + 1, c), (r, c - 1), (r - 1, c)}
        if len(starts) == agents:
            break
    if len(starts) < agents:
        raise SystemExit(f"only {len(starts)} agents fit apart on the generated map; ask for fewer")
    draws = random.Random(f"lorr-benchmark/{seed}/tasks")
    pairs = [draws.sample(cells, 2) for _ in range(tasks)]
    (folder / "random-32-32-20.map").write_text(
        f"type octile\nheight {SIDE}\nwidth {SIDE}\nmap\n" + "\n".join(rows) + "\n"
    )
    (folder / "agents.txt").write_text(f"{agents}\n" + "".join(f"{r * SIDE + c}\n" for r, c in starts))
    lines = "".join(f"{a[0] * SIDE + a[1]},{b[0] * SIDE + b[1]}\n" for a, b in pairs)
    (folder / "tasks.txt").write_text(f"# version for LoRR 2024\n{tasks}\n{lines}")
    problem = {
        "mapFile": "random-32-32-20.map",
        "agentFile": "agents.txt",
        "teamSize": agents,
        "taskFile": "tasks.txt",
        "numTasksReveal": 1,
        "version": "2024 LoRR",
    }
    path = folder / "random-32-32-20.json"
    path.write_text(json.dumps(problem, indent=4))
    return path


def import_problem(problem: Path, horizon: int, folder: Path) -> tuple[Scenario, float]:
    """The problem as a scenario (through a suite entry), and the seconds it took."""
    suite_path = folder / f"bench-{horizon}.fleetsim.yaml"
    suite_path.write_text(
        "fleetsim: 1\nname: bench\ndefaults:\n  allow_start_conflicts: true\n  stop_on: []\n"
        f"scenarios:\n  - name: lorr\n    lorr: {json.dumps(str(problem.resolve()))}\n    horizon: {horizon}\n"
    )
    start = time.perf_counter()
    suite = load_suite(suite_path)
    scenario = load_scenario(suite.scenarios[0], suite)
    return scenario, time.perf_counter() - start


class TimedDispatcher:
    """The reference dispatcher, with the time spent in it."""

    def __init__(self) -> None:
        self.inner = NearestVehicleDispatcher()
        self.seconds = 0.0

    def dispatch(self, board: OrderBoard, fleet: FleetSnapshot, layout: Layout) -> Any:
        start = time.perf_counter()
        try:
            return self.inner.dispatch(board, fleet, layout)
        finally:
            self.seconds += time.perf_counter() - start


def run_once(scenario: Scenario) -> dict[str, Any]:
    dispatcher = TimedDispatcher()
    result = run_scenario(scenario, ReservingPlanner(), keep_trace=False, dispatcher=dispatcher, planner_timeout=None)
    metrics = result.metrics
    vehicle_steps = len(scenario.vehicles) * result.steps
    counts = result.to_dict()["lorr"]
    harness = metrics.wall_time - metrics.planner_wall_time - dispatcher.seconds
    return {
        "wall": metrics.wall_time,
        "harness_us": harness / vehicle_steps * 1e6,
        "planner_us": metrics.planner_wall_time / vehicle_steps * 1e6,
        "dispatcher_us": dispatcher.seconds / vehicle_steps * 1e6,
        "finished": counts["tasks_finished"],
        "sum_of_cost": counts["sum_of_cost"],
        "makespan": counts["makespan"],
        "alerts": len(result.collisions),
        "steps": result.steps,
        "ended": result.ended,
        "sim_time": result.sim_time,
    }


def report(label: str, imports: list[float], runs: list[dict[str, Any]]) -> None:
    def median(key: str) -> float:
        return float(statistics.median(run[key] for run in runs))

    walls = ", ".join(f"{run['wall']:.1f}" for run in runs)
    endings = ", ".join(f"{run['ended']} at {run['sim_time']:.1f} s" for run in runs)
    spread = f" (runs: {walls} s)" if len(runs) > 1 else ""
    print(
        f"{label}: import {statistics.median(imports):.2f} s (min {min(imports):.2f}); run {median('wall'):.1f} s{spread}, "
        f"{int(median('steps'))} steps; harness {median('harness_us'):.2f} µs per vehicle-step (planner "
        f"{median('planner_us'):.2f}, dispatcher {median('dispatcher_us'):.2f}); tasks finished "
        f"{median('finished'):.0f}, sum of cost {median('sum_of_cost'):.0f}, makespan {median('makespan'):.0f}, "
        f"alerts {median('alerts'):.0f}; ended: {endings}"
    )


def warehouse(repeat: int) -> None:
    vehicle = movingai_vehicle_type(1.0)
    imports, layouts = [], []
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "warehouse.map"
        path.write_text(warehouse_map(140, 500))
        for _ in range(repeat):
            start = time.perf_counter()
            site = load_site_map(path, MapOptions())
            imports.append(time.perf_counter() - start)
            start = time.perf_counter()
            build_layout(site.segments, vehicle_radius=vehicle.swept_radius)
            layouts.append(time.perf_counter() - start)
    median = statistics.median(imports)
    print(
        f"warehouse 140 x 500: {len(site.segments)} segments; import median {median:.3f} s "
        f"(min {min(imports):.3f}, max {max(imports):.3f}), layout median {statistics.median(layouts):.3f} s; "
        f"import target < 3 s: {'met' if median < 3 else 'NOT met'}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--problem", type=Path, help="a League problem file (default: generate one of the same shape)")
    parser.add_argument("--horizon", type=int, default=5000, help="timesteps of the long run (default 5000)")
    parser.add_argument("--short", type=int, default=500, help="timesteps of the repeated short runs (default 500)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--agents", type=int, default=100)
    parser.add_argument("--tasks", type=int, default=20000)
    parser.add_argument("--seed", type=int, default=47)
    parser.add_argument("--skip-long", action="store_true", help="leave out the run of --horizon timesteps")
    parser.add_argument("--skip-warehouse", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        problem = args.problem or generate_problem(folder, args.agents, args.tasks, args.seed)
        print(f"problem: {problem if args.problem else 'generated random-32-32-20 shape'} ({problem.name})")
        horizons = [(args.short, args.repeat)] + ([] if args.skip_long else [(args.horizon, 1)])
        for horizon, times in horizons:
            imports, runs = [], []
            for _ in range(times):
                scenario, seconds = import_problem(problem, horizon, folder)
                imports.append(seconds)
                runs.append(run_once(scenario))
            report(f"{len(scenario.vehicles)} robots, {horizon} s", imports, runs)
    if not args.skip_warehouse:
        warehouse(args.repeat)


if __name__ == "__main__":
    main()
