"""Dispatchers in other processes (``exec:``, protocol 1.5): the same runs as in process, asked only when
they say they dispatch, and every fault of theirs a planner-error naming dispatch()."""

from __future__ import annotations

import dataclasses
import os
import sys
import textwrap
from functools import cache
from pathlib import Path

import pytest

import fleetsim.sim.loop as sim_loop
from fleetsim import load_scenario, load_suite
from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.exec import SubprocessPlanner
from fleetsim.exec.spec import load_planner_factory
from fleetsim.orders import Order, Shift, Stop
from fleetsim.planners import ReservingPlanner
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import NO_DISPATCHER, run_scenario
from fleetsim.sim.result import RunResult

ROOT = Path(__file__).resolve().parents[2]
SERVE = [sys.executable, "-m", "fleetsim.exec"]

# A planner that dispatches too (one object, both jobs), importable from the folder it is written to.
DISPATCHING_PLANNER = """
from fleetsim.dispatchers import NearestVehicleDispatcher
from fleetsim.planners import ReservingPlanner


class DispatchingPlanner(ReservingPlanner):
    def __init__(self):
        super().__init__()
        self.dispatcher = NearestVehicleDispatcher()

    def dispatch(self, board, fleet, layout):
        return self.dispatcher.dispatch(board, fleet, layout)


class GarbageDispatcher(ReservingPlanner):
    def dispatch(self, board, fleet, layout):
        return {"vehicle 1": list(board.orders)}
"""


@pytest.fixture
def planners(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The folder holding ``dispatching_planner.py``, the working folder (importable, as for a user)."""
    (tmp_path / "dispatching_planner.py").write_text(DISPATCHING_PLANNER, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    return tmp_path


@cache
def _suite_scenario(suite: str, name: str) -> Scenario:
    loaded = load_suite(ROOT / "scenario_suites" / suite)
    return load_scenario(next(spec for spec in loaded.scenarios if spec.name == name), loaded)


def warehouse(seconds: float) -> Scenario:
    """The shipped warehouse's deadline stream for ``seconds``, with no dispatcher of its own."""
    shipped = _suite_scenario("warehouse.fleetsim.yaml", "deadlines-nearest-vehicle")
    assert shipped.shift is not None
    shift = dataclasses.replace(shipped.shift, duration=seconds, warmup=0.0)
    return dataclasses.replace(shipped, dispatcher=None, shift=shift)


ORDERS = (Order("a", (Stop(7), Stop(2)), release=0.0), Order("b", (Stop(2, dwell=2.0), Stop(7)), release=5.0))


def loop(orders: tuple[Order, ...] = ORDERS) -> Scenario:
    """The shipped one-way loop's two vehicles with ``orders`` for a minute."""
    shipped = _suite_scenario("examples.fleetsim.yaml", "loop-one-way")
    settings = dataclasses.replace(shipped.settings, stop_on=(), time_limit=60.0)
    return dataclasses.replace(shipped, tasks=(), orders=orders, settings=settings, shift=Shift(duration=60.0))


@pytest.fixture(autouse=True)
def _every_vehicle_asked(monkeypatch: pytest.MonkeyPatch) -> None:
    """In-process runs ask about every vehicle, as a planner process is asked (their calls are compared)."""
    monkeypatch.setattr(sim_loop._Run, "quiet", False)


def _outcome(result: RunResult) -> tuple[object, ...]:
    return result.status, result.ended, result.trace_hash, result.orders, result.metrics.planner_calls


def test_a_dispatching_planner_served_over_the_protocol_gives_the_in_process_run(planners: Path) -> None:
    scenario = warehouse(400.0)
    direct = run_scenario(scenario, load_planner_factory("dispatching_planner:DispatchingPlanner")())
    planner = load_planner_factory(f"exec:{sys.executable} -m fleetsim.exec dispatching_planner:DispatchingPlanner")()
    served = run_scenario(scenario, planner)
    assert isinstance(planner, SubprocessPlanner) and planner.dispatches is True
    assert any(order["completed"] is not None for order in direct.orders)  # orders were served
    assert _outcome(served) == _outcome(direct)
    assert served.measures == direct.measures


def test_the_planner_has_dispatch_only_once_its_process_says_it_dispatches(planners: Path) -> None:
    dispatching = SubprocessPlanner([*SERVE, "dispatching_planner:DispatchingPlanner"])
    plain = SubprocessPlanner([*SERVE, "fleetsim.planners:ReservingPlanner"])
    try:
        assert not hasattr(dispatching, "dispatch") and dispatching.dispatches is None  # not started: not said
        dispatching.begin_run(loop())
        plain.begin_run(loop())
        assert callable(dispatching.dispatch) and dispatching.dispatches is True
        assert not hasattr(plain, "dispatch") and plain.dispatches is False
    finally:
        dispatching.close()
        plain.close()


def test_a_process_that_does_not_dispatch_is_not_asked_and_a_run_with_orders_needs_another_dispatcher(
    planners: Path,
) -> None:
    scenario = loop()
    plain = SubprocessPlanner([*SERVE, "fleetsim.planners:ReservingPlanner"])
    result = run_scenario(scenario, plain)
    assert (result.status, result.ended) == ("failed", "planner-error")
    assert result.failures[0].message == NO_DISPATCHER.format(name=scenario.name)
    assert plain._process is None  # started to learn that it does not dispatch, and ended

    # Narrowly not: another dispatcher given, the same process makes the in-process run.
    from fleetsim.dispatchers import NearestVehicleDispatcher

    direct = run_scenario(scenario, ReservingPlanner(), dispatcher=NearestVehicleDispatcher())
    plain = SubprocessPlanner([*SERVE, "fleetsim.planners:ReservingPlanner"])
    served = run_scenario(scenario, plain, dispatcher=NearestVehicleDispatcher())
    assert _outcome(served) == _outcome(direct) and direct.status == "passed"


def test_a_dispatching_process_is_not_asked_when_the_suite_names_a_dispatcher(planners: Path) -> None:
    scenario = dataclasses.replace(loop(), dispatcher="fleetsim.dispatchers:OldestFirstDispatcher")
    direct = run_scenario(scenario, ReservingPlanner())
    planner = SubprocessPlanner([*SERVE, "dispatching_planner:DispatchingPlanner"])
    served = run_scenario(scenario, planner)
    assert _outcome(served) == _outcome(direct)
    assert planner.requests == served.metrics.planner_calls  # planner calls only: no dispatch request
    assert planner.dispatches is True  # it said so, and was not asked


def test_a_served_dispatcher_that_returns_garbage_fails_the_run_naming_dispatch(planners: Path) -> None:
    result = run_scenario(loop(), SubprocessPlanner([*SERVE, "dispatching_planner:GarbageDispatcher"]))
    assert (result.status, result.ended) == ("failed", "planner-error")
    failure = result.failures[0]
    assert failure.message.endswith("exited with status 1 before answering request 1 (dispatch() at t=0 s)")
    assert "dispatch() returned {'vehicle 1': ['a']}; it must return a list of Assignment items" in str(
        failure.details["traceback"]
    )


# A dispatcher process written by hand (no fleetsim client): it answers planner requests with nothing to
# change, and dispatch requests by giving each unassigned order to an idle vehicle, except for one fault
# chosen by its first argument at its first dispatch request.
FAULTY = """
import json, sys, time
fault = sys.argv[1]
for line in sys.stdin:
    message = json.loads(line)
    if message["type"] == "init":
        ready = {"type": "ready"} if fault == "does-not-say" else {"type": "ready", "dispatches": True}
        print(json.dumps(ready), flush=True)
        continue
    n = message["id"]
    if message["type"] != "dispatch":
        print(json.dumps({"id": n, "plans": [], "route_errors": []}), flush=True)
        continue
    board = message["board"]
    idle = list(board["idle"])
    waiting = [order["id"] for order in board["orders"] if order["vehicle_id"] is None]
    assignments = [{"vehicle_id": idle.pop(0), "orders": [order]} for order in waiting if idle]
    answer = {"id": n, "assignments": assignments}
    print(f"dispatcher: going wrong on request {n}", file=sys.stderr, flush=True)
    if fault == "crash":
        raise RuntimeError("out of coffee")
    if fault == "hang":
        time.sleep(600)
    if fault == "json":
        print("{not json", flush=True)
        continue
    if fault == "schema":
        answer["assignments"] = [{"vehicle_id": "1", "orders": ["a"]}]
    if fault == "id":
        answer["id"] = n + 41
    if fault == "unknown-order":
        answer["assignments"] = [{"vehicle_id": 1, "orders": ["nope"]}]
    print(json.dumps(answer), flush=True)
"""


@pytest.fixture
def faulty(tmp_path: Path) -> Path:
    path = tmp_path / "faulty_dispatcher.py"
    path.write_text(textwrap.dedent(FAULTY), encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("fault", "said"),
    [
        ("crash", "exited with status 1 before answering request 1 (dispatch() at t=0 s)"),
        ("json", "answered request 1 (dispatch() at t=0 s) with invalid JSON"),
        ("schema", "answered request 1 (dispatch() at t=0 s) with an invalid answer: assignments[0].vehicle_id: '1'"),
        ("id", "answered request 1 (dispatch() at t=0 s) with the answer to request 42"),
    ],
)
def test_each_fault_of_a_dispatcher_process_fails_the_run_naming_dispatch_with_its_stderr(
    faulty: Path, fault: str, said: str
) -> None:
    planner = SubprocessPlanner([sys.executable, str(faulty), fault])
    result = run_scenario(loop(), planner)
    assert (result.status, result.ended) == ("failed", "planner-error")
    failure = result.failures[0]
    assert said in failure.message and failure.message.startswith("planner process ")
    assert "dispatcher: going wrong on request 1" in str(failure.details["traceback"])
    assert planner._process is None


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    try:  # a zombie has ended too
        return Path(f"/proc/{pid}/stat").read_text().split()[2] == "Z"
    except OSError:
        return True


def test_a_hanging_dispatcher_process_is_stopped_at_the_call_timeout_and_killed(faulty: Path) -> None:
    scenario = loop()
    planner = SubprocessPlanner([sys.executable, str(faulty), "hang"], timeout=1.0)
    planner.begin_run(scenario)  # as the run would: started before its first step
    assert planner._process is not None
    pid = planner._process.pid
    result = run_scenario(scenario, planner, planner_timeout=1.0)
    assert result.ended == "planner-error"
    message = result.failures[0].message
    assert "dispatch()" in message and "timeout of 1 s" in message, message
    assert _gone(pid)


def test_a_dispatcher_process_answer_is_judged_by_the_rules_as_an_in_process_one(faulty: Path) -> None:
    # Narrowly not a fault: an answer of the right shape naming an unknown order is refused by the rules.
    result = run_scenario(loop(), SubprocessPlanner([sys.executable, str(faulty), "unknown-order"]))
    assert "order-unknown" in [event.rejection.code.value for event in result.rejections]
    assert all(failure.kind != "planner-error" for failure in result.failures)

    class Unknown(ReservingPlanner):
        def dispatch(self, board: OrderBoard, fleet: object, layout: object) -> list[Assignment]:
            return [Assignment(1, ("nope",))]

    direct = run_scenario(loop(), Unknown())
    assert [(e.time, e.rejection) for e in result.rejections] == [(e.time, e.rejection) for e in direct.rejections]


def test_a_well_behaved_dispatcher_process_serves_the_orders(faulty: Path) -> None:
    planner = SubprocessPlanner([sys.executable, str(faulty), "none"])
    result = run_scenario(loop(), planner, dispatcher=None)
    assert planner.dispatches is True
    assert [order["vehicle"] for order in result.orders] == [1, 2]


def test_a_process_that_does_not_say_it_dispatches_is_never_sent_a_dispatch_request(faulty: Path) -> None:
    planner = SubprocessPlanner([sys.executable, str(faulty), "does-not-say"])
    result = run_scenario(loop(), planner)
    assert result.failures[0].message == NO_DISPATCHER.format(name=loop().name)
    assert planner.requests == 0
