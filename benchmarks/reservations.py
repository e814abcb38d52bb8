"""Time the reservation check (SPEC §7) for a large fleet on a generated 10,000-segment warehouse.

    python benchmarks/reservations.py [--segments 10000] [--vehicles 1000] [--fixed 5] [--planned 3]
                                      [--calls 200] [--seed 1]

Target (issue): the reservation check for 1000 vehicles with 5 fixed legs each on a 10,000-segment map
takes < 5 ms per call. Each arrangement is timed two ways (best, median and p95 per call; p95 includes
the garbage collector's pauses, which a run sees as well):

- *in a run*: the simulation keeps one :class:`ReservationIndex` and checks once per step; between
  checks ``--churn`` of the vehicles (default 10 %) change plans: a vehicle on its full plan drives past
  its first leg (the plan less that leg), one that did gets its full plan back (as a new route would
  give it). Each change moves one fixed leg's reservations, as driving past a leg or having one more leg
  fixed does in a run. This is the call the target is about.
- *from scratch*: ``find_alerts`` builds every vehicle's reservations anew on each call.

Arrangements:

- *conflict-free*: vehicles are placed one by one where their walks reserve nothing another vehicle
  holds, so no segment alerts (checked) -- the state a passing run is in. The target is judged here.
- *crowded*: every vehicle starts on a different random segment and drives a random walk along the
  layout's connections, so walks overlap and thousands of segments alert. A run stops at its first
  alert by default, so this measures the alert-reporting path at an extreme, for information.

Each plan is ``--fixed`` fixed legs followed by ``--planned`` planned legs along connected segments; the
plans pass the sanity checks of SPEC §7 (checked once, untimed). Everything is seeded: the same arguments
give the same plans.
"""

from __future__ import annotations

import argparse
import random
import statistics
import sys
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TypeVar

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import warehouse_with_at_least

from fleetsim.enums import Progress, Traverse
from fleetsim.layout import Layout, build_layout
from fleetsim.planning import (
    CheckContext,
    CollisionAlert,
    ConflictTable,
    FleetLeg,
    FleetPlan,
    Rejection,
    check_plans,
    find_alerts,
)
from fleetsim.planning.reservations import ReservationIndex
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE

T = TypeVar("T")
TARGET_MS = 5.0
Drive = tuple[int, Traverse]  # a segment and the way it is driven
Rank = Callable[[int, list[Drive]], "tuple[int, ...] | None"]  # smaller is better; None: may not be taken


def timed(fn: Callable[[], T]) -> tuple[T, float]:
    start = time.perf_counter()
    result = fn()
    return result, time.perf_counter() - start


def walk(layout: Layout, start: Drive, length: int, rng: random.Random, rank: Rank) -> list[Drive] | None:
    """``length`` connected drives from ``start``, each picked at random among the best-ranked successors.

    ``rank`` returns ``None`` for a successor that may not be taken; ``None`` is returned when stuck.
    """
    drives = [start]
    while len(drives) < length:
        segment, traverse = drives[-1]
        ranked = [
            (key, (s, t)) for s, t, _ in layout.successors(segment, traverse) if (key := rank(s, drives)) is not None
        ]
        if not ranked:
            return None
        best = min(key for key, _ in ranked)
        drives.append(rng.choice([option for key, option in ranked if key == best]))
    return drives


def driven(segment: int, drives: list[Drive]) -> bool:
    return any(segment == s for s, _ in drives)


def fresh_first(segment: int, drives: list[Drive]) -> tuple[int, ...]:
    """Turn back (a cusp) onto a segment already driven only when no new one is reachable."""
    return (driven(segment, drives),)


def plan_along(vehicle_id: int, drives: list[Drive], fixed: int) -> FleetPlan:
    legs = tuple(FleetLeg(s, t, Progress.FORWARD, fixed=index < fixed) for index, (s, t) in enumerate(drives))
    return FleetPlan(vehicle_id, legs)


def start_drives(layout: Layout, rng: random.Random) -> list[Drive]:
    segments = sorted(layout.segments)
    rng.shuffle(segments)
    return [(segment, rng.choice([t for t in Traverse if layout.segments[segment].allows(t)])) for segment in segments]


def crowded(layout: Layout, vehicles: int, fixed: int, planned: int, seed: int) -> dict[int, FleetPlan]:
    """Vehicles on distinct random start segments, each on a random walk that ignores the others."""
    rng = random.Random(seed)
    plans: dict[int, FleetPlan] = {}
    for start in start_drives(layout, rng):
        drives = walk(layout, start, fixed + planned, rng, fresh_first)
        if drives is not None:
            plans[len(plans) + 1] = plan_along(len(plans) + 1, drives, fixed)
        if len(plans) == vehicles:
            break
    return plans


def conflict_free(layout: Layout, vehicles: int, fixed: int, planned: int, seed: int) -> dict[int, FleetPlan]:
    """Vehicles placed greedily where their fixed legs touch nothing another vehicle's fixed legs reserve.

    Conflicts are symmetric, so a segment outside every conflict set of the others' fixed legs neither
    is reserved by them nor reserves one of their fixed legs. Walks prefer new segments, then those that
    reserve the fewest segments the walk does not reserve yet, so that many vehicles fit.
    """
    rng = random.Random(seed)
    blocked: set[int] = set()  # every segment the placed vehicles' fixed legs reserve

    def compact(segment: int, drives: list[Drive]) -> tuple[int, ...] | None:
        if segment in blocked:
            return None
        reserved = set().union(*(layout.conflicts(s) for s, _ in drives))
        return driven(segment, drives), len(layout.conflicts(segment) - reserved)

    plans: dict[int, FleetPlan] = {}
    for start in start_drives(layout, rng):
        if start[0] in blocked:
            continue
        head = walk(layout, start, fixed, rng, compact)
        if head is None:
            continue
        tail = walk(layout, head[-1], planned + 1, rng, fresh_first)  # planned legs may go anywhere
        assert tail is not None
        plans[len(plans) + 1] = plan_along(len(plans) + 1, head + tail[1:], fixed)
        blocked.update(*(layout.conflicts(segment) for segment, _ in head))
        if len(plans) == vehicles:
            break
    return plans


def sanity_rejections(layout: Layout, plans: dict[int, FleetPlan]) -> list[Rejection]:
    types = dict.fromkeys(plans, DEFAULT_VEHICLE_TYPE)
    ctx = CheckContext(layout, types, plans, dict.fromkeys(plans, ()))
    return [result for result in check_plans(list(plans.values()), ctx) if isinstance(result, Rejection)]


def percentile(values: Iterable[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(fraction * (len(ordered) - 1)))]


def _report(label: str, times: list[float]) -> float:
    median = statistics.median(times)
    print(
        f"  {'':<14} {label:<13} best {min(times):6.2f} ms   median {median:6.2f} ms   p95 {percentile(times, 0.95):6.2f} ms"
    )
    return median


def measure(
    label: str, plans: dict[int, FleetPlan], table: ConflictTable, calls: int, churn: float, seed: int
) -> tuple[tuple[CollisionAlert, ...], float]:
    """Time reservation checks in a run and from scratch; return the alerts and the in-a-run median (ms)."""
    rng = random.Random(seed)
    index = ReservationIndex(table)
    live = dict(plans)
    index.alerts(live)  # the index a run has built by its first step
    in_run = []
    vehicle_ids = sorted(live)
    alerts: tuple[CollisionAlert, ...] = ()
    for _ in range(calls):
        for vid in rng.sample(vehicle_ids, round(churn * len(vehicle_ids))):
            full = plans[vid]  # driven past its first leg, or back on its full plan
            live[vid] = FleetPlan(vid, full.legs[1:]) if live[vid] is full else full
        alerts, seconds = timed(lambda: index.alerts(live))
        in_run.append(seconds * 1e3)
    scratch = [timed(lambda: find_alerts(plans, table))[1] * 1e3 for _ in range(max(10, calls // 4))]
    involved = len({vid for alert in alerts for vid in alert.vehicles})
    fixed = sum(len(plan.fixed_legs) for plan in plans.values())
    print(f"  {label:<14} {len(plans)} vehicles, {fixed} fixed legs: {len(alerts)} alerts, {involved} vehicles in them")
    median = _report(f"in a run ({churn:.0%} new plans per call)", in_run)
    _report("from scratch", scratch)
    return alerts, median


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--segments", type=int, default=10_000)
    parser.add_argument("--vehicles", type=int, default=1000)
    parser.add_argument("--fixed", type=int, default=5)
    parser.add_argument("--planned", type=int, default=3)
    parser.add_argument("--calls", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--churn", type=float, default=0.10, help="share of vehicles whose plan changes between checks")
    args = parser.parse_args()

    radius = DEFAULT_VEHICLE_TYPE.swept_radius
    layout, build_seconds = timed(lambda: build_layout(warehouse_with_at_least(args.segments), vehicle_radius=radius))
    table, table_seconds = timed(lambda: ConflictTable(layout))
    print(f"map: {len(layout.segments)} segments; vehicle radius {radius:.3f} m")
    print(f"  build_layout {build_seconds:7.3f} s   ConflictTable (once per layout) {table_seconds * 1e3:7.1f} ms")

    arrangements = {
        "crowded": crowded(layout, args.vehicles, args.fixed, args.planned, args.seed),
        "conflict-free": conflict_free(layout, args.vehicles, args.fixed, args.planned, args.seed),
    }
    ok = True
    for label, plans in arrangements.items():
        rejections = sanity_rejections(layout, plans)
        if rejections:
            print(f"  {label}: generated plans fail the checks, first: {rejections[0]}")
            return 1
        if len(plans) < args.vehicles:
            print(f"  {label}: only {len(plans)} of {args.vehicles} vehicles could be placed")
            ok = False
        alerts, median = measure(label, plans, table, args.calls, args.churn, args.seed)
        if label == "conflict-free":
            print(f"  {'':<14} [target: in a run, median < {TARGET_MS:g} ms]")
            ok = ok and median < TARGET_MS
        if label == "conflict-free" and alerts:
            print(f"  conflict-free arrangement alerts, first: {alerts[0]}")
            ok = False
        if label == "crowded" and not alerts:
            print("  crowded arrangement gives no alert: it does not measure the alert path")
            ok = False
    print("targets met" if ok else "TARGETS MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
