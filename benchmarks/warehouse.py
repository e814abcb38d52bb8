"""Generated warehouse-like layouts for benchmarks: a lattice of junctions joined by straights.

The lattice is :func:`fleetsim.strategies.geometry.warehouse` (the one Hypothesis draws too): each
junction has a horizontal and a vertical straight crossing it and four 90° curves (10 waypoints, radius
1 m) joining its arms; long straights (*aisles*) join neighbouring junctions: 8 segments per junction.
:func:`write_fleet_scenario` puts a seeded fleet with tasks on such a lattice as a scenario folder;
:func:`write_congestion_scenario` one whose vehicles all work at a dozen stations.
"""

from __future__ import annotations

import math
import random
from pathlib import Path

import networkx as nx

from fleetsim.enums import Traverse
from fleetsim.layout import Layout, build_layout
from fleetsim.layout.segment import Segment
from fleetsim.load.tiled.writer import write_map
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE
from fleetsim.strategies.geometry import warehouse

__all__ = [
    "aisles",
    "spread_starts",
    "warehouse",
    "warehouse_with_at_least",
    "write_congestion_scenario",
    "write_fleet_scenario",
]


def warehouse_with_at_least(segment_count: int) -> list[Segment]:
    return warehouse(max(1, math.ceil(math.sqrt(segment_count / 8))))


def aisles(junctions_per_side: int) -> list[int]:
    """Ids of the long straights of :func:`warehouse`: the 7th and 8th segment of each junction."""
    return [8 * k + offset for k in range(junctions_per_side**2) for offset in (7, 8)]


def _reachable(layout: Layout, segment: int, hops: int) -> set[int]:
    """Segments a vehicle on ``segment`` (either way) reaches within ``hops`` legs, ``segment`` excluded."""
    found: set[int] = set()
    for traverse in Traverse:
        lengths = nx.single_source_shortest_path_length(layout.graph, (segment, traverse), cutoff=hops)
        found.update(s for s, _ in lengths)
    found.discard(segment)
    return found


def spread_starts(layout: Layout, candidates: list[int], vehicles: int, where: str) -> list[int]:
    """The first ``vehicles`` of ``candidates`` (in their order) whose conflict sets do not meet."""
    starts: list[int] = []
    taken: set[int] = set()  # segments conflicting with a chosen start
    for segment in candidates:
        if len(starts) == vehicles:
            break
        if segment not in taken:
            starts.append(segment)
            taken |= layout.conflicts(segment)
    if len(starts) < vehicles:
        msg = f"vehicles={vehicles!r} must fit on non-conflicting {where} ({len(starts)} do)"
        raise ValueError(msg)
    return starts


def write_fleet_scenario(
    folder: Path,
    vehicles: int,
    *,
    seed: int = 1,
    tasks_per_vehicle: tuple[int, int] = (2, 3),
    aisles_per_vehicle: float = 4.0,
    hops: int = 8,
) -> Path:
    """A lattice sized for ``vehicles`` (about ``aisles_per_vehicle`` aisles each) as a scenario folder.

    Vehicles start on distinct aisles whose conflict sets are disjoint (the loader rejects conflicting
    starts). Each gets ``tasks_per_vehicle`` (inclusive range) tasks, each goal an aisle reachable within
    ``hops`` legs of the previous goal (or the start). Vehicles park on their last goal, so last goals
    conflict with no earlier goal and no goal conflicts with an earlier vehicle's last goal: every task
    stays reachable. Goals near the edge can run out of such aisles; then the rule is relaxed for that
    goal. Seeded: the same arguments give the same files. Returns ``folder``.
    """
    side = max(2, math.ceil(math.sqrt(aisles_per_vehicle * vehicles / 2)))
    segments = warehouse(side)
    layout = build_layout(segments, vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius)
    rng = random.Random(seed)
    shuffled = aisles(side)
    rng.shuffle(shuffled)
    starts = spread_starts(layout, shuffled, vehicles, f"aisles of a {side}x{side} lattice")

    aisle_ids = set(shuffled)
    near_parked: set[int] = set()  # conflicts with some vehicle's last goal: no goal may go there
    near_goals: set[int] = set()  # conflicts with any goal so far: no last goal may go there
    rows: list[tuple[int, int]] = []
    for vehicle_id, start in enumerate(starts, start=1):
        here = start
        count = rng.randint(*tasks_per_vehicle)
        for number in range(count):
            reachable = sorted(_reachable(layout, here, hops) & aisle_ids)
            allowed = [s for s in reachable if s not in near_parked]
            if number == count - 1:
                allowed = [s for s in allowed if s not in near_goals] or allowed
            goal = rng.choice(allowed or reachable)
            near_goals |= layout.conflicts(goal)
            rows.append((vehicle_id, goal))
            here = goal
        near_parked |= layout.conflicts(here)

    return _write(folder, segments, starts, rows)


def write_congestion_scenario(
    folder: Path, vehicles: int, *, seed: int = 1, stations: int = 12, trips: tuple[int, int] = (2, 3)
) -> Path:
    """A site where the whole fleet queues at ``stations`` pick and drop aisles, as a scenario folder.

    The lattice has about two aisles per vehicle. Half the stations are picks, half drops, spread over the
    site (their conflict sets do not meet). Each vehicle makes ``trips`` (inclusive range) trips, each a
    pick then a drop station drawn at random, and then parks on an aisle of its own (conflicting with no
    station and no other parking place), so that every task stays reachable. This is the reference
    planner at its slowest: most vehicles stand queued behind others for most of the run. Seeded: the
    same arguments give the same files. Returns ``folder``.
    """
    side = max(3, math.ceil(math.sqrt(2.0 * vehicles / 2)) + 2)
    segments = warehouse(side)
    layout = build_layout(segments, vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius)
    rng = random.Random(seed)
    shuffled = aisles(side)
    rng.shuffle(shuffled)
    chosen = spread_starts(layout, shuffled, stations, f"aisles of a {side}x{side} lattice")
    picks, drops = chosen[: stations // 2], chosen[stations // 2 :]
    near_stations = set().union(*(layout.conflicts(s) for s in chosen))
    free = [s for s in shuffled if s not in near_stations]
    parking = spread_starts(layout, free, 2 * vehicles, "aisles away from the stations")
    starts, parks = parking[:vehicles], parking[vehicles:]
    rows: list[tuple[int, int]] = []
    for vehicle_id in range(1, vehicles + 1):
        for _ in range(rng.randint(*trips)):
            rows += [(vehicle_id, rng.choice(picks)), (vehicle_id, rng.choice(drops))]
        rows.append((vehicle_id, parks[vehicle_id - 1]))
    return _write(folder, segments, starts, rows)


def _write(folder: Path, segments: list[Segment], starts: list[int], rows: list[tuple[int, int]]) -> Path:
    """The map, the vehicles (vehicle ``k`` on ``starts[k - 1]``) and the tasks ``(vehicle, goal)`` as a
    scenario folder; ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    write_map(folder / "map.json", segments)
    vehicle_lines = ["vehicle_id,start_segment_id,segment_orientation"]
    vehicle_lines += [f"{v},{s},forward" for v, s in enumerate(starts, start=1)]
    (folder / "vehicles.csv").write_text("\n".join(vehicle_lines) + "\n", encoding="utf-8")
    task_lines = ["vehicle_id,goal_segment_id", *(f"{v},{g}" for v, g in rows)]
    (folder / "tasks.csv").write_text("\n".join(task_lines) + "\n", encoding="utf-8")
    return folder
