"""Import a generated 140 x 500 MovingAI warehouse map and build its layout.

    python benchmarks/movingai_import.py [--height 140] [--width 500] [--repeat 3] [--cell-size 1]

Target (issue 47): the 140 x 500 map imports in under 3 s. "Import" is reading the ``.map`` file into
segments (``load_site_map``); the layout (connections, joint kinds, conflicts with the MovingAI vehicle
type) is timed beside it, stage by stage, since a scenario needs both. The map is a warehouse in the
style of the League of Robot Runners' ``warehouse-large``: a free border of 3 cells, shelves of 1 x 10
blocked cells in pairs of rows, one-cell aisles between them and a cross aisle every 11 columns.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from fleetsim.enums import ConflictModel
from fleetsim.layout.conflicts import conflict_sets
from fleetsim.layout.connections import find_connections
from fleetsim.layout.layout import build_layout
from fleetsim.load.common.map_options import MapOptions
from fleetsim.load.maps.site_map import load_site_map
from fleetsim.load.movingai.agents import movingai_vehicle_type

BORDER = 3
SHELF = 10


def warehouse_map(height: int, width: int) -> str:
    """The text of a ``height x width`` MovingAI warehouse map (see the module docstring)."""
    rows = []
    for row in range(height):
        cells = []
        for column in range(width):
            inside = BORDER <= row < height - BORDER and BORDER <= column < width - BORDER
            shelf_row = (row - BORDER) % 3 != 2  # two rows of shelves, then an aisle
            shelf_column = (column - BORDER) % (SHELF + 1) != SHELF  # a cross aisle after every shelf
            cells.append("@" if inside and shelf_row and shelf_column else ".")
        rows.append("".join(cells))
    return f"type octile\nheight {height}\nwidth {width}\nmap\n" + "\n".join(rows) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--height", type=int, default=140)
    parser.add_argument("--width", type=int, default=500)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--cell-size", type=float, default=1.0)
    args = parser.parse_args()
    vehicle = movingai_vehicle_type(args.cell_size)
    stages: dict[str, list[float]] = {"import": [], "connections": [], "conflicts": [], "build_layout": []}
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "warehouse.map"
        path.write_text(warehouse_map(args.height, args.width))
        for _ in range(args.repeat):
            start = time.perf_counter()
            site = load_site_map(path, MapOptions(cell_size=args.cell_size))
            stages["import"].append(time.perf_counter() - start)
            start = time.perf_counter()
            find_connections(site.segments, 0.05, 30.0)
            stages["connections"].append(time.perf_counter() - start)
            start = time.perf_counter()
            conflict_sets(site.segments, ConflictModel.SWEPT, vehicle.swept_radius, 0.0, 0.05)
            stages["conflicts"].append(time.perf_counter() - start)
            start = time.perf_counter()
            layout = build_layout(site.segments, vehicle_radius=vehicle.swept_radius)
            stages["build_layout"].append(time.perf_counter() - start)
    free = sum(row.count(".") for row in warehouse_map(args.height, args.width).splitlines()[4:])
    print(
        f"{args.height} x {args.width} map, {free} free cells -> {len(site.segments)} segments, "
        f"{len(layout.connections)} connections"
    )
    for stage, times in stages.items():
        print(f"{stage:>13}: median {statistics.median(times):.3f} s (min {min(times):.3f}, max {max(times):.3f})")
    median = statistics.median(stages["import"])
    print(f"import target < 3 s: {'met' if median < 3 else 'NOT met'}")


if __name__ == "__main__":
    main()
