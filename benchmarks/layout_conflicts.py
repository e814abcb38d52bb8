"""Load a generated 10,000-segment Tiled map and compute its conflicts; compare with all pairs.

    python benchmarks/layout_conflicts.py [--segments 10000] [--repeat 3] [--all-pairs full|sample|skip]

Targets (issue 2): loading the map plus computing its conflict sets takes < 2 s on a 2-core machine, and
the grid broad phase is at least 20x faster than the all-pairs computation. ``--all-pairs full`` runs the
exact all-pairs reference on the whole map in the same run (about ten minutes) and checks that both give
identical conflict sets; ``sample`` (the default) times evenly spread rows of the pair matrix and
extrapolates by pair count, which the reference's cost is proportional to.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import warehouse_with_at_least

from fleetsim.enums import ConflictModel
from fleetsim.layout import Segment, build_layout
from fleetsim.layout.conflicts import SubSegments, all_pairs_conflicts, conflict_sets, polyline_distances
from fleetsim.layout.geometry import ragged_arange
from fleetsim.load.tiled.reader import load_map
from fleetsim.load.tiled.writer import write_map
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE

T = TypeVar("T")
TOLERANCE = 0.05


def timed(fn: Callable[[], T], repeat: int) -> tuple[T, list[float]]:
    times = []
    result: T
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return result, times


def show(label: str, times: list[float]) -> None:
    print(f"  {label:<44} best {min(times):7.3f} s   median {statistics.median(times):7.3f} s")


def sampled_all_pairs_seconds(segments: tuple[Segment, ...], threshold: float, rows: int = 40) -> float:
    subs = SubSegments.of(segments)
    n = len(segments)
    picked = np.linspace(0, n - 2, rows).astype(np.int64)
    later = n - picked - 1
    a = np.repeat(picked, later)
    b = a + 1 + ragged_arange(later)
    start = time.perf_counter()
    polyline_distances(subs, a, b)
    return (time.perf_counter() - start) * (n * (n - 1) / 2) / len(a)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--segments", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--all-pairs", choices=["full", "sample", "skip"], default="sample")
    args = parser.parse_args()

    radius = DEFAULT_VEHICLE_TYPE.swept_radius
    threshold = 2 * radius
    with tempfile.TemporaryDirectory() as tmp:
        map_path = write_map(Path(tmp) / "warehouse.json", warehouse_with_at_least(args.segments))
        size_mb = map_path.stat().st_size / 1e6
        tiled_map, load_times = timed(lambda: load_map(map_path), args.repeat)
    segments = tiled_map.segments
    pieces = sum(len(s.waypoints) - 1 for s in segments)
    print(
        f"map: {len(segments)} segments, {pieces} straight pieces, {size_mb:.1f} MB JSON; vehicle radius {radius:.3f} m"
    )
    conflicts, conflict_times = timed(
        lambda: conflict_sets(segments, ConflictModel.SWEPT, radius, 0.0, TOLERANCE), args.repeat
    )
    layout, build_times = timed(lambda: build_layout(segments, vehicle_radius=radius), args.repeat)
    _, lint_times = timed(layout.lint, 1)
    show("load_map (JSON)", load_times)
    show("conflict sets (grid broad phase + numpy)", conflict_times)
    load_plus_conflicts = [a + b for a, b in zip(load_times, conflict_times, strict=True)]
    show("load + conflicts            [target < 2 s]", load_plus_conflicts)
    show("build_layout (connections, indexes, conflicts)", build_times)
    show("Layout.lint", lint_times)
    sizes = [len(v) for v in conflicts.values()]
    print(f"  conflict set size: mean {np.mean(sizes):.1f}, max {max(sizes)}")

    if args.all_pairs == "skip":
        return 0
    if args.all_pairs == "full":
        reference, ref_times = timed(lambda: all_pairs_conflicts(segments, threshold, touch=TOLERANCE), 1)
        identical = reference == conflicts
        show("all pairs, exact (full run)", ref_times)
        print(f"  all-pairs result identical to the broad phase: {identical}")
        if not identical:
            return 1
        ref_seconds = ref_times[0]
    else:
        ref_seconds = sampled_all_pairs_seconds(segments, threshold)
        print(f"  {'all pairs, exact (extrapolated from 40 rows)':<44} {ref_seconds:7.1f} s")
    speedup = ref_seconds / min(conflict_times)
    print(f"  broad phase speed-up over all pairs: {speedup:.0f}x   [target >= 20x]")
    ok = min(load_plus_conflicts) < 2.0 and speedup >= 20
    print("targets met" if ok else "TARGETS MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
