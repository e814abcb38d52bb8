"""The Node.js example planner speaks the planner protocol and answers exactly like ``BFSPlanner``.

Protocol-level, independent of fleetsim's own planner-process runner: each shipped example runs
in-process with a recording ``BFSPlanner``; then ``node examples/planners/node/bfs_planner.js`` gets
the init message and every recorded call as a request (``fleet`` only when the snapshot changed, so the
omission rule is exercised), and each answer must decode to the very response ``BFSPlanner`` gave.
Every message both ways is checked against ``schemas/planner-*.schema.json``.
"""

from __future__ import annotations

import functools
import json
import os
import select
import subprocess
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.exec.protocol import decode_response, encode_fleet, encode_init, encode_task
from fleetsim.layout.layout import Layout
from fleetsim.planners import BFSPlanner
from fleetsim.planning.plans import FleetPlan, ResponseItem, RouteError
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Task, VehicleType
from fleetsim.sim.loop import run_scenario

ROOT = Path(__file__).resolve().parents[2]
SUITE = ROOT / "scenario_suites" / "examples.fleetsim.yaml"
PLANNER_JS = ROOT / "examples" / "planners" / "node" / "bfs_planner.js"
EXAMPLES = [spec.name for spec in load_suite(SUITE).scenarios]
ANSWER_TIMEOUT = 10.0  # seconds for one answer (node starts in well under a second)


@functools.cache
def schema(name: str) -> jsonschema.protocols.Validator:
    document = json.loads((ROOT / "schemas" / f"planner-{name}.schema.json").read_text(encoding="utf-8"))
    return jsonschema.validators.validator_for(document)(document)


def check(name: str, message: dict[str, Any]) -> None:
    error = jsonschema.exceptions.best_match(schema(name).iter_errors(message))
    assert error is None, f"planner-{name} message violates its schema: {error.message} at {list(error.absolute_path)}"


# ---- recording the in-process planner --------------------------------------------------------------


@dataclass(frozen=True)
class Call:
    """One planner call and what ``BFSPlanner`` answered (``raised``: a whole-request RouteError)."""

    method: str
    task: Task
    fleet: FleetSnapshot
    layout: Layout
    response: tuple[ResponseItem, ...] = ()
    raised: RouteError | None = None


def call(planner: BFSPlanner, method: str, task: Task, fleet: FleetSnapshot, layout: Layout) -> Call:
    try:
        response = tuple(getattr(planner, method)(task, fleet, layout))
    except RouteError as error:
        return Call(method, task, fleet, layout, raised=error)
    return Call(method, task, fleet, layout, response)


class RecordingPlanner:
    """``BFSPlanner`` with every call and its response recorded."""

    def __init__(self) -> None:
        self.inner = BFSPlanner()
        self.calls: list[Call] = []

    def _record(self, method: str, task: Task, fleet: FleetSnapshot, layout: Layout) -> Sequence[ResponseItem]:
        made = call(self.inner, method, task, fleet, layout)
        self.calls.append(made)
        if made.raised is not None:
            raise made.raised
        return made.response

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Sequence[ResponseItem]:
        return self._record("plan_routes", task, fleet, layout)

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Sequence[ResponseItem]:
        return self._record("fix_legs", task, fleet, layout)


@functools.cache
def recorded(name: str) -> tuple[Call, ...]:
    suite = load_suite(SUITE)
    scenario = load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)
    planner = RecordingPlanner()
    run_scenario(scenario, planner, planner_timeout=None)
    assert planner.calls, f"{name}: the planner was never called"
    return tuple(planner.calls)


# ---- talking to the node process ---------------------------------------------------------------------


class NodePlanner:
    """``node bfs_planner.js`` behind pipes: one JSON line out, one JSON line back, with a timeout."""

    def __init__(self, executable: str, stderr_path: Path) -> None:
        self._stderr_path = stderr_path
        with stderr_path.open("wb") as stderr:
            self.process = subprocess.Popen(
                [executable, str(PLANNER_JS)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=stderr, cwd=ROOT
            )
        self._buffer = b""

    @property
    def stderr(self) -> str:
        return self._stderr_path.read_text(encoding="utf-8", errors="replace")

    def write_line(self, line: str) -> None:
        assert self.process.stdin is not None
        self.process.stdin.write(line.encode() + b"\n")
        self.process.stdin.flush()

    def read_line(self) -> bytes | None:
        """The next line on stdout, or ``None`` at end of file."""
        assert self.process.stdout is not None
        fd = self.process.stdout.fileno()
        deadline = time.monotonic() + ANSWER_TIMEOUT
        while b"\n" not in self._buffer:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                pytest.fail(f"no answer from node within {ANSWER_TIMEOUT} s; stderr:\n{self.stderr}")
            if select.select([fd], [], [], remaining)[0]:
                chunk = os.read(fd, 1 << 16)
                if not chunk:
                    assert self._buffer == b"", f"node's output ends in an unfinished line: {self._buffer!r}"
                    return None
                self._buffer += chunk
        line, _, self._buffer = self._buffer.partition(b"\n")
        return line

    def ask(self, message: dict[str, Any]) -> dict[str, Any]:
        self.write_line(json.dumps(message))
        line = self.read_line()
        assert line is not None, (
            f"node closed stdout instead of answering; exit {self.process.poll()}; stderr:\n{self.stderr}"
        )
        answer = json.loads(line)
        assert isinstance(answer, dict), answer
        return answer

    def finish(self) -> int:
        """Close stdin; the exit status (after checking nothing more came on stdout)."""
        assert self.process.stdin is not None
        self.process.stdin.close()
        rest = []
        while (line := self.read_line()) is not None:
            rest.append(line)
        assert rest == [], f"node wrote more than one line per message: {rest!r}"
        return self.process.wait(timeout=ANSWER_TIMEOUT)

    def kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        for stream in (self.process.stdin, self.process.stdout):
            if stream is not None and not stream.closed:
                stream.close()


@pytest.fixture
def start_node(node: str, tmp_path: Path):
    started: list[NodePlanner] = []

    def start() -> NodePlanner:
        planner = NodePlanner(node, tmp_path / f"stderr-{len(started)}.txt")
        started.append(planner)
        return planner

    yield start
    for planner in started:
        planner.kill()


def comparable(items: Sequence[ResponseItem]) -> list[tuple[Any, ...]]:
    """Response items as plain tuples: plans field by field, route errors by vehicle and message."""
    return [
        (
            ("plan", item.vehicle_id, item.legs)
            if isinstance(item, FleetPlan)
            else ("route error", item.vehicle_id, item.message)
        )
        for item in items
    ]


def replay(planner: NodePlanner, calls: Sequence[Call]) -> int:
    """Init, then every call as a request, each answer checked; how many requests left ``fleet`` out."""
    init = encode_init(calls[0].layout, calls[0].fleet)
    check("init", init)
    ready = planner.ask(init)
    check("ready", ready)
    assert ready == {
        "type": "ready",
        "rounds": True,
    }  # a 1.2 init: the example asks for rounds (it answers requests too)
    omitted = 0
    previous: FleetSnapshot | None = None
    for number, made in enumerate(calls, start=1):
        assert made.layout is calls[0].layout, "one run, one layout"
        request: dict[str, Any] = {
            "type": made.method,
            "id": number,
            "vehicle": made.task.vehicle_id,
            "task": encode_task(made.task),
        }
        if made.fleet is not previous:
            request["fleet"] = encode_fleet(made.fleet)
            previous = made.fleet
        else:
            omitted += 1
        check("request", request)
        answer = planner.ask(request)
        check("response", answer)
        assert answer["id"] == number
        where = f"request {number} ({made.method}, task {made.task})"
        if made.raised is not None:
            with pytest.raises(RouteError) as raised:
                decode_response(answer)
            assert (raised.value.vehicle_id, raised.value.message) == (None, made.raised.message), where
        else:
            assert comparable(decode_response(answer)) == comparable(made.response), where
    return omitted


# ---- the tests ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", EXAMPLES)
def test_node_answers_every_call_of_a_run_like_bfs_planner(start_node, name: str) -> None:
    calls = recorded(name)
    planner = start_node()
    replay(planner, calls)
    assert planner.finish() == 0, planner.stderr


def test_the_runs_exercise_both_methods_and_the_fleet_omission_rule(start_node) -> None:
    calls = [made for name in EXAMPLES for made in recorded(name)]
    assert {made.method for made in calls} == {"plan_routes", "fix_legs"}
    planner = start_node()
    assert replay(planner, recorded("loop-one-way")) > 0, "no request reused the previous fleet"
    assert planner.finish() == 0, planner.stderr


def vehicle_types() -> dict[str, VehicleType]:
    """Every vehicle type the examples use (an in-place turner and a curve-only tugger)."""
    return {
        state.type.name: state.type
        for name in EXAMPLES
        for made in recorded(name)
        for state in made.fleet.vehicles.values()
    }


def sweep_fleet(name: str, kind: str, *, committed: bool) -> tuple[FleetSnapshot, Layout]:
    """The first fleet of a run with every vehicle made ``kind``; ``committed``: each vehicle's plan replaced
    by its longest BFS route, all legs fixed, so the fixed legs carry a goal mark."""
    first = recorded(name)[0]
    vehicle_type = vehicle_types()[kind]
    vehicles = {vid: state._replace(type=vehicle_type) for vid, state in first.fleet.vehicles.items()}
    fleet = FleetSnapshot(first.fleet.time, vehicles, first.fleet.plans, first.fleet.tasks, first.fleet.routed)
    if committed:
        plans = dict(fleet.plans)
        for vid in sorted(vehicles):
            routes = [
                item
                for goal in sorted(first.layout.segments)
                for item in BFSPlanner().plan_routes(Task(999, vid, goal), fleet, first.layout)
                if isinstance(item, FleetPlan)
            ]
            longest = max(routes, key=lambda plan: len(plan.legs))
            plans[vid] = FleetPlan(vid, tuple(replace(leg, fixed=True) for leg in longest.legs))
        fleet = replace(fleet, plans=plans)
    return fleet, first.layout


@pytest.mark.parametrize("name", EXAMPLES)
@pytest.mark.parametrize("kind", ["agv", "tugger"])
@pytest.mark.parametrize("committed", [False, True], ids=["start", "committed"])
def test_node_routes_every_vehicle_to_every_segment_like_bfs_planner(
    start_node, name: str, kind: str, committed: bool
) -> None:
    """Beyond the runs: one fleet, every vehicle to every goal segment, both methods."""
    fleet, layout = sweep_fleet(name, kind, committed=committed)
    bfs = BFSPlanner()
    calls = [
        call(bfs, method, Task(1000 + goal, vid, goal), fleet, layout)
        for vid in sorted(fleet.vehicles)
        for goal in sorted(layout.segments)
        for method in ("plan_routes", "fix_legs")
    ]
    planner = start_node()
    assert replay(planner, calls) == len(calls) - 1
    assert planner.finish() == 0, planner.stderr


def test_the_goal_sweeps_cover_every_branch_of_plan_routes() -> None:
    """Route errors (a tugger cannot take the mixed layout's corner), goals on fixed legs, marked or not."""
    fleet, layout = sweep_fleet("mixed-shapes", "tugger", committed=False)
    items = [
        item
        for vid in fleet.vehicles
        for goal in layout.segments
        for item in BFSPlanner().plan_routes(Task(1, vid, goal), fleet, layout)
    ]
    assert any(isinstance(item, RouteError) for item in items)
    assert any(isinstance(item, FleetPlan) for item in items)
    fleet, layout = sweep_fleet("loop-one-way", "agv", committed=True)
    assert all(plan.legs[-1].goal_for_task == 999 and len(plan.fixed_legs) > 3 for plan in fleet.plans.values())


def test_closing_stdin_ends_node_with_status_0(start_node) -> None:
    idle = start_node()
    assert idle.finish() == 0, idle.stderr  # before init: nothing to do
    planner = start_node()
    first = recorded("crossing")[0]
    assert planner.ask(encode_init(first.layout, first.fleet)) == {"type": "ready", "rounds": True}
    assert planner.finish() == 0, planner.stderr
    assert planner.stderr == ""


def test_node_reads_messages_however_the_pipe_cuts_them(start_node) -> None:
    """Lines written in pieces (one byte, a character split between two reads), several in one write,
    blank lines between them, and a line many times larger than the example's 64 KiB read buffer: each is
    answered as if written whole."""
    calls = recorded("crossing")
    planner = start_node()
    init = json.dumps(encode_init(calls[0].layout, calls[0].fleet)).encode()
    made = calls[0]
    request = {"type": made.method, "id": 1, "vehicle": made.task.vehicle_id, "task": encode_task(made.task)}
    fleet = encode_fleet(made.fleet)
    # JSON allows white space between tokens, and a string may hold any character: the same request made
    # 300 KiB long, and a route error's text carried through as a 2-byte UTF-8 character.
    padded = json.dumps({**request, "id": 2, "fleet": fleet}).replace(",", "," + " " * 10_000).encode()
    assert len(padded) > 300 * 1024
    assert planner.process.stdin is not None
    pieces = [init[:1], init[1:5000], init[5000:] + b"\n\n   \n", padded[:70_000], padded[70_000:] + b"\n"]
    for piece in pieces:
        planner.process.stdin.write(piece)
        planner.process.stdin.flush()
        time.sleep(0.05)  # each piece its own read
    ready, first = json.loads(planner.read_line() or b"null"), json.loads(planner.read_line() or b"null")
    assert ready == {"type": "ready", "rounds": True}
    assert first["id"] == 2 and comparable(decode_response(first)) == comparable(made.response)
    third = json.dumps({**request, "id": 3, "task": {**request["task"], "note": "\u00e4"}}, ensure_ascii=False).encode()
    split = third.index("\u00e4".encode()) + 1  # between the character's two bytes
    fourth = json.dumps({**request, "id": 4}).encode()
    for piece in (third[:split], third[split:] + b"\n" + fourth + b"\n"):
        planner.process.stdin.write(piece)
        planner.process.stdin.flush()
        time.sleep(0.05)
    answers = [json.loads(planner.read_line() or b"null") for _ in range(2)]
    assert [answer["id"] for answer in answers] == [3, 4]
    assert all(comparable(decode_response(answer)) == comparable(made.response) for answer in answers)
    assert planner.finish() == 0, planner.stderr


MALFORMED = {
    "not JSON": (False, "this is not json"),
    "not an object": (False, "[1, 2, 3]"),
    "unknown type": (True, '{"type": "plan_everything", "id": 1}'),
    "request before init": (
        False,
        '{"type": "fix_legs", "id": 1, "vehicle": 1, "task": {"id": 1, "vehicle_id": 1, '
        '"goal_segment": 1, "goal_progress": null}}',
    ),
    "no fleet ever sent": (
        True,
        '{"type": "fix_legs", "id": 1, "vehicle": 1, "task": {"id": 1, "vehicle_id": 1, '
        '"goal_segment": 1, "goal_progress": null}}',
    ),
    "wrong protocol": (False, '{"type": "init", "protocol": "fleetsim-planner/999", "layout": {}, "scenario": {}}'),
}


@pytest.mark.parametrize("case", MALFORMED)
def test_a_malformed_message_ends_node_with_status_1_and_a_reason(start_node, case: str) -> None:
    after_init, line = MALFORMED[case]
    planner = start_node()
    if after_init:
        first = recorded("crossing")[0]
        assert planner.ask(encode_init(first.layout, first.fleet)) == {"type": "ready", "rounds": True}
    planner.write_line(line)
    assert planner.read_line() is None, "node answered a malformed message"
    assert planner.process.wait(timeout=ANSWER_TIMEOUT) == 1
    assert "bfs_planner.js: " in planner.stderr


def test_node_answers_a_round_up_to_its_first_change_like_bfs_planner(start_node) -> None:
    """Protocol 1.2: a round's calls answered in order against one fleet, stopping after the first change."""
    fleet, layout = sweep_fleet("crossing", "agv", committed=True)
    bfs = BFSPlanner()
    goal = min(layout.segments)
    vehicles = sorted(fleet.vehicles)
    # Every plan is committed, so fix_legs hands it back (nothing to change); plan_routes then changes one.
    calls = [call(bfs, "fix_legs", Task(2000 + vid, vid, goal), fleet, layout) for vid in vehicles]
    calls.append(call(bfs, "plan_routes", Task(3000, vehicles[0], max(layout.segments)), fleet, layout))
    calls.append(call(bfs, "fix_legs", Task(2000 + vehicles[-1], vehicles[-1], goal), fleet, layout))
    assert all(made.response == (fleet.plans[made.task.vehicle_id],) for made in calls[: len(vehicles)])
    assert calls[len(vehicles)].response and calls[len(vehicles)].response != (fleet.plans[vehicles[0]],)
    planner = start_node()
    assert planner.ask(encode_init(layout, fleet)) == {"type": "ready", "rounds": True}
    message = {
        "type": "round",
        "calls": [
            {"type": made.method, "id": number, "vehicle": made.task.vehicle_id, "task": encode_task(made.task)}
            for number, made in enumerate(calls, start=1)
        ],
        "fleet": encode_fleet(fleet),
    }
    check("request", message)
    answer = planner.ask(message)
    check("round-answer", answer)
    for item in answer["answers"]:
        check("response", item)
    assert len(answer["answers"]) == len(answer["durations"]) == len(vehicles) + 1, "it stops after the change"
    assert answer["answers"][:-1] == [{"id": n, "plans": [], "route_errors": []} for n in range(1, len(vehicles) + 1)]
    assert comparable(decode_response(answer["answers"][-1])) == comparable(calls[len(vehicles)].response)
    assert all(seconds >= 0 for seconds in answer["durations"])
    assert planner.finish() == 0, planner.stderr


def test_node_answers_a_protocol_1_1_init_without_rounds(start_node) -> None:
    first = recorded("crossing")[0]
    planner = start_node()
    init = {**encode_init(first.layout, first.fleet), "protocol": "fleetsim-planner/1.1"}
    assert planner.ask(init) == {"type": "ready"}
    assert planner.finish() == 0, planner.stderr
