"""A master control that goes away or goes silent mid-run: its last will on fleetsim's
``master/connection`` topic fails the run naming it, and a silent one leaves the stuck-fleet diagnosis
saying, in VDA 5050's terms, which order each waiting vehicle waits for."""

from __future__ import annotations

import contextlib
import json
import threading
from collections.abc import Callable, Iterator
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import pytest
from paho.mqtt.client import Client, MQTTv311
from paho.mqtt.enums import CallbackAPIVersion
from result_document import schema_errors
from scripted_master import ScriptedMaster

from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult
from fleetsim.vda5050.broker import BrokerAddress
from fleetsim.vda5050.fleet import Vda5050Fleet, Vda5050Settings

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
SPEED = 20.0
PRESENCE = "uagv/fleetsim/master/connection"


def _crossing() -> Scenario:
    suite = load_suite(SUITES / "examples.fleetsim.yaml")
    return load_scenario(next(s for s in suite.scenarios if s.name == "crossing"), suite)


@contextlib.contextmanager
def _master(broker: BrokerAddress, **options: Any) -> Iterator[ScriptedMaster]:
    """A scripted master control on ``broker`` (``options`` as ScriptedMaster takes them), closed afterwards."""
    master = ScriptedMaster(broker.host, broker.port, **options)
    try:
        yield master
    finally:
        master.close()


def _run_while(broker: BrokerAddress, master: ScriptedMaster, then: Callable[[], None] | None = None) -> RunResult:
    """Run the crossing; ``then`` is called (in a thread) once a vehicle reports it drives an order."""

    def act() -> None:
        if master.wait_until(lambda: any(s["driving"] and s["orderId"] for s in master.history), timeout=30.0):
            assert then is not None
            then()

    watcher = threading.Thread(target=act, daemon=True) if then is not None else None
    if watcher is not None:
        watcher.start()
    try:
        return run_scenario(
            _crossing(), Vda5050Fleet(Vda5050Settings(broker=broker, speed=SPEED)), planner_timeout=None
        )
    finally:
        if watcher is not None:
            watcher.join(timeout=30.0)


def test_a_master_control_that_crashes_mid_run_fails_it_through_its_last_will(broker: BrokerAddress) -> None:
    with _master(broker, announce="mc-1") as master:
        result = _run_while(broker, master, master.crash)
    assert result.ended == "planner-error"
    [failure] = result.failures
    assert "the master control 'mc-1' lost its connection at t = " in failure.message
    assert f"(its last will on {PRESENCE}: CONNECTIONBROKEN) with 2 task(s) queued" in failure.message
    assert result.tasks_completed == 0


def test_a_master_control_that_announced_itself_and_stays_completes_the_run(broker: BrokerAddress) -> None:
    with _master(broker, announce="mc-1") as master:
        result = _run_while(broker, master)
    assert result.passed, [f.message for f in result.failures]
    assert result.tasks_completed == 2
    document = result.to_dict()
    assert schema_errors(document) == []  # paced and pacing as the published schema has them
    assert document["paced"] == SPEED and document["pacing"]["order_latency"]["orders"] == 2


def test_a_master_control_that_goes_offline_with_tasks_queued_fails_the_run(broker: BrokerAddress) -> None:
    with _master(broker, announce="mc-2") as master:
        result = _run_while(broker, master, master.leave)
    [failure] = result.failures
    assert result.ended == "planner-error"
    assert "the master control 'mc-2' went OFFLINE at t = " in failure.message
    assert "with 2 task(s) queued" in failure.message


def _retain(broker: BrokerAddress, state: str) -> None:
    """What an earlier run's master control left on the broker: a retained connection message."""
    client = Client(callback_api_version=CallbackAPIVersion.VERSION2, client_id="earlier-master", protocol=MQTTv311)
    client.connect(broker.host, broker.port)
    client.loop_start()
    message: dict[str, Any] = {
        "headerId": 7,
        "timestamp": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-4] + "Z",
        "version": "2.0.0",
        "manufacturer": "fleetsim",
        "serialNumber": "earlier",
        "connectionState": state,
    }
    client.publish(PRESENCE, json.dumps(message).encode(), qos=1, retain=True).wait_for_publish(5.0)
    client.loop_stop()
    client.disconnect()


def test_an_earlier_runs_retained_last_will_is_history_not_news(broker: BrokerAddress) -> None:
    _retain(broker, "CONNECTIONBROKEN")
    with _master(broker) as master:  # one that does not announce itself
        result = _run_while(broker, master)
    assert result.passed, [f.message for f in result.failures]


def test_a_message_on_master_connection_that_is_no_connection_is_ignored_with_a_word(
    broker: BrokerAddress, capsys: pytest.CaptureFixture[str]
) -> None:
    with _master(broker) as master:

        def garble() -> None:
            master.client.publish(PRESENCE, b'{"connectionState": "GONE"}', qos=1).wait_for_publish(5.0)

        result = _run_while(broker, master, garble)
    assert result.passed, [f.message for f in result.failures]
    said = capsys.readouterr().err
    assert f"fleetsim: ignored a message on {PRESENCE} that is not a connection: " in said
    assert "connectionState: 'GONE' is not one of ONLINE, OFFLINE, CONNECTIONBROKEN" in said


def _base_only_the_first_edge(order: dict[str, Any]) -> dict[str, Any]:
    """Release the order's first edge and its two nodes; the rest is horizon."""
    for k, node in enumerate(order["nodes"]):
        node["released"] = k < 2
    for k, edge in enumerate(order["edges"]):
        edge["released"] = k < 1
    return order


def test_a_silent_master_control_leaves_a_diagnosis_that_names_the_orders_the_vehicles_wait_for(
    broker: BrokerAddress,
) -> None:
    # One vehicle at a time: vehicle 1 gets an order with one released edge and never an update;
    # vehicle 2 never gets an order, as the master control waits for vehicle 1's task.
    with _master(broker, tamper=_base_only_the_first_edge) as master:
        result = _run_while(broker, master)
    assert result.ended == "deadlock"
    assert result.diagnosis is not None
    first, second = result.diagnosis.findings
    [order] = master.sent
    horizon = ", ".join(e["edgeId"] for e in order["edges"][1:])
    stitch = order["nodes"][1]
    assert first.note == (
        f"VDA 5050: order {order['orderId']!r} (update 0) is released up to node {stitch['nodeId']!r} "
        f"(sequence {stitch['sequenceId']}); it waits for an order update releasing its horizon ({horizon}); "
        "the master control's last message to it came at t = 0.0 s"
    )
    assert second.note == (
        f"VDA 5050: it has had no order (its task {second.task.id} is on uagv/fleetsim/transportOrders/"
        f"{second.task.id}); the master control has sent it nothing"
    )
    [failure] = [f for f in result.failures if f.kind == "deadlock"]
    report = "\n".join([failure.message, *result.diagnosis.lines()])
    assert first.note in report and second.note in report  # in the findings' lines, and a root cause's
    assert failure.details["vehicles"][0]["note"] == first.note
