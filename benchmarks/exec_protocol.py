"""What a planner process costs per call: the JSON-lines protocol against the same planner in process.

    python benchmarks/exec_protocol.py [--vehicles 100] [--seconds 40] [--warmup 10] [--repeat 5] [--seed 1]
                                       [--cpu N]

Runs a generated warehouse fleet with ReservingPlanner in process and served over the protocol
(``exec:python -m fleetsim.exec fleetsim.planners:ReservingPlanner``), and with BFSPlanner in process
and as the Node.js example (``exec:node examples/planners/node/bfs_planner.js``, when node is on PATH),
checking that each pair gives the same trace hash and call count. Each planner process runs twice:
answering planning rounds in one message (protocol 1.2, the clients' default) and one request per call
(``--no-rounds``, ``BFS_PLANNER_ROUNDS=0``).

The protocol's overhead per call is the time spent inside planner calls (for the process: writing the
request, the planner's work in the child, reading and checking the answer; in rounds, the same for a
whole round message, whose calls then count one each) per call, less the in-process planner's. Calls
are counted from ``--warmup`` simulated seconds on, in both runs: the first calls of a run also pay for
filling caches and, in a process with a JIT (Node.js), for its first compilations, a cost per run like
starting the process (the interpreter, its imports and the init message), and both are printed apart.
Each figure is the median of ``--repeat`` runs. A bare pipe round trip (a request-sized line through a
child that echoes it, read the way fleetsim reads a planner) is measured in the same run, and the
overhead's ratio to it printed (the issue's bar: at most 2). In rounds, the planner's own work by its
clock (each answer's duration) is taken out instead, too: what is left is the protocol alone.

Where the two processes of a round trip run decides what it costs: on one CPU (the kernel's choice on a
busy machine) a round trip is two context switches, about 4-5 us on the development machine, and the
two processes share that CPU's caches; on two (its choice when a CPU is idle) each message also wakes
the other CPU, about 12 us. Unpinned, a run gets whichever the kernel picks; ``--cpu N`` pins this
process and every process it starts (Linux) to one CPU for figures that repeat.
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
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from statistics import median

sys.path.insert(0, str(Path(__file__).parent))

from warehouse import write_fleet_scenario

from fleetsim.exec import SubprocessPlanner
from fleetsim.layout.layout import Layout
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning.plans import Response, RouteError
from fleetsim.planning.protocol import Planner, RoundCall
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import ScenarioSettings, Task, VehicleType
from fleetsim.sim import loop
from fleetsim.sim.guard import PlannerGuard
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


class _Guard(PlannerGuard):
    """The run's planner guard, kept where the benchmark can read it: its time inside planner calls and
    its call count are the measure (the same for a planner in process and a planner process)."""

    current: _Guard | None = None

    def __init__(self, timeout: float | None = 10.0) -> None:
        super().__init__(timeout)
        _Guard.current = self


class _Clock:
    """The guard's time inside planner calls and call count at the first call from the simulated time
    ``warmup`` on (earlier calls warm the planner up: caches, and a JIT's first compilations), and, in
    rounds, the answers' durations (the planner's own work by its clock) from then on."""

    def __init__(self, warmup: float) -> None:
        self.warmup = warmup
        self.at_warmup: tuple[float, int] | None = None
        self.answers: list[Sequence[tuple[object, float | None]]] = []

    def passed(self, fleet: FleetSnapshot) -> bool:
        """Note the guard's figures the first time a call comes at or after the warm-up (the guard has not
        counted that call yet); whether the warm-up is over."""
        if self.at_warmup is None and fleet.time >= self.warmup:
            guard = _Guard.current
            assert guard is not None
            self.at_warmup = (guard.wall_time, guard.calls)
        return self.at_warmup is not None

    def steady(self, total: float, calls: int) -> tuple[float, int, float]:
        """Seconds inside the calls after the warm-up, their number, and their own seconds."""
        assert self.at_warmup is not None, "no call after the warm-up"
        own = sum(seconds for answers in self.answers for _, seconds in answers if seconds is not None)
        return total - self.at_warmup[0], calls - self.at_warmup[1], own


def _in_process(planner: type[Planner], clock: _Clock) -> Planner:
    """``planner()``, its calls noting the warm-up's end on ``clock``."""

    class Marked(planner):  # type: ignore[valid-type,misc]
        def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
            clock.passed(fleet)
            response: Response = super().plan_routes(task, fleet, layout)
            return response

        def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
            clock.passed(fleet)
            response: Response = super().fix_legs(task, fleet, layout)
            return response

    made: Planner = Marked()
    return made


class _Served(SubprocessPlanner):
    """A planner process whose calls note the warm-up's end on ``clock`` (and keep a round's answers for
    their durations), and which notes how long starting it took (process, imports, the init message): a
    cost per run, not per call."""

    def __init__(self, command: list[str], clock: _Clock) -> None:
        super().__init__(command)
        self.clock = clock
        self.started = 0.0

    def _start(self, layout: Layout, vehicles: Mapping[int, VehicleType], tasks: Iterable[Task]) -> None:
        begin = time.perf_counter()
        super()._start(layout, vehicles, tasks)
        self.started = time.perf_counter() - begin

    def plan_round(
        self, calls: Sequence[RoundCall], fleet: FleetSnapshot, layout: Layout
    ) -> list[tuple[Response | RouteError, float | None]]:
        counted = self.clock.passed(fleet)
        answers = super().plan_round(calls, fleet, layout)
        if counted:
            self.clock.answers.append(answers)
        return answers

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self.clock.passed(fleet)
        return super().plan_routes(task, fleet, layout)

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self.clock.passed(fleet)
        return super().fix_legs(task, fleet, layout)


def _median(runs: list[tuple[float, int, float]]) -> tuple[float, float]:
    """The medians over runs of (seconds inside calls, calls, own seconds): seconds per call, own per call."""
    return median(seconds / calls for seconds, calls, _ in runs), median(own / calls for _, calls, own in runs)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=100)
    parser.add_argument("--seconds", type=float, default=40.0)
    parser.add_argument(
        "--warmup",
        type=float,
        default=10.0,
        help="simulated seconds at the start of a run whose calls are not counted per call (caches, a JIT's"
        " first compilations); what they cost more than the steady rate is printed apart",
    )
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--cpu",
        type=int,
        default=None,
        help="run on this CPU only, with every process started (a round trip between processes on one CPU"
        " and on two can differ threefold; unpinned, the kernel chooses per run)",
    )
    args = parser.parse_args()
    if not 0 <= args.warmup < args.seconds:
        parser.error(f"--warmup {args.warmup:g} must be at least 0 and less than --seconds {args.seconds:g}")
    if args.cpu is not None:
        os.sched_setaffinity(0, {args.cpu})
    loop.PlannerGuard = _Guard  # type: ignore[attr-defined]  # the runs' guards, kept for their figures
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
    print(
        f"{args.vehicles} vehicles, {args.seconds:g} s simulated, calls from {args.warmup:g} s on counted per call,"
        f" medians of {args.repeat} runs{pinned}"
    )
    for name, planner, commands in cases:
        direct, hashes = [], set()
        for _ in range(args.repeat):
            clock = _Clock(args.warmup)
            result = run_scenario(scenario, _in_process(planner, clock), keep_trace=False)
            metrics = result.metrics
            steady = clock.steady(metrics.planner_wall_time, metrics.planner_calls)
            direct.append((*steady, metrics.planner_wall_time, metrics.planner_calls))
            hashes.add(result.trace_hash)
        inside, _ = _median([run[:3] for run in direct])
        whole_inside = median(run[3] / run[4] for run in direct)
        calls = direct[0][4]
        print(f"  {name} in process: {inside * 1e6:6.1f} us per call ({direct[0][1]} of {calls} calls counted)")
        pipe = median(bare_round_trip(calls) for _ in range(args.repeat))
        for command in commands:
            served, starts, whole, rounds = [], [], [], False
            for _ in range(args.repeat):
                clock = _Clock(args.warmup)
                process = _Served(command, clock)
                result = run_scenario(scenario, process, keep_trace=False)
                # A process starts in its first call: counted when the warm-up is 0, and then taken out.
                started = process.started if args.warmup == 0 else 0.0
                served.append(clock.steady(result.metrics.planner_wall_time - started, result.metrics.planner_calls))
                starts.append(process.started)
                whole.append((result.metrics.planner_wall_time - process.started) / result.metrics.planner_calls)
                rounds = bool(process.rounds)
                if result.trace_hash not in hashes or result.metrics.planner_calls != calls:
                    print(f"{name}: the planner process's runs differ from the in-process runs", file=sys.stderr)
                    return 1
            per_call, own = _median(served)
            mode = "in rounds" if rounds else "one call at a time"
            words = " ".join(Path(part).name for part in command)
            overhead = per_call - inside
            # What the whole run's calls cost over the in-process run's beyond the steady overhead: the warm-up
            # (an estimate from the medians of each; a few ms either way is noise).
            warmup = ((median(whole) - whole_inside) - overhead) * calls
            print(
                f"  {name} as `{words}` ({mode}): {per_call * 1e6:6.1f} us per call; once per run, not counted:"
                f" starting the process {median(starts):.2f} s, the first {args.warmup:g} s of calls {warmup * 1e3:+.0f} ms"
                " over the steady rate"
            )
            print(
                f"    protocol overhead {overhead * 1e6:6.1f} us per call; bare pipe round trip {pipe * 1e6:4.1f} us;"
                f" overhead / round trip {overhead / pipe:4.2f} [target <= 2]; same trace hash {next(iter(hashes))[:12]}"
            )
            if rounds:
                # The planner's own work by its clock taken out instead of the in-process planner's: what is
                # left is the protocol alone (both sides' encoding and decoding, the pipe, the checks).
                alone = per_call - own
                print(
                    f"    the planner's own work {own * 1e6:6.1f} us per call by its clock; the protocol"
                    f" alone {alone * 1e6:6.1f} us per call, {alone / pipe:4.2f} x the round trip"
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
