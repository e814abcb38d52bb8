"""How well the reference planners finish their fleets' work: a fixed set of layouts, measured against a bound.

    python benchmarks/planner_quality.py [--planners ReservingPlanner,BFSPlanner] [--cases lattice-21,...]
                                         [--generated 60] [--seed 1] [--quick]

Per case: tasks completed, makespan, runs that ended in deadlock, collision alerts, rejections, the
waiting share (vehicle-seconds standing still with a task pending, over vehicle-seconds simulated),
planner µs per call, and the *efficiency*: a lower bound on the makespan divided by the makespan reached.
The bound is the longest of the vehicles' solo makespans: each vehicle alone on the map, driving its
tasks' shortest routes (by length) with every leg fixed at once, under the same motion model. A run that
does not complete has no makespan and no efficiency.

Cases (all seeded; the same arguments give the same scenarios and, for a deterministic planner, the same
trace hashes):

- ``lattice-11``, ``lattice-21``, ``lattice-41``: square grids of 2 m two-way straights (11 x 11 with 10
  vehicles, 21 x 21 with 30, 41 x 41 with 100), three tasks each: two goals anywhere, then back to the
  start segment; 600 s limit.
- ``one-way-warehouse``: the generated warehouse lattice (junctions with curves) whose inner aisles are
  one-way, alternating by row and column like city streets; 8 vehicles, three tasks each.
- ``loop-bays``: a two-way ring with a lane shift on each side, 4 vehicles sent round it.
- ``corridor-bay``: a corridor with one passing bay; two vehicles swap ends, twice.
- ``generated``: ``--generated`` scenarios drawn by ``fleetsim.strategies.scenarios`` (every layout kind,
  1-6 vehicles of two types, 1-3 tasks each; derandomised), run one by one; figures are totals (tasks,
  deadlocks, alerts, rejections), means (waiting share, µs per call, efficiency) and the number of runs
  that completed.
"""

from __future__ import annotations

import argparse
import random
import statistics
import sys
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import networkx as nx
from hypothesis import HealthCheck, Phase, given, settings
from lattice import write_lattice_scenario
from warehouse import aisles, spread_starts

from fleetsim.enums import Direction, JointKind, Traverse, TurnCapability
from fleetsim.layout import Layout, build_layout
from fleetsim.layout.segment import Segment
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.load.tiled.writer import write_map
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planners.routing import legs_along, mark_goal_on_fixed, shortest_route, straight_line_estimate
from fleetsim.planning.plans import FleetPlan, Response, RouteError
from fleetsim.planning.protocol import Planner
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Scenario, ScenarioSettings, Task, VehicleType
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult
from fleetsim.strategies import GenerationSpec, scenarios
from fleetsim.strategies.geometry import corridor, loop, warehouse

PLANNERS: dict[str, Callable[[], Planner]] = {"ReservingPlanner": ReservingPlanner, "BFSPlanner": BFSPlanner}
AGV = replace(DEFAULT_VEHICLE_TYPE, name="agv")
TUGGER = VehicleType("tugger", 1.4, 0.7, 0.5, 1.2, 0.4, TurnCapability.CURVE)
LONG = ScenarioSettings(time_limit=600.0, stop_on=())


class SoloPlanner:
    """For the bound: the shortest route by length, every leg fixed at once (alone, nothing is in the way)."""

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        vehicle_id = task.vehicle_id
        fixed = fleet.plans[vehicle_id].fixed_legs
        marked = mark_goal_on_fixed(fixed, task, check_progress=True)
        if marked is not None:
            return [FleetPlan(vehicle_id, marked)]
        last = fixed[-1]
        lengths = {sid: segment.length for sid, segment in layout.segments.items()}

        def cost(segment: int, traverse: Traverse, joint: JointKind) -> float:
            return lengths[segment]

        capability = fleet.vehicles[vehicle_id].type.turn_capability
        estimate = straight_line_estimate(layout, task.goal_segment)
        path = shortest_route(
            layout,
            capability,
            (last.segment, last.traverse, last.progress),
            task.goal_segment,
            task.goal_progress,
            cost,
            estimate,
        )
        if path is None:
            return [RouteError(vehicle_id, f"no route to segment {task.goal_segment}")]
        legs = tuple(replace(leg, fixed=True) for leg in legs_along(path, task, task.goal_progress))
        return [FleetPlan(vehicle_id, (*fixed, *legs))]

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return []


def makespan_bound(scenario: Scenario) -> float | None:
    """The longest solo makespan: each vehicle alone with its tasks (None if one cannot finish alone)."""
    bound = 0.0
    for vehicle in scenario.vehicles:
        tasks = tuple(task for task in scenario.tasks if task.vehicle_id == vehicle.id)
        if not tasks:
            continue
        alone = replace(scenario, vehicles=(vehicle,), tasks=tasks)
        result = run_scenario(alone, SoloPlanner(), keep_trace=False)
        if result.metrics.makespan is None:
            return None
        bound = max(bound, result.metrics.makespan)
    return bound


# -- the cases --------------------------------------------------------------------------------------


def lattice(side: int, vehicles: int) -> Callable[[Path, int], Scenario]:
    def make(folder: Path, seed: int) -> Scenario:
        return load_scenario_dir(write_lattice_scenario(folder, side, vehicles, seed=seed), settings=LONG)

    return make


def one_way_warehouse(folder: Path, seed: int, side: int = 4, vehicles: int = 8) -> Scenario:
    """The warehouse lattice with its inner aisles one-way, alternating like city streets."""
    segments = []
    for segment in warehouse(side):
        k, offset = divmod(segment.id - 1, 8)
        i, j = divmod(k, side)  # junction column, row
        if offset == 6 and i < side - 1:  # an east aisle that leads to another junction
            segment = replace(segment, direction=Direction.FORWARD if j % 2 == 0 else Direction.BACKWARD)
        elif offset == 7 and j < side - 1:  # a north aisle that leads to another junction
            segment = replace(segment, direction=Direction.FORWARD if i % 2 == 0 else Direction.BACKWARD)
        segments.append(segment)
    layout = build_layout(segments, vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius)
    # Goals and starts only where every vehicle can come and go: the largest strongly connected part.
    part = max(nx.strongly_connected_components(layout.graph), key=lambda c: (len(c), -min(s for s, _ in c)))
    both = sorted({sid for sid, _ in part})
    rng = random.Random(seed)
    candidates = [a for a in aisles(side) if a in both]
    rng.shuffle(candidates)
    starts = spread_starts(layout, candidates, vehicles, f"aisles of a {side}x{side} one-way warehouse")
    rows = ["vehicle_id,start_segment_id,segment_orientation"]
    for vehicle_id, start in enumerate(starts, start=1):
        traverse = next(t for t in (Traverse.FORWARD, Traverse.BACKWARD) if (start, t) in part)
        rows.append(f"{vehicle_id},{start},{traverse.value}")
    tasks = ["vehicle_id,goal_segment_id"]
    for vehicle_id, start in enumerate(starts, start=1):
        tasks += [
            f"{vehicle_id},{rng.choice(candidates)}",
            f"{vehicle_id},{rng.choice(candidates)}",
            f"{vehicle_id},{start}",
        ]
    return _write(folder, segments, rows, tasks)


def loop_bays(folder: Path, seed: int) -> Scenario:
    segments = loop(4, shift=(0, 1, 2))
    ids = [s.id for s in segments]
    rng = random.Random(seed)
    layout = build_layout(segments, vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius)
    order = ids[:]
    rng.shuffle(order)
    starts = spread_starts(layout, order, 4, "segments of the ring")
    rows = [
        "vehicle_id,start_segment_id,segment_orientation",
        *(f"{v},{s},forward" for v, s in enumerate(starts, start=1)),
    ]
    tasks = ["vehicle_id,goal_segment_id"]
    for vehicle_id, start in enumerate(starts, start=1):
        tasks += [f"{vehicle_id},{rng.choice(ids)}", f"{vehicle_id},{rng.choice(ids)}", f"{vehicle_id},{start}"]
    return _write(folder, segments, rows, tasks)


def corridor_bay(folder: Path, seed: int) -> Scenario:
    segments = corridor(5, [(2, 1)])
    last = 7  # the corridor's straights are 1..7; the bay is 8..10
    rows = ["vehicle_id,start_segment_id,segment_orientation", "1,1,forward", f"2,{last},backward"]
    tasks = ["vehicle_id,goal_segment_id", f"1,{last}", "2,1", "1,1", f"2,{last}"]
    return _write(folder, segments, rows, tasks)


def _write(folder: Path, segments: Sequence[Segment], vehicles: list[str], tasks: list[str]) -> Scenario:
    folder.mkdir(parents=True, exist_ok=True)
    write_map(folder / "map.json", segments)
    (folder / "vehicles.csv").write_text("\n".join(vehicles) + "\n", encoding="utf-8")
    (folder / "tasks.csv").write_text("\n".join(tasks) + "\n", encoding="utf-8")
    return load_scenario_dir(folder, settings=LONG)


CASES: dict[str, Callable[[Path, int], Scenario]] = {
    "lattice-11": lattice(11, 10),
    "lattice-21": lattice(21, 30),
    "lattice-41": lattice(41, 100),
    "one-way-warehouse": one_way_warehouse,
    "loop-bays": loop_bays,
    "corridor-bay": corridor_bay,
}


def generated_scenarios(count: int) -> list[Scenario]:
    """``count`` scenarios of every layout kind, 1-6 vehicles of two types (derandomised: always the same)."""
    spec = GenerationSpec(layout="any", size=(1, 4), vehicles=(1, 6), tasks=(1, 3), vehicle_types=(AGV, TUGGER))
    found: list[Scenario] = []

    @settings(
        max_examples=count,
        derandomize=True,
        database=None,
        phases=[Phase.generate],
        deadline=None,
        suppress_health_check=list(HealthCheck),
    )
    @given(scenarios(spec))
    def collect(scenario: Scenario) -> None:
        found.append(scenario)

    collect()
    return found


# -- measuring ----------------------------------------------------------------------------------------


@dataclass
class Figures:
    runs: int = 0
    completed_runs: int = 0
    tasks_done: int = 0
    tasks_total: int = 0
    deadlocks: int = 0
    alerts: int = 0
    rejections: int = 0
    makespans: list[float] | None = None
    waiting: list[float] | None = None
    per_call: list[float] | None = None
    efficiency: list[float] | None = None

    def add(self, result: RunResult, bound: float | None, vehicles: int) -> None:
        self.runs += 1
        self.completed_runs += result.ended == "completed"
        self.tasks_done += result.tasks_completed
        self.tasks_total += result.tasks_total
        self.deadlocks += result.ended == "deadlock"
        self.alerts += len(result.collisions)
        self.rejections += len(result.rejections)
        m = result.metrics
        for name, value in (
            ("makespans", m.makespan),
            ("waiting", sum(m.waiting_time.values()) / max(vehicles * result.sim_time, 1e-9)),
            ("per_call", m.planner_wall_time / m.planner_calls * 1e6 if m.planner_calls else None),
            ("efficiency", bound / m.makespan if bound and m.makespan else None),
        ):
            if value is not None:
                values = getattr(self, name) or []
                values.append(value)
                setattr(self, name, values)

    def row(self, case: str, planner: str) -> str:
        def mean(values: list[float] | None, fmt: str) -> str:
            return format(statistics.fmean(values), fmt) if values else "-"

        makespan = (
            "-"
            if not self.makespans
            else (f"{self.makespans[0]:.1f}" if self.runs == 1 else f"{statistics.fmean(self.makespans):.1f}*")
        )
        return (
            f"{case:<18} {planner:<16} {self.completed_runs:>4}/{self.runs:<4} {self.tasks_done:>5}/{self.tasks_total:<5} {makespan:>8} "
            f"{self.deadlocks:>5} {self.alerts:>6} {self.rejections:>5} {mean(self.waiting, '.1%'):>8} {mean(self.per_call, '.1f'):>8} "
            f"{mean(self.efficiency, '.2f'):>6}"
        )


HEADER = (
    f"{'case':<18} {'planner':<16} {'runs done':>9} {'tasks':>11} {'makespan':>8} {'dlock':>5} {'alerts':>6} {'rejs':>5} "
    f"{'waiting':>8} {'µs/call':>8} {'effic.':>6}"
)


def measure(case: str, scenarios_of_case: Sequence[Scenario], planner: str) -> Figures:
    figures = Figures()
    for scenario in scenarios_of_case:
        bound = makespan_bound(scenario)
        result = run_scenario(scenario, PLANNERS[planner](), planner_name=planner, keep_trace=False)
        figures.add(result, bound, len(scenario.vehicles))
    return figures


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--planners", default="ReservingPlanner,BFSPlanner")
    parser.add_argument("--cases", default=",".join([*CASES, "generated"]))
    parser.add_argument("--generated", type=int, default=60, help="how many generated scenarios (default: %(default)s)")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    planners = [p for p in args.planners.split(",") if p]
    unknown = [p for p in planners if p not in PLANNERS] + [
        c for c in args.cases.split(",") if c and c not in CASES and c != "generated"
    ]
    if unknown:
        parser.error(f"unknown planner or case: {', '.join(unknown)}")
    print(HEADER)
    with tempfile.TemporaryDirectory() as tmp:
        for case in (c for c in args.cases.split(",") if c):
            cases = (
                generated_scenarios(args.generated)
                if case == "generated"
                else [CASES[case](Path(tmp) / case, args.seed)]
            )
            for planner in planners:
                print(measure(case, cases, planner).row(case, planner), flush=True)
    print("makespan*: mean over the runs that completed; efficiency: bound / makespan (mean over completed runs)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
