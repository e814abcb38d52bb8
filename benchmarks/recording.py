"""What recording a run costs (its trace, MCAP file and view page): time over an unrecorded run, and file size.

    python benchmarks/recording.py [--vehicles 100] [--seconds 60] [--every 1] [--repeat 5] [--seed 1]
                                   [--planner ReservingPlanner|BFSPlanner]

Target (issue 18): on the 100-vehicle benchmark (generated warehouse, ReservingPlanner, 60 s simulated),
recording every step adds at most 25 % (median of 5) to the wall time of an unrecorded run. The recorded
run keeps its trace (the recording is drawn from it) and then writes the MCAP; the unrecorded run keeps
no trace, as a CI run without artifacts does. Each part is timed on its own, one after the other, in each of
``--repeat`` rounds; a round's overhead is (max(run with trace - run without, 0) + writing) / run without
trace (its parts ran seconds apart, so a busy spell on a shared machine weighs on all of them), and the
median of the rounds' overheads is the figure. The parts are printed as median (best). The writing is the
MCAP file and the run's view page (``view.html``), as ``fleetsim run --record`` writes them.

Target (issue 46): the same with a planner that answers fast (``--planner BFSPlanner``, about 15 µs a
call), where the reference planner's own time does not hide the recording's: at most 25 %.
Also printed: the file size per 1000 vehicle-seconds (vehicles x simulated seconds).
"""

from __future__ import annotations

import argparse
import gc
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import write_fleet_scenario

from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning.protocol import Planner
from fleetsim.recording.recorder import record_mcap
from fleetsim.scenario import ScenarioSettings
from fleetsim.sim.loop import run_scenario
from fleetsim.view import write_view_file

PLANNERS: dict[str, type[Planner]] = {"ReservingPlanner": ReservingPlanner, "BFSPlanner": BFSPlanner}

TARGET_OVERHEAD = 0.25


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=100)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--every", type=int, default=1, help="record every N-th step")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--planner", choices=PLANNERS, default="ReservingPlanner")
    args = parser.parse_args()
    make = PLANNERS[args.planner]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write_fleet_scenario(folder / "scenario", args.vehicles, seed=args.seed)
        settings = ScenarioSettings(time_limit=args.seconds, stop_on=())
        scenario = load_scenario_dir(folder / "scenario", settings=settings)
        plain, kept, writing = [], [], []
        size = messages = 0
        for _ in range(args.repeat):
            gc.collect()  # each part starts without the previous part's garbage
            started = time.perf_counter()
            result = run_scenario(scenario, make(), keep_trace=False)
            plain.append(time.perf_counter() - started)
            gc.collect()
            started = time.perf_counter()
            result = run_scenario(scenario, make(), keep_trace=True)
            kept.append(time.perf_counter() - started)
            assert result.trace is not None
            gc.collect()
            started = time.perf_counter()
            recording = record_mcap(folder / "run.mcap", scenario, result.trace.lines, every=args.every)
            write_view_file(folder, scenario, result, {})
            writing.append(time.perf_counter() - started)
            size, messages = recording.size, recording.messages
        median = statistics.median
        base, with_trace, write = median(plain), median(kept), median(writing)
        # Keeping the trace costs what it measurably costs (never less than nothing), writing the rest.
        overhead = median((max(k - p, 0.0) + w) / p for p, k, w in zip(plain, kept, writing, strict=True))
        vehicle_seconds = args.vehicles * result.sim_time
        print(
            f"{args.vehicles} vehicles, {args.planner}, {result.sim_time:.0f} s simulated, every {args.every} step(s); median (best) of {args.repeat} rounds"
        )
        print(f"  run, no trace kept    {base:7.3f} s  ({min(plain):.3f} s)")
        print(f"  run, trace kept       {with_trace:7.3f} s  ({min(kept):.3f} s)")
        print(f"  writing MCAP, page    {write:7.3f} s  ({min(writing):.3f} s)")
        print(f"  overhead              {overhead:7.1%}  median of the rounds  [target <= {TARGET_OVERHEAD:.0%}]")
        print(f"  file                  {size / 1e6:7.2f} MB, {messages} messages")
        print(f"  per 1000 vehicle-s    {size / vehicle_seconds * 1000 / 1e6:7.2f} MB")
        return 0 if overhead <= TARGET_OVERHEAD else 1


if __name__ == "__main__":
    sys.exit(main())
