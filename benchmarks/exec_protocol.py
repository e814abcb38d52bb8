"""What a planner process costs per call: the JSON-lines protocol against the same planner in process.

    python benchmarks/exec_protocol.py [--vehicles 100] [--seconds 20] [--repeat 3] [--seed 1]

Runs a generated warehouse fleet with ReservingPlanner twice: in process, and served over the protocol
(``exec:python -m fleetsim.exec fleetsim.planners:ReservingPlanner``), checking that both runs give the
same trace hash. The protocol's overhead per call is the difference of the time spent inside planner
calls (the guard's measure: for the process, writing the request, the planner's work in the child,
reading and validating the answer) divided by the number of calls. Each figure is the best of
``--repeat`` runs. The first call of each step carries the fleet snapshot (every vehicle moved); the
others refer to it.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import write_fleet_scenario  # noqa: E402

from fleetsim.exec import SubprocessPlanner  # noqa: E402
from fleetsim.load.scenario import load_scenario_dir  # noqa: E402
from fleetsim.planners import ReservingPlanner  # noqa: E402
from fleetsim.scenario import ScenarioSettings  # noqa: E402
from fleetsim.sim.loop import run_scenario  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=100)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        write_fleet_scenario(Path(tmp), args.vehicles, seed=args.seed)
        scenario = load_scenario_dir(Path(tmp), settings=ScenarioSettings(time_limit=args.seconds, stop_on=()))
    command = [sys.executable, "-m", "fleetsim.exec", "fleetsim.planners:ReservingPlanner"]
    direct = [run_scenario(scenario, ReservingPlanner(), keep_trace=False) for _ in range(args.repeat)]
    served = [run_scenario(scenario, SubprocessPlanner(command), keep_trace=False) for _ in range(args.repeat)]
    if {r.trace_hash for r in direct} != {r.trace_hash for r in served}:
        print("the served planner's runs differ from the in-process runs", file=sys.stderr)
        return 1
    calls = direct[0].metrics.planner_calls
    inside = min(r.metrics.planner_wall_time for r in direct)
    outside = min(r.metrics.planner_wall_time for r in served)
    per_call = (outside - inside) / calls
    print(f"{args.vehicles} vehicles, ReservingPlanner, {direct[0].sim_time:.0f} s simulated, {calls} calls, best of {args.repeat}")
    print(f"  in process        planner time {inside:7.3f} s  ({inside / calls * 1e6:6.1f} us per call), run {min(r.metrics.wall_time for r in direct):.3f} s")
    print(f"  planner process   planner time {outside:7.3f} s  ({outside / calls * 1e6:6.1f} us per call), run {min(r.metrics.wall_time for r in served):.3f} s")
    print(f"  protocol overhead {per_call * 1e6:7.1f} us per call (same trace hash: {direct[0].trace_hash[:12]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
