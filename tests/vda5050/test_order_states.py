"""What a vehicle's state says around its orders, read on the wire by a master control written here from
the standard's text (paho-mqtt alone): a vehicle without an order stands on its start edge, and a new
order's first state already names the node the order begins at, with that order's sequence id
(VDA 5050 2.0 6.7: sequence ids start again with a new orderId; 6.10.6: lastNodeSequenceId is that of
the last node reached, or the node the vehicle is on, in the current order)."""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from dataclasses import replace
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import official
import pytest
from paho.mqtt.client import CallbackAPIVersion, Client, MQTTMessage, MQTTv311

from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult
from fleetsim.vda5050.broker import EmbeddedBroker
from fleetsim.vda5050.fleet import Vda5050Fleet, Vda5050Settings

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
# The crossing: vehicle 1 drives e1 (s1.first -> s1.last), then e2, e3, e4 to s4.last; vehicle 2 gets nothing.
FIRST = [("s1.first", "e1", "s1.last")]
SECOND = [("s1.last", "e2", "s2.last"), ("s2.last", "e3", "s3.last"), ("s3.last", "e4", "s4.last")]


def _order(order_id: str, route: list[tuple[str, str, str]], header: int) -> dict[str, Any]:
    """A new order along ``route`` (start node, edge, end node), all released, its sequence ids from 0."""
    nodes = [route[0][0], *(end for _, _, end in route)]
    now = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-4] + "Z"
    message = {
        "headerId": header,
        "timestamp": now,
        "version": "2.0.0",
        "manufacturer": "fleetsim",
        "serialNumber": "1",
        "orderId": order_id,
        "orderUpdateId": 0,
        "nodes": [{"nodeId": n, "sequenceId": 2 * k, "released": True, "actions": []} for k, n in enumerate(nodes)],
        "edges": [
            {
                "edgeId": edge,
                "sequenceId": 2 * k + 1,
                "released": True,
                "startNodeId": start,
                "endNodeId": end,
                "actions": [],
            }
            for k, (start, edge, end) in enumerate(route)
        ],
    }
    return message


ORDERS = {"order-1": _order("order-1", FIRST, 1), "order-2": _order("order-2", SECOND, 2)}


class _Master:
    """Sends vehicle 1 ``order-1`` (e1) at its first state, and a new order ``order-2`` (e2, e3, e4) from
    the node it stands on once it has driven order-1's base; records every state of both vehicles."""

    def __init__(self, host: str, port: int) -> None:
        self.states: list[dict[str, Any]] = []
        self.sent: list[str] = []
        self.lock = threading.Lock()
        self.client = Client(callback_api_version=CallbackAPIVersion.VERSION2, client_id="master", protocol=MQTTv311)
        self.client.on_message = self._on_message
        self.client.connect(host, port)
        self.client.subscribe("uagv/v2/fleetsim/+/state", qos=1)
        self.client.loop_start()

    def _on_message(self, client: Client, userdata: Any, message: MQTTMessage) -> None:
        state = json.loads(message.payload)
        with self.lock:
            self.states.append(state)
            if state["serialNumber"] != "1":
                return
            if not self.sent:
                self._send("order-1")
            elif (
                self.sent == ["order-1"]
                and state["orderId"] == "order-1"
                and not state["driving"]
                and not state["nodeStates"]
                and state["lastNodeId"] == "s1.last"
            ):
                self._send("order-2")

    def _send(self, order_id: str) -> None:
        self.sent.append(order_id)
        self.client.publish("uagv/v2/fleetsim/1/order", json.dumps(ORDERS[order_id]).encode(), qos=1)

    def close(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()


@pytest.fixture(scope="module")
def run() -> Iterator[tuple[RunResult, list[dict[str, Any]]]]:
    """The crossing driven by :class:`_Master` at 20x (vehicle 2 never gets an order): its result and
    every state the vehicles sent."""
    for order in ORDERS.values():
        assert official.validate("2.0", "order", order) == [], order
    suite = load_suite(SUITES / "examples.fleetsim.yaml")
    crossing = load_scenario(next(s for s in suite.scenarios if s.name == "crossing"), suite)
    scenario = replace(crossing, settings=replace(crossing.settings, time_limit=30.0, stop_on=()))
    with EmbeddedBroker() as broker:
        master = _Master(broker.address.host, broker.address.port)
        try:
            fleet = Vda5050Fleet(Vda5050Settings(broker=broker.address, speed=20.0))
            result = run_scenario(scenario, fleet, planner_timeout=None)
        finally:
            master.close()
    assert master.sent == ["order-1", "order-2"], master.sent
    with master.lock:
        yield result, list(master.states)


def test_a_new_orders_states_name_its_own_nodes_with_its_own_sequence_ids(
    run: tuple[RunResult, list[dict[str, Any]]],
) -> None:
    result, states = run
    assert result.tasks_completed == 1  # vehicle 1's task: order-2 drove it onto segment 4
    second = [s for s in states if s["serialNumber"] == "1" and s["orderId"] == "order-2"]
    assert second
    # Its first state, before the vehicle has left the node the order begins at, names that node with
    # order-2's sequence id 0 (not order-1's 2), and every later one a node of order-2 with its id.
    assert (second[0]["lastNodeId"], second[0]["lastNodeSequenceId"]) == ("s1.last", 0)
    nodes = {("s1.last", 0), ("s2.last", 2), ("s3.last", 4), ("s4.last", 6)}
    assert {(s["lastNodeId"], s["lastNodeSequenceId"]) for s in second} <= nodes
    assert (second[-1]["lastNodeId"], second[-1]["lastNodeSequenceId"]) == ("s4.last", 6)


def test_a_vehicle_without_an_order_stands_on_its_start_edge(run: tuple[RunResult, list[dict[str, Any]]]) -> None:
    result, states = run
    waiting = [s for s in states if s["serialNumber"] == "2"]
    assert len(waiting) > 2 and all(s["orderId"] == "" for s in waiting)
    assert not any(s["driving"] for s in waiting)
    assert {(s["agvPosition"]["x"], s["agvPosition"]["y"]) for s in waiting} == {
        (waiting[0]["agvPosition"]["x"], waiting[0]["agvPosition"]["y"])
    }
    assert result.metrics.distance[2] == 0.0  # the trace says so too
    # Vehicle 1 stood until its first order and drove it at once.
    unordered = [s for s in states if s["serialNumber"] == "1" and not s["orderId"]]
    assert unordered and not any(s["driving"] for s in unordered)
    assert any(s["driving"] for s in states if s["serialNumber"] == "1" and s["orderId"] == "order-1")
