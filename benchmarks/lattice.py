"""A dense fleet on a grid of short two-way straights; with a greedy planner, the stuck-fleet example.

    python benchmarks/lattice.py [--side 21] [--vehicles 30] [--seed 1] [--planner ReservingPlanner]
                                 [--time-limit 600] [--record DIR]

Each vehicle starts on its own straight (no two starts conflict) and gets three tasks: two goals drawn
from the whole grid, then back to its start segment. The run prints its report (for a failed run, the
why of a deadlock or a timeout); with ``--record DIR`` it writes the artifact folder too (failure
picture, MCAP). ``--planner GreedyPlanner`` is a planner without any coordination: shortest routes, each
next leg fixed as soon as it is free (``fleetsim.planners:GreedyPlanner``). It fills the grid with vehicles waiting for each other and for
vehicles that have finished their work: the README's example of a stuck-fleet report.
"""

from __future__ import annotations

import argparse
import dataclasses
import random
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import spread_starts

from fleetsim.layout import build_layout
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.load.tiled.writer import write_map
from fleetsim.planners import BFSPlanner, GreedyPlanner, ReservingPlanner
from fleetsim.planning.protocol import Planner
from fleetsim.recording.artifacts import write_run_artifacts
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, ScenarioSettings
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.report import failure_report
from fleetsim.strategies.geometry import grid

__all__ = ["write_lattice_scenario"]

PLANNERS: dict[str, type[Planner]] = {
    "BFSPlanner": BFSPlanner,
    "GreedyPlanner": GreedyPlanner,
    "ReservingPlanner": ReservingPlanner,
}


def write_lattice_scenario(folder: Path, side: int = 21, vehicles: int = 30, *, seed: int = 1) -> Path:
    """``vehicles`` on a ``side`` x ``side`` grid of 2 m straights, three tasks each, as a scenario folder."""
    segments = grid(side)
    layout = build_layout(segments, vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius)
    rng = random.Random(seed)
    ids = [segment.id for segment in segments]
    order = ids[:]
    rng.shuffle(order)
    starts = spread_starts(layout, order, vehicles, f"straights of a {side}x{side} grid")
    folder.mkdir(parents=True, exist_ok=True)
    write_map(folder / "map.json", segments)
    rows = [
        "vehicle_id,start_segment_id,segment_orientation",
        *(f"{v},{s},forward" for v, s in enumerate(starts, start=1)),
    ]
    (folder / "vehicles.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    tasks = ["vehicle_id,goal_segment_id"]
    for vehicle_id, start in enumerate(starts, start=1):
        tasks += [f"{vehicle_id},{rng.choice(ids)}", f"{vehicle_id},{rng.choice(ids)}", f"{vehicle_id},{start}"]
    (folder / "tasks.csv").write_text("\n".join(tasks) + "\n", encoding="utf-8")
    return folder


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--side", type=int, default=21)
    parser.add_argument("--vehicles", type=int, default=30)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--planner", choices=sorted(PLANNERS), default="ReservingPlanner")
    parser.add_argument("--time-limit", type=float, default=600.0)
    parser.add_argument("--record", type=Path, help="write the artifact folder (result, picture, MCAP) here")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = write_lattice_scenario(
            Path(tmp) / f"lattice-{args.side}x{args.side}-{args.vehicles}", args.side, args.vehicles, seed=args.seed
        )
        scenario = load_scenario_dir(folder, settings=ScenarioSettings(time_limit=args.time_limit))
        result = run_scenario(scenario, PLANNERS[args.planner](), planner_name=args.planner)
        if args.record is not None:
            paths = write_run_artifacts(args.record, result, scenario=scenario)
            result = dataclasses.replace(result, artifacts=paths)
    print(failure_report(result, heading=f"lattice {args.side}x{args.side}, {args.vehicles} vehicles, {args.planner}"))
    return 0 if result.passed else 1


if __name__ == "__main__":
    sys.exit(main())
