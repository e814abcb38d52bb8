"""What a planner process costs per call: the JSON-lines protocol against the same planner in process.

    python benchmarks/exec_protocol.py [--vehicles 100] [--seconds 20] [--repeat 3] [--seed 1] [--cpu N]

Runs a generated warehouse fleet with ReservingPlanner in process and served over the protocol
(``exec:python -m fleetsim.exec fleetsim.planners:ReservingPlanner``), and with BFSPlanner in process
and as the Node.js example (``exec:node examples/planners/node/bfs_planner.js``, when node is on PATH),
checking that each pair gives the same trace hash. Each planner process runs twice: answering planning
rounds in one message (protocol 1.2, the clients' default) and one request per call (``--no-rounds``,
``BFS_PLANNER_ROUNDS=0``). The protocol's overhead per call is the difference of the time spent inside
planner calls (the guard's measure: for the process, writing the request, the planner's work in the
child, reading and validating the answer; in rounds, the same for a whole round message, whose calls
then count one each) divided by the number of planner calls, leaving out the time to start the process
(once per run: the interpreter, its imports and the init message; printed apart). The whole run's wall
time per call against the in-process run's is printed too: it also holds the harness's own work outside
planner calls (in rounds, putting each round's calls together). Each figure is
the best of ``--repeat`` runs. The first call of each step carries the fleet snapshot (every vehicle
moved); the others refer to it. A bare pipe round trip (a request-sized line through a child that echoes
it, read the way fleetsim reads a planner) is measured in the same run, and the overhead's ratio to it
printed (the issue's bar: at most 2). In rounds, the planner's own work by its clock (each answer's duration) is
taken out instead, too: what is left is the protocol alone.

Where the two processes of a round trip run decides what it costs: on one CPU (the kernel's choice on a
busy machine) a round trip is two context switches, about 4–5 us on the development machine; on two
(its choice when a CPU is idle) each message also wakes the other CPU, about 12 us. Unpinned, a run gets
whichever the kernel picks; ``--cpu N`` pins this process and every process it starts (Linux) to one CPU
for figures that repeat.
"""

from __future__ import annotations

import argparse
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import write_fleet_scenario

from fleetsim.exec import SubprocessPlanner
from fleetsim.load.scenario import load_scenario_dir
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning.protocol import Planner
from fleetsim.scenario import ScenarioSettings
from fleetsim.sim.loop import run_scenario

NODE_PLANNER = Path(__file__).resolve().parents[1] / "examples" / "planners" / "node" / "bfs_planner.js"


ECHO = "import sys\nfor line in sys.stdin.buffer:\n    sys.stdout.buffer.write(line)\n    sys.stdout.buffer.flush()\n"
# A fix_legs request as fleetsim sends it, and about the size of the commonest answer.
LINE = b'{"type":"fix_legs","id":12345,"vehicle":42,"task":{"id":97,"vehicle_id":42,"goal_segment":1234,"goal_progress":null}}\n'


def bare_round_trip(rounds: int) -> float:
    """Seconds per round trip of a request-sized line through a child that echoes it: the pipe's own
    cost (two writes, two reads, two wake-ups), read the way fleetsim reads a planner process. The clock
    starts after the first round trip, which waits for the child's interpreter to start (about 25 ms,
    2.5 us per round over 10,000 rounds), as the planner process's start is left out of its calls."""
    child = subprocess.Popen([sys.executable, "-c", ECHO], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    assert child.stdin is not None and child.stdout is not None
    write, read = child.stdin.fileno(), child.stdout.fileno()

    def round_trip() -> None:
        os.write(write, LINE)
        buffer = b""
        while not buffer.endswith(b"\n"):
            select.select([read], [], [], None)
            buffer += os.read(read, 1 << 16)

    try:
        round_trip()
        start = time.perf_counter()
        for _ in range(rounds):
            round_trip()
        return (time.perf_counter() - start) / rounds
    finally:
        child.stdin.close()
        child.wait()


class _TimedStart(SubprocessPlanner):
    """A planner process that notes how long starting it took (process, imports, the init message): a cost
    per run, not per call, which the first call would otherwise carry; and, in rounds, the time its calls
    took by its own clock (each answer's duration), which is the planner's own work."""

    started = 0.0
    own = 0.0

    def _start(self, layout: Any, fleet: Any) -> None:
        begin = time.perf_counter()
        super()._start(layout, fleet)
        _TimedStart.started = time.perf_counter() - begin
        _TimedStart.own = 0.0

    def plan_round(self, calls: Any, fleet: Any, layout: Any) -> Any:
        answers = super().plan_round(calls, fleet, layout)
        _TimedStart.own += sum(seconds for _, seconds in answers if seconds is not None)
        return answers


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=100)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--cpu",
        type=int,
        default=None,
        help="run on this CPU only, with every process started (a round trip between processes on one CPU"
        " and on two can differ threefold; unpinned, the kernel chooses per run)",
    )
    args = parser.parse_args()
    if args.cpu is not None:
        os.sched_setaffinity(0, {args.cpu})
    with tempfile.TemporaryDirectory() as tmp:
        write_fleet_scenario(Path(tmp), args.vehicles, seed=args.seed)
        scenario = load_scenario_dir(Path(tmp), settings=ScenarioSettings(time_limit=args.seconds, stop_on=()))
    node = shutil.which("node")
    serve = [sys.executable, "-m", "fleetsim.exec"]
    cases: list[tuple[str, type[Planner], list[list[str]]]] = [
        (
            "ReservingPlanner",
            ReservingPlanner,
            [
                [*serve, "fleetsim.planners:ReservingPlanner"],
                [*serve, "--no-rounds", "fleetsim.planners:ReservingPlanner"],
            ],
        )
    ]
    if node is not None:
        one_by_one = ["env", "BFS_PLANNER_ROUNDS=0", node, str(NODE_PLANNER)]
        cases.append(("BFSPlanner", BFSPlanner, [[node, str(NODE_PLANNER)], one_by_one]))
    pinned = "" if args.cpu is None else f", on CPU {args.cpu} only"
    print(f"{args.vehicles} vehicles, {args.seconds:.0f} s simulated, best of {args.repeat}{pinned}")
    for name, planner, commands in cases:
        direct = [run_scenario(scenario, planner(), keep_trace=False) for _ in range(args.repeat)]
        calls = direct[0].metrics.planner_calls
        inside = min(r.metrics.planner_wall_time for r in direct)
        whole = min(r.metrics.wall_time for r in direct)
        print(f"  {name} in process: {inside / calls * 1e6:6.1f} us per call ({calls} calls)")
        pipe = min(bare_round_trip(calls) for _ in range(args.repeat))
        for command in commands:
            served, starts, rounds, own = [], [], [], []
            for _ in range(args.repeat):
                process = _TimedStart(command)
                served.append(run_scenario(scenario, process, keep_trace=False))
                starts.append(_TimedStart.started)
                rounds.append(process.rounds)
                own.append(_TimedStart.own)
            if {r.trace_hash for r in direct} != {r.trace_hash for r in served}:
                print(f"{name}: the planner process's runs differ from the in-process runs", file=sys.stderr)
                return 1
            if served[0].metrics.planner_calls != calls:
                print(
                    f"{name}: the planner process was called {served[0].metrics.planner_calls} times", file=sys.stderr
                )
                return 1
            outside = min(r.metrics.planner_wall_time - start for r, start in zip(served, starts, strict=True))
            run = min(r.metrics.wall_time - start for r, start in zip(served, starts, strict=True))
            mode = "in rounds" if rounds[0] else "one call at a time"
            words = " ".join(Path(part).name for part in command)
            print(
                f"  {name} as `{words}` ({mode}): {outside / calls * 1e6:6.1f} us per call"
                f" (starting the process: {min(starts):.2f} s, once per run, not counted)"
            )
            overhead = (outside - inside) / calls
            print(
                f"    protocol overhead {overhead * 1e6:6.1f} us per call; whole run {(run - whole) / calls * 1e6:6.1f} us"
                f" per call more than in process; same trace hash {direct[0].trace_hash[:12]}"
            )
            print(
                f"    bare pipe round trip {pipe * 1e6:6.1f} us; overhead / round trip {overhead / pipe:4.2f} [target <= 2]"
            )
            if rounds[0]:
                # The planner's own work by its clock taken out instead of the in-process planner's: what is
                # left is the protocol alone (both sides' encoding and decoding, the pipe, the checks).
                alone = min(
                    r.metrics.planner_wall_time - start - mine
                    for r, start, mine in zip(served, starts, own, strict=True)
                )
                print(
                    f"    the planner's own work {min(own) / calls * 1e6:6.1f} us per call by its clock; the protocol"
                    f" alone {alone / calls * 1e6:6.1f} us per call, {alone / calls / pipe:4.2f} x the round trip"
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
