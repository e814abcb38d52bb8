"""One trace format: every line of a real run's trace satisfies the published schema (schemas/trace.schema.json).

The runs are the shipped scenarios with both reference planners (collisions, disturbances, contacts) and
the crossing with planners that are rejected, answer route errors, fail, are interrupted or pause
vehicles, and a trace cut short by a killed run. Lines are validated with jsonschema against the
repository's file (and with ``trace_problem``, which also checks their order); hand-broken lines, and
fields a writer might add, are refused, so the schema is strict enough to notice the writer change.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import signal
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import jsonschema
import pytest
from dispatch_support import FirstIdle, Scripted
from dispatch_support import scenario as order_scenario

from fleetsim import FleetLeg, FleetPlan, Progress, RouteError, Traverse, load_scenario, load_suite, run_scenario
from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.layout.layout import Layout
from fleetsim.orders import Order, Shift, Stop
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning.checks import Rejection, RejectionCode
from fleetsim.planning.plans import Response
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.scenario import Disturbance, Scenario, Task
from fleetsim.sim.interrupt import StopSignals
from fleetsim.sim.trace import TRACE_FORMAT, Trace, complete_lines
from fleetsim.sim.trace_schema import trace_line_problem, trace_problem, trace_schema

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = ROOT / "schemas" / "trace.schema.json"
SUITES = ROOT / "scenario_suites"
PAGE = ROOT / "docs" / "trace.md"


# The repository's file, read by jsonschema itself: independent of how fleetsim loads its packaged copy.
VALIDATOR = jsonschema.Draft202012Validator(json.loads(SCHEMA.read_text(encoding="utf-8")))


def schema_errors(line: str) -> list[str]:
    """Every way one trace line breaks the published schema (empty: it satisfies it)."""
    return [f"{error.json_path}: {error.message}" for error in VALIDATOR.iter_errors(json.loads(line))]


def _schema_event_kinds() -> set[str]:
    return set(trace_schema()["$defs"]["event"]["prefixItems"][0]["enum"])


# -- the runs -------------------------------------------------------------------------------------


def scenario(suite_file: str, name: str, **settings: Any) -> Scenario:
    suite = load_suite(SUITES / suite_file)
    loaded = load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)
    return replace(loaded, settings=replace(loaded.settings, **settings)) if settings else loaded


def crossing(**settings: Any) -> Scenario:
    return scenario("examples.fleetsim.yaml", "crossing", **settings)


def _shipped() -> list[tuple[str, str]]:
    return [
        (path.name, spec.name)
        for path in sorted(SUITES.glob("*.fleetsim.yaml"))
        for spec in load_suite(path).scenarios
        if spec.generate is None
    ]


class Rejected(ReservingPlanner):
    """Vehicle 1's plans end on a segment the map does not have (``unknown-segment`` at that leg), vehicle
    2's have no legs (``empty-plan``, about the plan as a whole): nothing is accepted, the fleet deadlocks."""

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        if task.vehicle_id == 2:
            return [FleetPlan(2, ())]
        unknown = FleetLeg(999, Traverse.FORWARD, Progress.FORWARD, False)
        return [
            FleetPlan(item.vehicle_id, (*item.legs, unknown)) if isinstance(item, FleetPlan) else item
            for item in super().plan_routes(task, fleet, layout)
        ]


class NoWay(ReservingPlanner):
    """Answers route errors only (one in other letters, escaped in the line): the fleet deadlocks."""

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return [RouteError(task.vehicle_id, "kein Weg über die Kreuzung")]


class Fails(ReservingPlanner):
    """Raises in its tenth call: a planner error."""

    calls = 0

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self.calls += 1
        if self.calls == 10:
            raise RuntimeError("lost the map")
        return super().fix_legs(task, fleet, layout)


class SignalAt(ReservingPlanner):
    """Sends this process SIGTERM from inside its 30th call: the run ends interrupted."""

    calls = 0

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        self.calls += 1
        if self.calls == 30:
            os.kill(os.getpid(), signal.SIGTERM)
        return super().fix_legs(task, fleet, layout)


class Pauses(ReservingPlanner):
    """A stepped planner (as the VDA 5050 vehicles are): refuses a message at 0.5 s and pauses vehicle 1
    from 1 s to 2 s."""

    now = 0.0

    def begin_step(self, fleet: FleetSnapshot, layout: Layout) -> Sequence[Rejection]:
        self.now = fleet.time
        if abs(fleet.time - 0.5) < 1e-9:
            return [Rejection(RejectionCode.ORDER_INVALID, 2, None, None, "nodes[1].sequenceId is 3, expected 2")]
        return []

    def paused(self) -> set[int]:
        return {1} if 1.0 - 1e-9 <= self.now < 2.0 - 1e-9 else set()


def _interrupted() -> list[str]:
    with StopSignals() as stop:
        result = run_scenario(crossing(), SignalAt(), stop=stop)
    assert result.ended == "interrupted" and result.trace is not None
    return result.trace.lines


def _disturbed() -> list[str]:
    disturbances = (Disturbance(1, "slow", 2.0, at=1.0, factor=0.5), Disturbance(2, "stop", 1.5, on_segment=6))
    return _lines(replace(crossing(), disturbances=disturbances), ReservingPlanner(), "completed")


def _killed(tmp: Path) -> list[str]:
    path = tmp / "trace.jsonl"
    run_scenario(scenario("examples.fleetsim.yaml", "loop-one-way"), ReservingPlanner(), trace_file=path)
    lines, whole = complete_lines(path.read_text(encoding="ascii")[:-7])  # killed while writing the last line
    assert not whole
    return lines


def _lines(run: Scenario, planner: Any, ended: str | None = None) -> list[str]:
    result = run_scenario(run, planner)
    assert result.trace is not None and result.ended == (ended or result.ended)
    expected = hashlib.sha256("".join(f"{line}\n" for line in result.trace.lines).encode("ascii")).hexdigest()
    assert result.trace_hash == expected  # the hash is over the lines, each with its newline
    return result.trace.lines


class Ignores2(ReservingPlanner):
    """Never plans for vehicle 2: with work, it stands (a stall in a shift)."""

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return [] if task.vehicle_id == 2 else super().plan_routes(task, fleet, layout)


def _orders(stall: bool) -> list[str]:
    """A shift of orders: releases, a refused answer, assignments, dwells, completions (and a stall)."""
    orders = (Order("a", (Stop(7, dwell=2.0), Stop(2)), release=0.0), Order("b", (Stop(2),), release=3.0))
    refused = [False]

    def script(board: OrderBoard) -> Sequence[Assignment]:
        if not refused[0]:
            refused[0] = True
            return [Assignment(9, ["a"])]  # no vehicle 9: refused whole
        return FirstIdle().dispatch(board, None, None)

    shift = Shift(duration=90.0, dispatch_period=1.0, stall_after=5.0)
    run = replace(order_scenario(orders), shift=shift)
    result = run_scenario(run, Ignores2() if stall else ReservingPlanner(), dispatcher=Scripted(script))
    assert result.trace is not None and result.ended == "shift-end"
    return result.trace.lines


RUNS: dict[str, Callable[[Path], list[str]]] = {
    **{
        f"{suite}::{name} {planner.__name__}": (
            lambda _, suite=suite, name=name, planner=planner: _lines(scenario(suite, name), planner())
        )
        for suite, name in _shipped()
        for planner in (BFSPlanner, ReservingPlanner)
    },
    "rejections then deadlock": lambda _: _lines(crossing(stop_on=()), Rejected(), "deadlock"),
    "route errors then deadlock": lambda _: _lines(crossing(), NoWay(), "deadlock"),
    "planner error": lambda _: _lines(crossing(), Fails(), "planner-error"),
    "interrupted": lambda _: _interrupted(),
    "paused and refused": lambda _: _lines(crossing(stop_on=()), Pauses(), "completed"),
    "slowed and stopped on a segment": lambda _: _disturbed(),
    "killed": _killed,
    "a shift of orders": lambda _: _orders(stall=False),
    "a shift with a stall": lambda _: _orders(stall=True),
}


_EVERY_LINE_UP_TO = 5_000
_RAN: dict[str, list[str]] = {}  # run name -> its lines, each run made once per process


def _ran(name: str, tmp: Path) -> list[str]:
    if name not in _RAN:
        _RAN[name] = RUNS[name](tmp)
    return _RAN[name]


def test_the_packaged_schema_is_the_published_one_and_a_valid_schema() -> None:
    packaged = ROOT / "fleetsim" / "schemas" / "trace.schema.json"
    assert packaged.read_bytes() == SCHEMA.read_bytes()
    published = json.loads(SCHEMA.read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(published)
    assert trace_schema() == published
    assert published["$defs"]["header"]["properties"]["format"]["const"] == TRACE_FORMAT
    assert published["$id"].endswith(":" + TRACE_FORMAT.rsplit("/", 1)[1])  # the schema's version is the format's


@pytest.mark.parametrize("name", list(RUNS))
def test_every_line_of_a_real_runs_trace_satisfies_the_schema(name: str, tmp_path: Path) -> None:
    lines = _ran(name, tmp_path)
    assert len(lines) >= 2
    # fleetsim's own reader (jsonschema-rs) checks every line; jsonschema, the second opinion, checks every
    # line of a short run, and of an hour's run (36,000 lines, 12 s of it) the header, each line with
    # new plans or events and every tenth step.
    every = 1 if len(lines) <= _EVERY_LINE_UP_TO else 10
    for number, line in enumerate(lines, start=1):
        if number % every == 1 % every or not line.endswith(",[],[]]"):
            assert schema_errors(line) == [], f"line {number}: {line[:200]}"
    assert trace_problem(lines) is None


def test_the_runs_write_every_kind_of_line_the_schema_describes(tmp_path_factory: pytest.TempPathFactory) -> None:
    tmp = tmp_path_factory.mktemp("runs")
    runs = {name: _ran(name, tmp) for name in RUNS}
    headers = [json.loads(lines[0]) for lines in runs.values()]
    events = [event for lines in runs.values() for line in lines[1:] for event in json.loads(line)[3]]
    assert {event[0] for event in events} == _schema_event_kinds()
    assert {event[1] for event in events if event[0] == "reject"} >= {"unknown-segment", "empty-plan", "order-invalid"}
    assert {type(event[3]) for event in events if event[0] == "reject"} == {int, type(None)}  # a leg, the whole plan
    assert {event[2] for event in events if event[0] in ("disturb", "resume")} == {"stop", "slow", "pause"}
    assert ["route-error", 1, "kein Weg über die Kreuzung"] in events
    assert "kein Weg \\u00fcber" in "".join(runs["route errors then deadlock"])  # ASCII: escaped as json escapes
    assert ["interrupted", "SIGTERM"] in events and ["planner-error", 2] in events
    assert any("disturbances" not in header for header in headers)
    schedules = [entry for header in headers for entry in header.get("disturbances", [])]
    assert {(entry[2] is None, entry[3] is None) for entry in schedules} == {(True, False), (False, True)}
    assert [1, "slow", 1000, None, 2000, 500] in schedules
    vehicles = [record for lines in runs.values() for line in lines[1:] for record in json.loads(line)[1]]
    assert {record[3] for record in vehicles} == {"f", "r"} and {record[2] for record in vehicles} == {"f", "b"}


def test_every_event_kind_the_simulator_writes_is_in_the_schema() -> None:
    # An event kind a writer adds without the schema would be caught by the runs only if one of them
    # happened to write it: the writers' source names every kind.
    written = set()
    for path in (ROOT / "fleetsim").rglob("*.py"):
        written |= set(re.findall(r'events\.append\(\s*\[\s*"([\w-]+)"', path.read_text(encoding="utf-8")))
    assert written == _schema_event_kinds()


def test_the_schema_lists_every_rejection_code() -> None:
    codes = trace_schema()["$defs"]["event-reject"]["prefixItems"][1]["enum"]
    assert codes == [code.value for code in RejectionCode]


# -- what the schema refuses ----------------------------------------------------------------------------

HEADER = '{"format":"fleetsim-trace/1","planning_period_steps":1,"tasks":2,"time_step_us":100000,"vehicles":[1,2]}'
STEP = '[1,[[1,1,"f","f",-7990,0,0,100]],[[1,[[1,"f","f",1,null],[4,"f","f",0,1]]]],[["alert",2,[1],[2]]]]'


def _changed(line: str, change: Callable[[Any], None]) -> Any:
    document = json.loads(line)
    change(document)
    return document


@pytest.mark.parametrize(
    ("line", "change", "problem"),
    [
        (HEADER, lambda h: h.pop("time_step_us"), "the line: 'time_step_us' is a required property"),
        (HEADER, lambda h: h.update(seed=7), "the line: Additional properties are not allowed ('seed' was unexpected)"),
        (HEADER, lambda h: h.update(format="fleetsim-trace/2"), "format: 'fleetsim-trace/1' was expected"),
        (HEADER, lambda h: h.update(time_step_us=0.1), "time_step_us: 0.1 is not of type 'integer'"),
        (
            HEADER,
            lambda h: h.update(disturbances=[[1, "stop", 100, None, 500, 250]]),
            "disturbances[0][5]: 0 was expected",
        ),
        (
            HEADER,
            lambda h: h.update(disturbances=[[1, "halt", 100, None, 500, 0]]),
            "disturbances[0][1]: 'halt' is not one of",
        ),
        (STEP, lambda s: s[1][0].pop(), "vehicles[0]: [1, 1, 'f', 'f', -7990, 0, 0] is too short"),
        (STEP, lambda s: s[1][0].append(0), "vehicles[0]: Expected at most 8 items but found 1 extra"),
        (STEP, lambda s: s[1][0].__setitem__(4, -7.99), "vehicles[0][4]: -7.99 is not of type 'integer'"),
        (STEP, lambda s: s[1][0].__setitem__(2, "forward"), "vehicles[0][2]: 'forward' is not one of ['f', 'b']"),
        (STEP, lambda s: s[1][0].__setitem__(7, -5), "vehicles[0][7]: -5 is less than the minimum of 0"),
        (STEP, lambda s: s[2][0][1][0].__setitem__(3, True), "plans[0][1][0][3]: True is not one of [0, 1]"),
        (STEP, lambda s: s[2][0].__setitem__(1, []), "plans[0][1]: [] should be non-empty"),
        (STEP, lambda s: s[3].append(["crash", 1, 2]), "events[1][0]: 'crash' is not one of ['complete', 'reject'"),
        (STEP, lambda s: s[3].append(["complete"]), "events[1]: ['complete'] is too short"),
        (STEP, lambda s: s[3].append(["complete", 1, 2]), "events[1]: Expected at most 2 items but found 1 extra"),
        (
            STEP,
            lambda s: s[3].append(["reject", "wrong-way", 1, "2"]),
            "events[1][3]: '2' is not of type 'integer', 'null'",
        ),
        (STEP, lambda s: s[3].append(["reject", "bad-plan", 1, 2]), "events[1][1]: 'bad-plan' is not one of"),
        (
            STEP,
            lambda s: s[3].append(["disturb", 1, "nap"]),
            "events[1][2]: 'nap' is not one of ['stop', 'slow', 'pause']",
        ),
        (STEP, lambda s: s.append([]), "the line: Expected at most 4 items but found 1 extra"),
        (STEP, lambda s: s.pop(), "the line: [1, [[1, 1, 'f', 'f', -7990, 0, 0, 100]]"),
    ],
)
def test_a_broken_line_is_refused_naming_the_element(line: str, change: Callable[[Any], None], problem: str) -> None:
    assert trace_line_problem(json.loads(line)) is None  # narrowly: the line as written is valid
    broken = _changed(line, change)
    assert schema_errors(json.dumps(broken)) != []
    said = trace_line_problem(broken)
    assert said is not None and said.startswith(problem), said


def test_a_field_the_writer_adds_breaks_the_schema() -> None:
    trace = Trace()
    trace.begin({"time_step_us": 100000, "planning_period_steps": 1, "vehicles": [1], "tasks": 1})
    trace.record(0, (), [], [["complete", 1]])
    assert trace_problem(trace.lines) is None
    extra = Trace()
    extra.begin({"time_step_us": 100000, "planning_period_steps": 1, "vehicles": [1], "tasks": 1, "seed": 3})
    assert (
        trace_problem(extra.lines) == "line 1: the line: Additional properties are not allowed ('seed' was unexpected)"
    )
    trace.record(1, (), [], [["complete", 1, 12.5]])
    assert trace_problem(trace.lines) == "line 3: events[0]: Expected at most 2 items but found 1 extra: 12.5"


def test_a_trace_whose_lines_are_out_of_place_is_refused_at_the_line() -> None:
    step0 = STEP.replace("[1,", "[0,", 1)
    assert trace_problem([HEADER, step0, STEP]) is None
    assert trace_problem([]) == "line 1: the trace is empty (a trace begins with its header)"
    assert trace_problem([step0]) == "line 1: the header must be an object"
    assert trace_problem([HEADER, HEADER]) == "line 2: a step must be an array"
    assert trace_problem([HEADER, STEP]) == "line 2: step=1 must be 0 (steps are numbered from 0, one by one)"
    assert trace_problem([HEADER, step0, step0]) == "line 3: step=0 must be 1 (steps are numbered from 0, one by one)"
    said = trace_problem([HEADER, step0[:40]])
    assert said is not None and said.startswith("line 2: not JSON"), said


def test_a_killed_runs_last_cut_line_is_no_trace_line(tmp_path: Path) -> None:
    path = tmp_path / "trace.jsonl"
    run_scenario(crossing(), ReservingPlanner(), trace_file=path)
    text = path.read_text(encoding="ascii")
    cut = text[:-7]
    lines, whole = complete_lines(cut)
    assert not whole and trace_problem(lines) is None
    said = trace_problem(cut.split("\n"))
    assert said is not None and said.startswith(f"line {len(lines) + 1}: not JSON"), said


# -- the documentation --------------------------------------------------------------------------------

_EVENT_ROW = re.compile(r'^\| `(\["[\w-]+"[^`]*\])` \|', re.M)


def test_the_trace_page_documents_every_header_key_and_event_kind() -> None:
    text = PAGE.read_text(encoding="utf-8")
    keys = trace_schema()["$defs"]["header"]["properties"]
    for key in keys:
        assert f"| `{key}` |" in text, key
    rows = _EVENT_ROW.findall(text)
    assert sorted(row.split('"')[1] for row in rows) == sorted(_schema_event_kinds())
    assert "schemas/trace.schema.json" in text and TRACE_FORMAT in text
