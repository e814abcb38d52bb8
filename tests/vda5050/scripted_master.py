"""A small master control for the tests, written on paho-mqtt alone (none of fleetsim's code): it reads
the site and the transport orders fleetsim publishes, routes each task by shortest path from where its
vehicle stands, and sends the whole route as one order, either at once for every vehicle or one vehicle
at a time (the next vehicle's order only once the last one's task is done)."""

from __future__ import annotations

import itertools
import json
import socket
import threading
import time
from collections.abc import Callable
from datetime import datetime, timezone
from typing import Any

import networkx as nx
from paho.mqtt.client import CallbackAPIVersion, Client, MQTTMessage, MQTTv311

Tamper = Callable[[dict[str, Any]], dict[str, Any] | bytes]


class ScriptedMaster:
    """Connects to ``host:port`` and drives the vehicles of ``interface``/``manufacturer``."""

    def __init__(
        self,
        host: str,
        port: int,
        *,
        interface: str = "uagv",
        manufacturer: str = "fleetsim",
        version: str = "2.0.0",
        one_at_a_time: bool = True,
        tamper: Tamper | None = None,
        announce: str | None = None,
    ) -> None:
        self.interface, self.manufacturer, self.version = interface, manufacturer, version
        self.one_at_a_time = one_at_a_time
        self.tamper = tamper
        self.site: dict[str, Any] | None = None
        self.states: dict[str, dict[str, Any]] = {}  # each vehicle's latest
        self.history: list[dict[str, Any]] = []  # every state, in arrival order
        self.tasks: dict[str, dict[str, Any]] = {}
        self.sent: list[dict[str, Any]] = []
        self.orders_of: dict[str, int] = {}
        self.busy: str | None = None  # the task whose vehicle drives now (one at a time)
        self.lock = threading.RLock()
        self.client = Client(
            callback_api_version=CallbackAPIVersion.VERSION2, client_id="scripted-master", protocol=MQTTv311
        )
        self.client.on_message = self._on_message
        self.announce = announce
        if announce is not None:  # fleetsim's master/connection: ONLINE now, CONNECTIONBROKEN as the last will
            self.client.will_set(self._presence, self._connection("CONNECTIONBROKEN"), qos=1, retain=True)
        self.client.connect(host, port)
        if announce is not None:
            self.client.publish(self._presence, self._connection("ONLINE"), qos=1, retain=True)
        self.wire: list[tuple[str, dict[str, Any]]] = []  # every VDA 5050 message a vehicle published
        self.client.subscribe([(f"{interface}/fleetsim/#", 1), (f"{interface}/v2/{manufacturer}/+/+", 0)])
        self.client.loop_start()

    def close(self) -> None:
        self.client.loop_stop()
        self.client.disconnect()

    @property
    def _presence(self) -> str:
        return f"{self.interface}/fleetsim/master/connection"

    def _connection(self, state: str) -> bytes:
        now = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-4] + "Z"
        message = {
            "headerId": 0,
            "timestamp": now,
            "version": self.version,
            "manufacturer": self.manufacturer,
            "serialNumber": self.announce or "",
            "connectionState": state,
        }
        return json.dumps(message).encode()

    def leave(self) -> None:
        """Say OFFLINE on master/connection and disconnect cleanly (no last will)."""
        self.client.publish(self._presence, self._connection("OFFLINE"), qos=1, retain=True).wait_for_publish(5.0)
        self.close()

    def crash(self) -> None:
        """Drop the connection without DISCONNECT, as a crashed process would: the broker sends the will."""
        sock = self.client.socket()
        if isinstance(sock, socket.socket):
            socket.socket.shutdown(sock, socket.SHUT_RDWR)
        self.client.loop_stop()

    def _on_message(self, client: Client, userdata: Any, message: MQTTMessage) -> None:
        if message.topic.rsplit("/", 1)[-1] in ("order", "instantActions") or message.topic == self._presence:
            return  # our own
        document = json.loads(message.payload)
        with self.lock:
            if message.topic.endswith("/fleetsim/site"):
                self.site = document
            elif "/transportOrders/" in message.topic:
                self.tasks[document["taskId"]] = document
                if document["state"] == "FINISHED" and self.busy == document["taskId"]:
                    self.busy = None
            else:
                name = message.topic.rsplit("/", 1)[-1]
                self.wire.append((name, document))
                if name == "state":
                    self.states[document["serialNumber"]] = document
                    self.history.append(document)
            self._dispatch()

    def _dispatch(self) -> None:
        if self.site is None:
            return
        for task_id, task in sorted(self.tasks.items(), key=lambda item: int(item[0])):
            if task["state"] != "OPEN" or task.get("sent") or (self.one_at_a_time and self.busy is not None):
                continue
            serial = task["serialNumber"]
            if serial not in self.states:
                if self.one_at_a_time:  # strictly in the tasks' order, whichever vehicle reported first
                    break
                continue
            order = self._order(serial, task)
            if order is None:
                continue
            task["sent"] = True
            self.busy = task_id
            self._send(serial, order)

    def _order(self, serial: str, task: dict[str, Any]) -> dict[str, Any] | None:
        assert self.site is not None
        graph = nx.DiGraph()
        for edge in self.site["edges"]:
            graph.add_edge(edge["startNodeId"], edge["endNodeId"], edgeId=edge["edgeId"], weight=edge["length"])
        vehicle = next(v for v in self.site["vehicles"] if v["serialNumber"] == serial)
        state = self.states[serial]
        first = self.orders_of.get(serial, 0) == 0
        path: list[str]
        edges: list[str]
        if first:  # it stands on its start edge: the order begins with it
            start_edge = next(
                e
                for e in self.site["edges"]
                if e["edgeId"] == vehicle["startEdgeId"] and e["startNodeId"] == vehicle["startNodeId"]
            )
            path, edges = [start_edge["startNodeId"], start_edge["endNodeId"]], [start_edge["edgeId"]]
        else:
            path, edges = [state["lastNodeId"]], []
        # The task is done on its goal edge: route to the edge's start, then drive it.
        best: tuple[float, list[str], str] | None = None
        for goal in (e for e in self.site["edges"] if e["edgeId"] in task["goalEdgeIds"]):
            try:
                lead = nx.shortest_path(graph, path[-1], goal["startNodeId"], weight="weight")
            except nx.NetworkXNoPath:
                continue
            cost = nx.path_weight(graph, lead, "weight") + goal["length"] if len(lead) > 1 else goal["length"]
            if best is None or cost < best[0]:
                best = (cost, [*lead, goal["endNodeId"]], goal["edgeId"])
        if best is None:
            return None
        _, route, goal_edge = best
        for a, b in itertools.pairwise(route[:-1]):
            path.append(b)
            edges.append(graph.edges[a, b]["edgeId"])
        path.append(route[-1])
        edges.append(goal_edge)
        if not edges:
            return None
        return self._order_message(serial, path, edges)

    def _order_message(self, serial: str, path: list[str], edges: list[str]) -> dict[str, Any]:
        """A new order for ``serial`` driving ``edges`` through ``path``, all released."""
        sequence = 0  # a new order numbers its nodes and edges from 0
        self.orders_of[serial] = self.orders_of.get(serial, 0) + 1
        order_id = f"order-{serial}-{self.orders_of[serial]}"
        now = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-4] + "Z"
        return {
            "headerId": len(self.sent),
            "timestamp": now,
            "version": self.version,
            "manufacturer": self.manufacturer,
            "serialNumber": serial,
            "orderId": order_id,
            "orderUpdateId": 0,
            "nodes": [
                {"nodeId": node, "sequenceId": sequence + 2 * k, "released": True, "actions": []}
                for k, node in enumerate(path)
            ],
            "edges": [
                {
                    "edgeId": edge,
                    "sequenceId": sequence + 2 * k + 1,
                    "released": True,
                    "startNodeId": path[k],
                    "endNodeId": path[k + 1],
                    "actions": [],
                }
                for k, edge in enumerate(edges)
            ],
        }

    def _send(self, serial: str, order: dict[str, Any]) -> None:
        payload: dict[str, Any] | bytes = self.tamper(order) if self.tamper is not None else order
        self.sent.append(order)
        data = payload if isinstance(payload, bytes) else json.dumps(payload).encode()
        self.client.publish(f"{self.interface}/v2/{self.manufacturer}/{serial}/order", data, qos=0)

    def instant(self, serial: str, *actions: dict[str, Any], key: str = "actions") -> None:
        """Send ``actions`` (each a dict with actionType and actionId) to vehicle ``serial`` (under ``key``:
        vda-5050-lib 1.4.0 wrongly writes ``instantActions``)."""
        now = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-4] + "Z"
        message = {
            "headerId": len(self.sent),
            "timestamp": now,
            "version": self.version,
            "manufacturer": self.manufacturer,
            "serialNumber": serial,
            key: [{"blockingType": "NONE", "actionParameters": [], **a} for a in actions],
        }
        self.client.publish(
            f"{self.interface}/v2/{self.manufacturer}/{serial}/instantActions", json.dumps(message).encode()
        )

    def wait_until(self, condition: Callable[[], bool], timeout: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self.lock:
                if condition():
                    return True
            time.sleep(0.01)
        return False

    def wait_for_site(self, timeout: float = 10.0) -> None:
        deadline = time.monotonic() + timeout
        while self.site is None and time.monotonic() < deadline:
            time.sleep(0.01)


def main() -> int:
    """Run as the master control of a ``vda5050:...,exec=`` planner spec: the broker from the environment,
    until fleetsim stops it (SIGTERM)."""
    import os
    import signal
    from urllib.parse import urlsplit

    url = urlsplit(os.environ["FLEETSIM_MQTT_URL"])
    stopped = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stopped.set())
    master = ScriptedMaster(
        url.hostname or "127.0.0.1",
        url.port or 1883,
        interface=os.environ["FLEETSIM_VDA5050_INTERFACE"],
        manufacturer=os.environ["FLEETSIM_VDA5050_MANUFACTURER"],
        version=os.environ["FLEETSIM_VDA5050_VERSION"],
    )
    stopped.wait()
    master.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
