"""Planners in other processes (``exec:``): same outcomes as in process, and every fault contained."""

from __future__ import annotations

import os
import shlex
import sys
import textwrap
import time
from pathlib import Path

import pytest

import fleetsim.sim.loop as loop
from fleetsim import load_scenario, load_suite
from fleetsim.cli import main
from fleetsim.exec import SubprocessPlanner, process
from fleetsim.exec.protocol import LegBook, decode_response
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "scenario_suites" / "examples.fleetsim.yaml"
NAMES = [spec.name for spec in load_suite(EXAMPLES).scenarios]
SERVE = [sys.executable, "-m", "fleetsim.exec"]


def example(name: str) -> Scenario:
    suite = load_suite(EXAMPLES)
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("planner", [ReservingPlanner, BFSPlanner])
@pytest.mark.parametrize("rounds", [True, False], ids=["rounds", "one-call-at-a-time"])
def test_a_python_planner_served_over_the_protocol_gives_the_in_process_run(
    name: str, planner: type, rounds: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    scenario = example(name)
    monkeypatch.setattr(loop._Run, "quiet", False)  # a process is asked about every vehicle: so is this one
    direct = run_scenario(scenario, planner())
    options = [] if rounds else ["--no-rounds"]
    process = SubprocessPlanner([*SERVE, *options, f"fleetsim.planners:{planner.__name__}"])
    served = run_scenario(scenario, process)
    assert process.rounds is rounds
    assert (served.status, served.ended, served.trace_hash) == (direct.status, direct.ended, direct.trace_hash)
    assert served.metrics.planner_calls == direct.metrics.planner_calls


def test_fleetsim_run_takes_an_exec_planner(capsys: pytest.CaptureFixture[str]) -> None:
    command = f"exec:{sys.executable} -m fleetsim.exec fleetsim.planners:ReservingPlanner"
    status = main(["run", str(EXAMPLES), "--planner", command])
    out = capsys.readouterr().out
    assert status == 0 and "4 passed" in out


# -- faults ---------------------------------------------------------------------------------------

# A minimal planner process that changes nothing, with one fault chosen by its first argument, at the
# request numbered by its second; a third, "rounds", makes it answer planning rounds (protocol 1.2).
FAULTY = """
import json, os, sys, time
fault, at = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 1
rounds = sys.argv[3:] == ["rounds"]
print("faulty planner starting", file=sys.stderr, flush=True)
if fault == "no-start":
    print("cannot load my model file", file=sys.stderr)
    sys.exit(2)
plans = {}
for line in sys.stdin:
    message = json.loads(line)
    if message["type"] == "init":
        if fault == "init-exit":
            sys.exit(3)
        if fault == "init-hang":
            time.sleep(600)
        if fault == "init-answer":
            print(json.dumps({"type": "hello"}), flush=True)
            continue
        print(json.dumps({"type": "ready", "rounds": True} if rounds else {"type": "ready"}), flush=True)
        continue
    for plan in message.get("fleet", {}).get("plans", []):
        plans[plan["vehicle_id"]] = plan
    calls = message["calls"] if message["type"] == "round" else [message]
    answers, durations, garbled = [], [], False
    for call in calls:
        n = call["id"]
        answer = {"id": n, "plans": [], "route_errors": []}
        durations.append(0.001)
        if n == at:
            print(f"planner: going wrong on request {n}", file=sys.stderr, flush=True)
            if fault == "crash":
                raise RuntimeError("segfault-ish")
            if fault == "exit":
                sys.exit(0)
            if fault == "hang":
                time.sleep(600)
            garbled = fault == "json"
            if fault == "schema":
                answer["plans"] = [{"vehicle_id": call["vehicle"], "legs": [{"segment": "seven", "traverse": "forward", "progress": "forward", "fixed": True}]}]
            if fault == "id":
                answer["id"] = n + 41
            if fault == "slow":
                durations[-1] = 99.0  # by its own clock, this call took longer than a call may
            if fault == "change-and-go-on":  # a real change, then more answers computed on the old fleet
                plan = plans[call["vehicle"]]
                answer["plans"] = [{**plan, "legs": plan["legs"] + plan["legs"][-1:]}]
        answers.append(answer)
    if garbled:
        print("{not json", flush=True)
    elif message["type"] == "round":
        print(json.dumps({"answers": answers, "durations": durations}), flush=True)
    else:
        print(json.dumps(answers[0]), flush=True)
if fault == "ignore-close":
    print(os.getpid(), file=sys.stderr, flush=True)
    time.sleep(600)  # never exits on its own after stdin closes
"""


@pytest.fixture
def faulty(tmp_path: Path) -> Path:
    script = tmp_path / "faulty_planner.py"
    script.write_text(textwrap.dedent(FAULTY), encoding="utf-8")
    return script


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return _zombie(pid)


def _zombie(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split()[2] == "Z"
    except OSError:
        return True


def _run_faulty(faulty: Path, *args: str, timeout: float = 10.0) -> tuple[object, SubprocessPlanner]:
    planner = SubprocessPlanner([sys.executable, str(faulty), *args], timeout=timeout)
    result = run_scenario(example("crossing"), planner, planner_timeout=timeout)
    return result, planner


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("no-start",), "exited with status 2 before answering the init message"),
        (("crash", "3"), "exited with status 1 before answering request 3 (plan_routes for vehicle 1)"),
        (("exit", "2"), "exited with status 0 before answering request 2"),
        (("json", "1"), "answered request 1 (plan_routes for vehicle 1) with invalid JSON"),
        (("schema", "1"), "with an invalid response: plans[0].legs[0].segment: 'seven' is not of type 'integer'"),
        (("id", "2"), "answered request 2 (plan_routes for vehicle 2) with the answer to request 43"),
    ],
)
def test_each_fault_fails_the_run_with_a_planner_error_and_the_stderr_tail(
    faulty: Path, args: tuple[str, ...], message: str
) -> None:
    result, planner = _run_faulty(faulty, *args)

    assert result.ended == "planner-error"
    [failure] = [f for f in result.failures if f.kind == "planner-error"]
    assert message in failure.message, failure.message
    assert "faulty planner starting" in failure.details.get("traceback", "")
    assert planner._process is None  # closed


# The same faults in round mode: crossing's two vehicles are asked in rounds of two calls (requests 1-2,
# then 3-4, ...); the planner changes nothing, so each round is answered whole.
ROUND = "in one round (plan_routes for vehicle 1, plan_routes for vehicle 2)"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("crash", "3"), f"exited with status 1 before answering requests 3-4 {ROUND}"),
        (("exit", "2"), f"exited with status 0 before answering requests 1-2 {ROUND}"),
        (("json", "1"), f"answered requests 1-2 {ROUND} with invalid JSON"),
        (("schema", "1"), "an invalid answer: answers[0].plans[0].legs[0].segment: 'seven' is not of type 'integer'"),
        (("id", "2"), f"answered requests 1-2 {ROUND} with the answer to request 43 in place of request 2's"),
        (("slow", "4"), "plan_routes() for vehicle 2 did not return within the per-call timeout of 10 s"),
        (("change-and-go-on", "1"), "answers[0] (request 1) changing something before the round's last answer"),
    ],
)
def test_each_fault_in_a_round_fails_the_run_with_a_planner_error_and_the_stderr_tail(
    faulty: Path, args: tuple[str, ...], message: str
) -> None:
    fault, at = args
    result, planner = _run_faulty(faulty, fault, at, "rounds")

    assert planner.rounds is True
    assert result.ended == "planner-error"
    [failure] = [f for f in result.failures if f.kind == "planner-error"]
    assert message in failure.message, failure.message
    assert "faulty planner starting" in failure.details.get("traceback", "")
    assert planner._process is None  # closed


# A planner that fails at its init message is told about the init message, never about the calls of the
# round (or the request) that started it, whether it would have answered rounds or not.
@pytest.mark.parametrize("mode", ["rounds", "one-call-at-a-time"])
@pytest.mark.parametrize(
    ("fault", "message"),
    [
        ("no-start", "exited with status 2 before answering the init message"),
        ("init-exit", "exited with status 3 before answering the init message"),
        ("init-answer", 'answered the init message with {"type": "hello"}, not {"type": "ready"}'),
        ("init-hang", "did not answer the init message within 2 x the per-call timeout of 1 s"),
    ],
)
def test_a_fault_at_init_names_the_init_message(faulty: Path, mode: str, fault: str, message: str) -> None:
    result, planner = _run_faulty(faulty, fault, "1", *(["rounds"] if mode == "rounds" else []), timeout=1.0)

    [failure] = result.failures
    assert failure.kind == "planner-error"
    said = failure.message.removeprefix(f"planner process {shlex.join(planner.command)}: ")
    assert said.startswith(message), failure.message
    assert "round" not in said and "vehicle" not in said
    assert "faulty planner starting" in failure.details.get("traceback", "")


def test_a_fault_after_init_names_the_request_its_kind_and_vehicle(faulty: Path) -> None:
    """Narrowly: a planner that started well is told which request it failed, not the init message."""
    result, _planner = _run_faulty(faulty, "exit", "2")
    [failure] = result.failures
    assert failure.message == (
        f"planner process {sys.executable} {faulty} exit 2: exited with status 0 before answering request 2 "
        "(plan_routes for vehicle 2)"
    )


def test_a_hanging_planner_in_a_round_is_stopped_at_the_rounds_timeout_and_killed(faulty: Path) -> None:
    started = time.monotonic()
    result, _planner = _run_faulty(faulty, "hang", "1", "rounds", timeout=1.0)

    assert time.monotonic() - started < 10.0
    [failure] = result.failures
    assert failure.kind == "planner-error"
    # The run's timer or the process's own, whichever comes first, says the same.
    assert failure.message == (
        f"planner process {sys.executable} {faulty} hang 1 rounds: did not answer requests 1-2 in one round "
        "(plan_routes for vehicle 1, plan_routes for vehicle 2) within 2 x the per-call timeout of 1 s"
    )
    assert "planner: going wrong on request 1" in failure.details.get("traceback", "")


def test_a_hanging_planner_is_stopped_at_the_call_timeout_and_killed(faulty: Path) -> None:
    started = time.monotonic()
    result, _planner = _run_faulty(faulty, "hang", "1", timeout=1.0)

    assert time.monotonic() - started < 8.0
    [failure] = result.failures
    assert failure.kind == "planner-error"
    assert "within the per-call timeout of 1 s" in failure.message
    assert "planner: going wrong on request 1" in failure.details.get("traceback", "")


def test_a_process_that_ignores_the_end_of_its_input_is_killed_with_its_children(faulty: Path, tmp_path: Path) -> None:
    # Run through a shell so the planner is a child of the started process: the whole group must go.
    wrapper = tmp_path / "wrapper.sh"
    wrapper.write_text(f'#!/bin/sh\n"{sys.executable}" "{faulty}" ignore-close 999\n', encoding="utf-8")
    wrapper.chmod(0o755)
    planner = SubprocessPlanner([str(wrapper)], timeout=10.0)
    started = time.monotonic()
    result = run_scenario(example("crossing"), planner, planner_timeout=10.0)
    assert result.ended != "planner-error"
    assert time.monotonic() - started < 30.0
    stderr = planner.diagnostics()
    pids = [int(word) for word in stderr.split() if word.isdigit()]
    assert pids, stderr
    deadline = time.monotonic() + 5.0
    while not _gone(pids[-1]) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _gone(pids[-1]), "the planner process outlived its run"


def test_after_a_faulty_planner_the_next_run_is_normal(faulty: Path) -> None:
    result, _ = _run_faulty(faulty, "crash", "1")
    assert result.ended == "planner-error"
    again = run_scenario(example("crossing"), SubprocessPlanner([*SERVE, "fleetsim.planners:ReservingPlanner"]))
    assert again.passed and again.trace_hash == run_scenario(example("crossing"), ReservingPlanner()).trace_hash


def test_a_program_that_cannot_start_fails_the_run_not_the_harness(tmp_path: Path) -> None:
    not_executable = tmp_path / "planner.sh"
    not_executable.write_text("#!/bin/sh\n", encoding="utf-8")  # no execute permission
    result = run_scenario(example("crossing"), SubprocessPlanner([str(not_executable)]))
    [failure] = result.failures
    assert failure.kind == "planner-error" and "cannot start: Permission denied" in failure.message


def test_close_ends_a_started_process_and_is_idempotent() -> None:
    planner = SubprocessPlanner([*SERVE, "fleetsim.planners:BFSPlanner"])
    scenario = example("crossing")
    run_scenario(scenario, planner)  # closes it
    planner.close()
    with pytest.raises(Exception, match="was closed"):
        planner.fix_legs(scenario.tasks[0], None, scenario.layout)  # type: ignore[arg-type]


def test_the_planner_runs_in_its_own_process_group() -> None:
    # So that closing it can end everything it started, and a Ctrl-C at the terminal reaches fleetsim
    # (which then closes the planner) rather than the planner directly.
    planner = SubprocessPlanner([*SERVE, "fleetsim.planners:BFSPlanner"])
    scenario = example("crossing")
    planner.plan_routes(scenario.tasks[0], _first_snapshot(scenario), scenario.layout)
    assert planner._process is not None
    assert os.getpgid(planner._process.pid) != os.getpgid(0)
    planner.close()


def _first_snapshot(scenario: Scenario) -> object:
    from fleetsim.planning.controller import FleetController

    return FleetController(scenario).snapshot(0.0)


# -- answers recognised by their bytes --------------------------------------------------------------

# A planner process that hands every vehicle asked about its plan in force back, written compactly (as
# fleetsim's clients write) or with the json module's default spaces.
HAND_BACK = """
import json, sys
separators = (",", ":") if sys.argv[1] == "compact" else (", ", ": ")
plans = {}
for line in sys.stdin:
    message = json.loads(line)
    if message["type"] == "init":
        print(json.dumps({"type": "ready"}), flush=True)
        continue
    for plan in message.get("fleet", {}).get("plans", []):
        plans[plan["vehicle_id"]] = plan
    answer = {"id": message["id"], "plans": [plans[message["vehicle"]]], "route_errors": []}
    print(json.dumps(answer, separators=separators), flush=True)
"""


class HandBack:
    """In process, what HAND_BACK does."""

    def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
        return [fleet.plans[task.vehicle_id]]

    fix_legs = plan_routes


@pytest.mark.parametrize(("spelling", "decoded"), [("compact", False), ("spaced", True)])
def test_a_plan_handed_back_unchanged_changes_nothing_however_it_is_spelt(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, spelling: str, decoded: bool
) -> None:
    script = tmp_path / "hand_back.py"
    script.write_text(textwrap.dedent(HAND_BACK), encoding="utf-8")
    decodes: list[object] = []

    def counted(answer: dict[str, object], book: LegBook | None = None) -> object:
        decodes.append(answer)
        return decode_response(answer, book)

    monkeypatch.setattr(process, "decode_response", counted)
    scenario = example("crossing")
    served = run_scenario(scenario, SubprocessPlanner([sys.executable, str(script), spelling]))
    direct = run_scenario(scenario, HandBack())
    assert (served.status, served.ended, served.trace_hash) == (direct.status, direct.ended, direct.trace_hash)
    assert served.metrics.planner_calls == direct.metrics.planner_calls > 1
    # Compact: recognised as the plan in force by its bytes; spelt otherwise: decoded and checked.
    assert bool(decodes) is decoded


# -- the Node.js example ------------------------------------------------------------------------------

NODE_PLANNER = ROOT / "examples" / "planners" / "node" / "bfs_planner.js"


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("rounds", ["1", "0"], ids=["rounds", "one-call-at-a-time"])
def test_the_node_example_planner_gives_the_bfs_planners_runs(
    name: str, node: str, rounds: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("BFS_PLANNER_ROUNDS", rounds)
    scenario = example(name)
    direct = run_scenario(scenario, BFSPlanner())
    served = run_scenario(scenario, SubprocessPlanner([node, str(NODE_PLANNER)]))
    assert (served.status, served.ended, served.trace_hash) == (direct.status, direct.ended, direct.trace_hash)
    assert [(f.kind, f.message) for f in served.failures] == [(f.kind, f.message) for f in direct.failures]


@pytest.mark.parametrize("client", ["python", "node"])
def test_both_clients_rounds_of_nothing_to_change_are_recognised_by_their_bytes(
    client: str, request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The commonest round answer skips decoding with fleetsim's own clients, and the run is the same."""
    recognised = []
    read = process.nothing_changed

    def counted(line: bytes, first: int, count: int) -> list[float] | None:
        durations = read(line, first, count)
        recognised.append(durations is not None)
        return durations

    monkeypatch.setattr(process, "nothing_changed", counted)
    command = [*SERVE, "fleetsim.planners:BFSPlanner"]
    if client == "node":
        command = [request.getfixturevalue("node"), str(NODE_PLANNER)]
    scenario = example("corridor-passing-bay")  # two vehicles, 182 calls: most rounds change nothing
    served = run_scenario(scenario, SubprocessPlanner(command))
    direct = run_scenario(scenario, BFSPlanner())
    assert (served.status, served.trace_hash) == (direct.status, direct.trace_hash)
    assert any(recognised) and not all(recognised), "some rounds change something: those are decoded"
