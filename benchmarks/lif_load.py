"""Load a generated LIF site of about 5,000 edges and compute its layout with conflicts.

    python benchmarks/lif_load.py [--edges 5000] [--repeat 5] [--curved-every 3]

Target (issue 19): reading the LIF file, sampling its NURBS trajectories, merging opposite edges and
building the layout with its conflict sets takes < 2 s (the median of the repeats) on a 2-core machine.
The site is a square lattice of nodes 4 m apart; every pair of neighbours is joined by two opposite edges
(one two-way segment), every ``--curved-every``-th of them along a gently bulging rational quadratic
trajectory, the rest straight.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from fleetsim.layout.layout import build_layout
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE

SPACING = 4.0
TYPE = "Bench.AGV"


def _edge(edge_id: str, start: str, end: str, trajectory: dict[str, Any] | None) -> dict[str, Any]:
    prop: dict[str, Any] = {"vehicleTypeId": TYPE, "rotationAllowed": True}
    if trajectory is not None:
        prop["trajectory"] = trajectory
    return {"edgeId": edge_id, "startNodeId": start, "endNodeId": end, "vehicleTypeEdgeProperties": [prop]}


def _bulge(a: tuple[float, float], b: tuple[float, float]) -> dict[str, Any]:
    """A rational quadratic from ``a`` to ``b`` bulging 0.6 m to the left of the straight line."""
    (ax, ay), (bx, by) = a, b
    length = math.dist(a, b)
    mx, my = (ax + bx) / 2 - (by - ay) / length * 0.6, (ay + by) / 2 + (bx - ax) / length * 0.6
    return {
        "degree": 2,
        "knotVector": [0, 0, 0, 1, 1, 1],
        "controlPoints": [{"x": ax, "y": ay}, {"x": mx, "y": my, "weight": 0.8}, {"x": bx, "y": by}],
    }


def site(edges: int, curved_every: int) -> dict[str, Any]:
    """A lattice with at least ``edges`` edges (two per pair of neighbours)."""
    side = 2
    while 2 * 2 * side * (side - 1) < edges:
        side += 1
    position = {f"N{i}_{j}": (i * SPACING, j * SPACING) for i in range(side) for j in range(side)}
    nodes = [
        {"nodeId": name, "nodePosition": {"x": x, "y": y}, "vehicleTypeNodeProperties": [{"vehicleTypeId": TYPE}]}
        for name, (x, y) in position.items()
    ]
    edge_list = []
    count = 0
    for i in range(side):
        for j in range(side):
            for di, dj in ((1, 0), (0, 1)):
                if i + di >= side or j + dj >= side:
                    continue
                a, b = f"N{i}_{j}", f"N{i + di}_{j + dj}"
                curved = count % curved_every == 0
                there = _bulge(position[a], position[b]) if curved else None
                back = None
                if there is not None:
                    back = dict(there, controlPoints=list(reversed(there["controlPoints"])))
                edge_list += [_edge(f"{a}-{b}", a, b, there), _edge(f"{b}-{a}", b, a, back)]
                count += 1
    return {
        "metaInformation": {
            "projectIdentification": "benchmark",
            "creator": "fleetsim",
            "exportTimestamp": "2026-01-01T00:00:00.00Z",
            "lifVersion": "1.0.0",
        },
        "layouts": [{"layoutId": "lattice", "layoutVersion": "1", "nodes": nodes, "edges": edge_list, "stations": []}],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--edges", type=int, default=5000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--curved-every", type=int, default=3)
    args = parser.parse_args()
    document = site(args.edges, args.curved_every)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "site.lif.json"
        path.write_text(json.dumps(document))
        size = path.stat().st_size
        times, load_times = [], []
        for _ in range(args.repeat):
            start = time.perf_counter()
            loaded = load_site_map(path, MapOptions())
            loaded_at = time.perf_counter()
            layout = build_layout(loaded.segments, vehicle_radius=DEFAULT_VEHICLE_TYPE.swept_radius)
            conflicts = sum(len(layout.conflicts(sid)) for sid in layout.segments)
            times.append(time.perf_counter() - start)
            load_times.append(loaded_at - start)
    edges = len(document["layouts"][0]["edges"])
    points = sum(len(segment.waypoints) for segment in loaded.segments)
    print(
        f"{edges} edges ({size / 1e6:.1f} MB) -> {len(layout.segments)} segments, "
        f"{points} waypoints, {len(layout.connections)} connections, {conflicts} conflict pairs (ordered)"
    )
    print(f"load (parse, sample, merge): median {statistics.median(load_times):.3f} s")
    print(
        f"load + layout with conflicts: median {statistics.median(times):.3f} s over {args.repeat} runs "
        f"(min {min(times):.3f}, max {max(times):.3f}); target < 2 s: {'met' if statistics.median(times) < 2 else 'NOT met'}"
    )


if __name__ == "__main__":
    main()
