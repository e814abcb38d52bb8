"""fleetsim's vehicles driven over MQTT by a master control that is not fleetsim's (paho-mqtt, networkx):
the shipped crossing completed one vehicle at a time, and a collision alert when both routes are released
at once, on the embedded broker and on Debian's mosquitto."""

from __future__ import annotations

import itertools
import json
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import pytest
from paho.mqtt.client import CallbackAPIVersion, Client, MQTTv311
from scripted_master import ScriptedMaster

from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.scenario import Disturbance, Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.vda5050.broker import BrokerAddress
from fleetsim.vda5050.fleet import Vda5050Fleet, Vda5050Settings

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
SPEED = 20.0


def _scenario(name: str) -> Scenario:
    suite = load_suite(SUITES / "examples.fleetsim.yaml")
    return load_scenario(next(s for s in suite.scenarios if s.name == name), suite)


@pytest.fixture
def master(broker: BrokerAddress) -> Iterator[ScriptedMaster]:
    control = ScriptedMaster(broker.host, broker.port)
    yield control
    control.close()


def test_a_master_control_completes_the_crossing_one_vehicle_at_a_time(
    broker: BrokerAddress, master: ScriptedMaster
) -> None:
    fleet = Vda5050Fleet(Vda5050Settings(broker=broker, speed=SPEED))
    result = run_scenario(_scenario("crossing"), fleet, planner_timeout=None)
    assert result.passed, [f.message for f in result.failures]
    assert result.tasks_completed == 2 and not result.collisions and not result.rejections
    assert len(master.sent) == 2 and {o["serialNumber"] for o in master.sent} == {"1", "2"}
    assert fleet.latencies and max(fleet.latencies) < 5.0
    # The states told it where each vehicle went: node after node of its order, each removed once passed.
    for serial, goal_node in (("1", "s4.last"), ("2", "s8.last")):
        seen = [s for s in master.history if s["serialNumber"] == serial and s["orderId"]]
        remaining = [[n["nodeId"] for n in s["nodeStates"]] for s in seen]
        assert remaining[0][-1] == goal_node  # the whole route ahead, to the goal edge's end
        assert all(len(b) <= len(a) for a, b in itertools.pairwise(remaining))  # only shrinks
        [order] = [o for o in master.sent if o["serialNumber"] == serial]
        route = [n["nodeId"] for n in order["nodes"]]
        passed = [route.index(s["lastNodeId"]) for s in seen]
        assert passed == sorted(passed) and passed[-1] > passed[0]  # its last node moved along the route


def test_releasing_both_routes_at_once_raises_a_collision_alert(broker: BrokerAddress) -> None:
    greedy = ScriptedMaster(broker.host, broker.port, one_at_a_time=False)
    try:
        fleet = Vda5050Fleet(Vda5050Settings(broker=broker, speed=SPEED))
        result = run_scenario(_scenario("crossing"), fleet, planner_timeout=None)
    finally:
        greedy.close()
    assert not result.passed
    assert result.collisions and result.failures[0].kind == "collision"


def test_a_master_control_that_never_speaks_fails_the_run_saying_where_it_was_awaited(broker: BrokerAddress) -> None:
    fleet = Vda5050Fleet(Vda5050Settings(broker=broker, speed=SPEED, start_timeout=1.0))
    result = run_scenario(_scenario("crossing"), fleet, planner_timeout=None)
    assert result.ended == "planner-error" and result.steps == 1  # the clock never started
    [failure] = result.failures
    assert "the master control sent no message to any vehicle within 1 s" in failure.message
    assert broker.url in failure.message


def test_malformed_json_is_a_validation_error_in_the_state_and_an_order_invalid_rejection(
    broker: BrokerAddress,
) -> None:
    def garble(order: dict[str, object]) -> bytes:
        return b'{"headerId": 0, "orderId": ' if order["serialNumber"] == "1" else json.dumps(order).encode()

    tampering = ScriptedMaster(broker.host, broker.port, tamper=garble)
    try:
        fleet = Vda5050Fleet(Vda5050Settings(broker=broker, speed=SPEED))
        crossing = _scenario("crossing")
        going_on = replace(crossing, settings=replace(crossing.settings, stop_on=(), time_limit=40.0))
        result = run_scenario(going_on, fleet, planner_timeout=None)
    finally:
        tampering.close()
    assert result.rejections and result.rejections[0].rejection.code.value == "order-invalid"
    assert result.rejections[0].rejection.vehicle_id == 1
    assert "JSON" in result.rejections[0].rejection.message or "json" in result.rejections[0].rejection.message
    errors = [e for s in tampering.history if s["serialNumber"] == "1" for e in s["errors"]]
    assert errors and all(e["errorType"] == "validationError" for e in errors)


def test_a_flood_is_contained_one_rejection_a_step_and_a_bounded_buffer(broker: BrokerAddress) -> None:
    flooder = Client(callback_api_version=CallbackAPIVersion.VERSION2, client_id="flooder", protocol=MQTTv311)
    flooder.connect(broker.host, broker.port)
    flooder.loop_start()
    try:
        fleet = Vda5050Fleet(Vda5050Settings(broker=broker, speed=SPEED, start_timeout=20.0))
        done = threading.Event()

        def flood() -> None:
            while not done.is_set():
                for _ in range(200):
                    flooder.publish("uagv/v2/fleetsim/1/order", b"not json at all", qos=0)
                time.sleep(0.01)

        thread = threading.Thread(target=flood, daemon=True)
        thread.start()
        scenario = replace(
            _scenario("crossing"), settings=replace(_scenario("crossing").settings, time_limit=5.0, stop_on=())
        )
        result = run_scenario(scenario, fleet, planner_timeout=None)
        done.set()
        thread.join(timeout=5)
    finally:
        flooder.loop_stop()
        flooder.disconnect()
    assert result.ended == "time-limit"  # the harness went on, step by step
    assert len(result.rejections) <= result.steps  # at most one a step for the flooded vehicle
    assert any("more refused messages this step" in r.rejection.message for r in result.rejections)


def test_a_master_control_that_exits_fails_the_run_naming_its_status(tmp_path: Path) -> None:
    from fleetsim.exec.spec import load_planner_factory

    planner = load_planner_factory(f"vda5050:speed={SPEED},exec={sys.executable} -c 'import sys; sys.exit(3)'")()
    result = run_scenario(_scenario("crossing"), planner, planner_timeout=None)
    assert result.ended == "planner-error"
    assert "the master control exited with status 3" in result.failures[0].message


def test_a_disturbed_vehicle_tells_it_in_its_state(broker: BrokerAddress, master: ScriptedMaster) -> None:
    crossing = _scenario("crossing")
    stop = Disturbance(vehicle=1, kind="stop", duration=4.0, at=3.0)
    disturbed = replace(crossing, disturbances=(stop,))
    result = run_scenario(disturbed, Vda5050Fleet(Vda5050Settings(broker=broker, speed=SPEED)), planner_timeout=None)
    assert result.passed and [d.kind for d in result.disturbances] == ["stop"]
    told = [s for s in master.history if s["serialNumber"] == "1" and s["information"]]
    assert told and told[0]["information"][0]["infoType"] == "disturbance"
    assert all(s["safetyState"]["fieldViolation"] for s in told)
    calm = [s for s in master.history if s["serialNumber"] == "2"]
    assert calm and not any(s["information"] or s["safetyState"]["fieldViolation"] for s in calm)
