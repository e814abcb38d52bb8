"""Instant actions, each with its action state: answered at once (stateRequest, factsheetRequest), a pause
that really holds the vehicle, refusals that fail with an error (initPosition, an unknown action, a cancel
with nothing to cancel), and vda-5050-lib 1.4.0's instantActions key answered by a validationError."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from official import validate
from scripted_master import ScriptedMaster

from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import ReservingPlanner
from fleetsim.planning.checks import RejectionCode
from fleetsim.scenario import Scenario, Task
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult
from fleetsim.vda5050.broker import BrokerAddress, EmbeddedBroker
from fleetsim.vda5050.fleet import Vda5050Fleet, Vda5050Settings

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
SPEED = 20.0


def _crossing() -> Scenario:
    suite = load_suite(SUITES / "examples.fleetsim.yaml")
    return load_scenario(next(s for s in suite.scenarios if s.name == "crossing"), suite)


@pytest.fixture
def address() -> Iterator[BrokerAddress]:
    with EmbeddedBroker() as broker:
        yield broker.address


def _run_with(
    address: BrokerAddress,
    script: Any,
    version: str = "2.0",
    fleet: Vda5050Fleet | None = None,
    scenario: Scenario | None = None,
) -> tuple[RunResult, ScriptedMaster]:
    """Run the crossing with a one-at-a-time master control and ``script(master)`` in a thread beside it."""
    master = ScriptedMaster(address.host, address.port, version=f"{version}.0")
    helper = threading.Thread(target=script, args=(master,), daemon=True)
    helper.start()
    fleet = fleet or Vda5050Fleet(Vda5050Settings(version=version, broker=address, speed=SPEED))
    try:
        result = run_scenario(scenario or _crossing(), fleet, planner_timeout=None)
    finally:
        helper.join(timeout=10)
        master.close()
    return result, master


def _action_states(master: ScriptedMaster, serial: str) -> dict[str, dict[str, Any]]:
    states = [s for s in master.history if s["serialNumber"] == serial]
    return {a["actionId"]: a for a in states[-1]["actionStates"]} if states else {}


def test_a_state_and_a_factsheet_on_request(address: BrokerAddress) -> None:
    def ask(master: ScriptedMaster) -> None:
        master.wait_until(lambda: "1" in master.states)
        master.instant(
            "1", {"actionType": "stateRequest", "actionId": "s1"}, {"actionType": "factsheetRequest", "actionId": "f1"}
        )
        master.wait_until(lambda: "f1" in _action_states(master, "1"))

    result, master = _run_with(address, ask)
    assert result.passed
    done = _action_states(master, "1")
    assert done["s1"]["actionStatus"] == done["f1"]["actionStatus"] == "FINISHED"
    sheets = [d for name, d in master.wire if name == "factsheet" and d["serialNumber"] == "1"]
    assert len(sheets) >= 2  # at the start (retained) and on request
    assert sheets[-1]["physicalParameters"]["speedMax"] == 1.0 and sheets[-1]["physicalParameters"]["length"] == 1.0


def test_a_pause_holds_the_vehicle_until_it_is_lifted(address: BrokerAddress) -> None:
    held: list[dict[str, Any]] = []

    def pause(master: ScriptedMaster) -> None:
        master.wait_until(
            lambda: any(s["serialNumber"] == "1" and s["orderId"] and s["driving"] for s in master.history)
        )
        master.instant("1", {"actionType": "startPause", "actionId": "p1"})
        master.wait_until(
            lambda: any(s["serialNumber"] == "1" and s.get("paused") and not s["driving"] for s in master.history)
        )
        seen = len(master.history)
        threading.Event().wait(0.5)  # 10 simulated seconds at 20x
        held.extend(s for s in master.history[seen:] if s["serialNumber"] == "1")
        master.instant("1", {"actionType": "stopPause", "actionId": "p2"})

    result, master = _run_with(address, pause)
    assert result.passed  # it drove on afterwards
    assert held and all(s["paused"] and not s["driving"] for s in held)
    positions = {(round(s["agvPosition"]["x"], 3), round(s["agvPosition"]["y"], 3)) for s in held}
    assert len(positions) == 1  # it stood still
    unpaused = run_scenario(_crossing(), ReservingPlanner())
    assert result.metrics.makespan is not None and unpaused.metrics.makespan is not None
    assert result.metrics.makespan > unpaused.metrics.makespan + 5.0  # the pause cost time
    assert _action_states(master, "1")["p1"]["actionStatus"] == "FINISHED"


@pytest.mark.parametrize(
    ("action", "error_type", "words"),
    [
        ("initPosition", "actionError", "stands where its scenario puts it"),
        ("liftFork", "unknownActionError", "know no action 'liftFork'"),
        ("cancelOrder", "noOrderToCancel", "there is no order to cancel"),
    ],
)
def test_an_action_it_cannot_carry_out_fails_with_an_error(
    address: BrokerAddress, action: str, error_type: str, words: str
) -> None:
    def send(master: ScriptedMaster) -> None:
        master.wait_until(lambda: "2" in master.states)
        master.instant("2", {"actionType": action, "actionId": "a1"})  # vehicle 2 has no order yet
        master.wait_until(lambda: "a1" in _action_states(master, "2"))

    result, master = _run_with(address, send)
    state = _action_states(master, "2")["a1"]
    assert state["actionStatus"] == "FAILED" and words in state["resultDescription"]
    errors = [e for s in master.history if s["serialNumber"] == "2" for e in s["errors"]]
    assert any(
        e["errorType"] == error_type and {"referenceKey": "actionId", "referenceValue": "a1"} in e["errorReferences"]
        for e in errors
    )
    assert result.passed  # a refused action changes nothing else


def test_the_instant_actions_key_of_vda_5050_lib_1_4_is_a_validation_error(address: BrokerAddress) -> None:
    def send(master: ScriptedMaster) -> None:
        master.wait_until(lambda: "2" in master.states)
        master.instant("2", {"actionType": "stateRequest", "actionId": "x"}, key="instantActions")
        master.wait_until(lambda: any(s["serialNumber"] == "2" and s["errors"] for s in master.history))

    result, master = _run_with(address, send)
    errors = [e for s in master.history if s["serialNumber"] == "2" for e in s["errors"]]
    assert any(
        e["errorType"] == "validationError" and "expected key 'actions'" in e["errorDescription"] for e in errors
    )
    assert [r.rejection.code for r in result.rejections] == [RejectionCode.ORDER_INVALID]


@pytest.mark.parametrize("version", ["2.0", "2.1"])
def test_every_message_the_vehicles_publish_passes_the_independent_schemas(
    address: BrokerAddress, version: str
) -> None:
    def ask(master: ScriptedMaster) -> None:
        master.wait_until(lambda: "1" in master.states)
        master.instant(
            "1", {"actionType": "factsheetRequest", "actionId": "f"}, {"actionType": "liftFork", "actionId": "u"}
        )

    result, master = _run_with(address, ask, version)
    assert result.passed
    kinds = {name for name, _ in master.wire}
    assert {"connection", "state", "visualization", "factsheet"} <= kinds
    for name, document in master.wire:
        assert validate(version, name, document) == [], (name, document)


def test_a_cancel_drives_the_base_to_its_end_then_finishes(address: BrokerAddress) -> None:
    def cancel(master: ScriptedMaster) -> None:
        master.wait_until(
            lambda: any(s["serialNumber"] == "1" and s["orderId"] and s["driving"] for s in master.history)
        )
        master.instant("1", {"actionType": "cancelOrder", "actionId": "c1"})
        master.wait_until(
            lambda: _action_states(master, "1").get("c1", {}).get("actionStatus") == "FINISHED", timeout=5
        )

    fleet = Vda5050Fleet(Vda5050Settings(broker=address, speed=SPEED))
    crossing = _crossing()
    longer = replace(crossing, tasks=(*crossing.tasks, Task(3, 2, 5)))  # vehicle 2 drives back: time to stop
    result, master = _run_with(address, cancel, fleet=fleet, scenario=longer)
    statuses = [
        a["actionStatus"]
        for s in master.history
        if s["serialNumber"] == "1"
        for a in s["actionStates"]
        if a["actionId"] == "c1"
    ]
    assert statuses[0] == "RUNNING"  # while the base is driven
    assert fleet.vehicles[1].actions["c1"].action_status.value == "FINISHED"  # once it stood at its end
    assert result.tasks_completed >= 1  # its base held its goal: the commitment was kept
