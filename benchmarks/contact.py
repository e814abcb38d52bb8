"""What the contact check costs the harness: contact off and on, side by side, at 100 to 10,000 vehicles.

    python benchmarks/contact.py [--sizes 100,1000,10000] [--seconds 20] [--repeat 3] [--planner BFSPlanner]

As ``scale.py``: each size gets a generated warehouse sized to the fleet (``warehouse.write_fleet_scenario``,
seeded), written once in a process of its own, and each repeat loads it in a fresh process. Within that
process the scenario runs twice, once with the contact check on (``checks.contact``, the default) and
once off, in alternating order from one repeat to the next (so that neither always runs first, on a
warmer or a colder machine). The planner is a cheap one (BFSPlanner by default) so that the harness's
own cost is what is measured; the harness's time is the run's wall time less the time inside planner
calls, per vehicle-step. Contacts, clearance and near misses enter no hash, so both runs of a repeat,
and every repeat of a size, must give the same trace hash (the script fails otherwise).

Per size: harness µs per vehicle-step with the check off and on (medians of the repeats), the added
cost (the median of the repeats' paired ratios on / off - 1: the two runs of a repeat share the machine's
moment), the on figure's ratio to the first size's (flatness), and the run's clearance, contacts and near
misses as a sanity line.

Targets (issue 34): contact and clearance add at most 15 % to the harness cost per vehicle-step at 100
and at 1,000 vehicles, and the per-vehicle cost with the check on stays flat (at 1,000 vehicles <= 1.2x
the figure at 100, at 10,000 <= 1.5x, as ``scale.py``'s). The script exits 1 when a target is missed or
hashes differ, 2 when a run fails.

``--seconds`` defaults to 20 rather than ``scale.py``'s 60: at 10,000 vehicles a 60 s run takes about
100 s here (0.6x realtime), so a repeat (loading, then two runs) would take some four minutes and the
default three repeats a quarter of an hour; 20 s simulated is past the fleet's start-up at every size.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import json
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import write_fleet_scenario

PLANNERS = ("BFSPlanner", "GreedyPlanner", "ReservingPlanner")
TARGET_ADDED = 0.15  # at 100 and 1,000 vehicles
TARGET_FLAT = {1000: 1.2, 10000: 1.5}  # harness µs/vs with contact on, against the first size's


def write_one(vehicles: int, folder: Path) -> float:
    """Generate and write the scenario of a fleet of ``vehicles``; the seconds it took."""
    start = time.perf_counter()
    write_fleet_scenario(folder, vehicles, seed=1)
    return time.perf_counter() - start


def run_pair(vehicles: int, folder: Path, seconds: float, planner_name: str, contact_first: bool) -> dict[str, Any]:
    """Load one fleet's scenario in this process and run it with the contact check on and off, in the
    order given; both runs' figures."""
    from fleetsim import planners
    from fleetsim.load.suites.scenario import load_scenario_dir
    from fleetsim.scenario import ScenarioSettings
    from fleetsim.sim.loop import run_scenario

    on = load_scenario_dir(folder, settings=ScenarioSettings(time_limit=seconds, stop_on=()))
    assert on.settings.checks.contact, "the contact check is on by default"
    settings = on.settings
    off = dataclasses.replace(
        on, settings=dataclasses.replace(settings, checks=dataclasses.replace(settings.checks, contact=False))
    )
    figures: dict[str, Any] = {"vehicles": vehicles, "contact_first": contact_first}
    for name, scenario in (("on", on), ("off", off)) if contact_first else (("off", off), ("on", on)):
        gc.collect()  # each run starts without the previous run's garbage
        result = run_scenario(scenario, getattr(planners, planner_name)(), keep_trace=False)
        metrics = result.metrics
        report = result.contact
        figures[name] = {
            "hash": result.trace_hash,
            "harness_us_per_vs": (metrics.wall_time - metrics.planner_wall_time) / (vehicles * result.steps) * 1e6,
            "planner_us_per_call": metrics.planner_wall_time / max(metrics.planner_calls, 1) * 1e6,
            "clearance": None if report is None or report.clearance is None else report.clearance.distance,
            "contacts": None if report is None else len(report.contacts),
            "near_misses": None if report is None else len(report.near_misses),
            "tasks": f"{result.tasks_completed}/{result.tasks_total}",
            "ended": result.ended,
        }
    return figures


def _in_child(*arguments: str) -> Any:
    """This script run with ``arguments`` in a process of its own: the JSON it printed last."""
    command = [sys.executable, __file__, *arguments]
    done = subprocess.run(command, check=False, capture_output=True, text=True)
    if done.returncode != 0:
        msg = f"benchmark child {' '.join(arguments)!r} failed (exit {done.returncode}):\n{done.stderr}"
        raise RuntimeError(msg)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _sizes(text: str) -> list[int]:
    """``--sizes``: comma-separated fleet sizes, each at least 2, in increasing order."""
    try:
        sizes = [int(size) for size in text.split(",") if size.strip()]
    except ValueError:
        msg = f"--sizes={text!r} must be comma-separated whole numbers, e.g. 100,1000,10000"
        raise argparse.ArgumentTypeError(msg) from None
    if not sizes or any(size < 2 for size in sizes):
        msg = f"--sizes={text!r} must name at least one fleet, each of at least 2 vehicles"
        raise argparse.ArgumentTypeError(msg)
    if sizes != sorted(set(sizes)):
        msg = f"--sizes={text!r} must be increasing, without repeats (the first is the flatness yardstick)"
        raise argparse.ArgumentTypeError(msg)
    return sizes


def _positive(kind: type[int] | type[float], option: str) -> Any:
    def parse(text: str) -> int | float:
        try:
            value = kind(text)
        except ValueError:
            value = None
        if value is None or not value > 0:
            msg = f"{option}={text!r} must be a positive {'whole number' if kind is int else 'number'}"
            raise argparse.ArgumentTypeError(msg)
        return value

    return parse


def _metres(value: float | None) -> str:
    return "none within reach" if value is None else f"{value:.3f} m"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=_sizes, default=[100, 1000, 10000], help="default: 100,1000,10000")
    parser.add_argument(
        "--seconds", type=_positive(float, "--seconds"), default=20.0, help="simulated seconds per run (default: 20)"
    )
    parser.add_argument("--repeat", type=_positive(int, "--repeat"), default=3, help="processes per size (default: 3)")
    parser.add_argument("--planner", choices=PLANNERS, default="BFSPlanner")
    parser.add_argument("--write", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--contact-first", type=int, choices=(0, 1), help=argparse.SUPPRESS)
    parser.add_argument("--folder", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.write is not None:
        print(json.dumps(write_one(args.write, args.folder)))
        return 0
    if args.child is not None:
        figures = run_pair(args.child, args.folder, args.seconds, args.planner, bool(args.contact_first))
        print(json.dumps(figures))
        return 0
    sizes: list[int] = args.sizes
    runs: dict[int, list[dict[str, Any]]] = {size: [] for size in sizes}
    try:
        with tempfile.TemporaryDirectory() as tmp:
            folders = {size: Path(tmp) / f"fleet-{size}" for size in sizes}
            for size in sizes:
                _in_child("--write", str(size), "--folder", str(folders[size]))
            for repeat in range(args.repeat):  # the sizes in turn, so that each repeat sees the machine's same moments
                for size in sizes:
                    child = ("--child", str(size), "--folder", str(folders[size]), "--seconds", str(args.seconds))
                    order = ("--contact-first", str(1 - repeat % 2))
                    runs[size].append(_in_child(*child, *order, "--planner", args.planner))
    except RuntimeError as error:
        print(error, file=sys.stderr)
        return 2
    print(
        f"{args.planner}, {args.seconds:g} s simulated, median of {args.repeat} processes per size, "
        "each running contact off and on in alternating order"
    )
    print(
        f"{'vehicles':>8} {'harness µs/vs off':>18} {'on':>7} {'added':>7} {'on ratio':>9} {'µs/call':>8}  "
        "clearance, contacts, near misses"
    )
    first: float | None = None
    failed = False
    verdicts: list[str] = []
    for size in sizes:
        rows = runs[size]
        hashes = {row[side]["hash"] for row in rows for side in ("on", "off")}
        if len(hashes) != 1:
            print(
                f"{size} vehicles: the runs' trace hashes differ (contact enters no hash): {sorted(h[:12] for h in hashes)}",
                file=sys.stderr,
            )
            failed = True
        off = statistics.median(row["off"]["harness_us_per_vs"] for row in rows)
        on = statistics.median(row["on"]["harness_us_per_vs"] for row in rows)
        added = statistics.median(
            row["on"]["harness_us_per_vs"] / row["off"]["harness_us_per_vs"] - 1.0 for row in rows
        )
        first = on if first is None else first
        sample = rows[0]["on"]
        calls = statistics.median(row[side]["planner_us_per_call"] for row in rows for side in ("on", "off"))
        print(
            f"{size:>8} {off:>18.2f} {on:>7.2f} {added:>+7.1%} {on / first:>9.2f} {calls:>8.1f}  "
            f"{_metres(sample['clearance'])}, {sample['contacts']} contacts, {sample['near_misses']} near misses "
            f"(tasks {sample['tasks']}, {sample['ended']})"
        )
        if size in (100, 1000):
            met = added <= TARGET_ADDED
            verdicts.append(f"{size}: added {added:+.1%} {'<=' if met else '>'} {TARGET_ADDED:.0%}")
            failed |= not met
        if size in TARGET_FLAT and sizes[0] == 100:
            met = on / first <= TARGET_FLAT[size]
            verdicts.append(f"{size}: on ratio {on / first:.2f} {'<=' if met else '>'} {TARGET_FLAT[size]}")
            failed |= not met
    if verdicts:
        print("targets: " + "; ".join(verdicts))
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
