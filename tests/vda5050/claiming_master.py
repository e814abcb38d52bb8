"""A master control that dispatches, for the tests, on paho-mqtt and networkx alone (none of fleetsim's code):
it reads the transport orders fleetsim publishes on ``<interface>/fleetsim/transportOrders/<orderId>``,
claims each released order, oldest first, for the nearest idle vehicle (by the length of the shortest path
from where the vehicle will stand to the order's first stop), and once fleetsim tells it the order is
assigned to that vehicle, sends the vehicle one order through every stop. Or, scripted, it sends the claims
it is given and nothing else."""

from __future__ import annotations

import itertools
import json
from collections.abc import Sequence
from typing import Any
from urllib.parse import quote

import networkx as nx
from paho.mqtt.client import Client, MQTTMessage
from scripted_master import ScriptedMaster


class ClaimingMaster(ScriptedMaster):
    """``claims``: None dispatches as the module docstring says; a sequence of (order id, payload) sends
    those claims (a payload dict is sent as JSON, bytes as they are) once the first order is seen, and
    nothing else."""

    def __init__(
        self, host: str, port: int, *, claims: Sequence[tuple[str, dict[str, Any] | bytes]] | None = None, **kw: Any
    ) -> None:
        self.orders: dict[str, dict[str, Any]] = {}  # each order's latest message, in the order first seen
        self.seen: list[dict[str, Any]] = []  # every message on a transportOrders topic, in arrival order
        self.script = list(claims) if claims is not None else None
        self.claimed: dict[str, str] = {}  # order id -> the serial number it was claimed for
        self.serving: dict[str, str] = {}  # serial number -> the order it serves (claimed, not completed)
        self.ends: dict[str, str] = {}  # serial number -> the node its last order ends at
        self.routed: set[str] = set()
        super().__init__(host, port, **kw)

    def _on_message(self, client: Client, userdata: Any, message: MQTTMessage) -> None:
        name = message.topic.rsplit("/", 1)[-1]
        if name in ("order", "instantActions", "claim", "connection") or message.topic.endswith("/factsheet"):
            return
        document = json.loads(message.payload)
        with self.lock:
            if message.topic.endswith("/fleetsim/site"):
                self.site = document
            elif "/transportOrders/" in message.topic:
                self.seen.append(document)
                self.orders[document["orderId"]] = document
            elif name == "state":
                self.states[document["serialNumber"]] = document
                self.history.append(document)
            self._act()

    def claim(self, order_id: str, payload: dict[str, Any] | bytes) -> None:
        data = payload if isinstance(payload, bytes) else json.dumps(payload).encode()
        self.client.publish(f"{self.interface}/fleetsim/transportOrders/{quote(order_id, safe='')}/claim", data, qos=1)

    def _act(self) -> None:
        if self.site is None:
            return
        if self.script is not None:
            if self.orders and self.script:
                for order_id, payload in self.script:
                    self.claim(order_id, payload)
                self.script = []
            return
        for order_id, order in self.orders.items():
            serial = order.get("serialNumber")
            if order["state"] == "COMPLETED" and self.serving.get(serial or "") == order_id:
                del self.serving[serial or ""]
            if order["state"] == "ASSIGNED" and serial == self.claimed.get(order_id) and order_id not in self.routed:
                self.routed.add(order_id)
                self._send(serial, self._route(serial, order))
        for order_id, order in self.orders.items():
            if order["state"] == "RELEASED" and order_id not in self.claimed:
                idle = [v["serialNumber"] for v in self.site["vehicles"] if v["serialNumber"] not in self.serving]
                if not idle:
                    return
                first = order["stops"][0]["goalEdgeIds"]
                serial = min(idle, key=lambda s: (self._plan(s, [first])[0], int(s)))
                self.claimed[order_id] = serial
                self.serving[serial] = order_id
                self.claim(order_id, {"serialNumber": serial})

    # -- routing ------------------------------------------------------------------------------------

    def _graph(self) -> nx.DiGraph:
        assert self.site is not None
        graph = nx.DiGraph()
        for edge in self.site["edges"]:
            graph.add_edge(edge["startNodeId"], edge["endNodeId"], edgeId=edge["edgeId"], weight=edge["length"])
        return graph

    def _start(self, serial: str) -> tuple[list[str], list[str]]:
        """The nodes and edges an order for ``serial`` begins with: its start edge until its first order,
        then the node its last order ended at."""
        assert self.site is not None
        if serial in self.ends:
            return [self.ends[serial]], []
        vehicle = next(v for v in self.site["vehicles"] if v["serialNumber"] == serial)
        edge = next(
            e
            for e in self.site["edges"]
            if e["edgeId"] == vehicle["startEdgeId"] and e["startNodeId"] == vehicle["startNodeId"]
        )
        return [edge["startNodeId"], edge["endNodeId"]], [edge["edgeId"]]

    def _plan(self, serial: str, stops: list[list[str]]) -> tuple[float, list[str], list[str]]:
        """The cost, nodes and edges of the shortest route from where ``serial`` will stand through a goal
        edge of each stop in turn."""
        assert self.site is not None
        graph = self._graph()
        path, edges = self._start(serial)
        cost = 0.0
        for goal_edges in stops:
            best: tuple[float, list[str], dict[str, Any]] | None = None
            for goal in (e for e in self.site["edges"] if e["edgeId"] in goal_edges):
                try:
                    lead = nx.shortest_path(graph, path[-1], goal["startNodeId"], weight="weight")
                except nx.NetworkXNoPath:
                    continue
                length = nx.path_weight(graph, lead, "weight") + goal["length"]
                if best is None or length < best[0]:
                    best = (length, lead, goal)
            if best is None:
                return float("inf"), path, edges
            length, lead, goal = best
            cost += length
            for a, b in itertools.pairwise(lead):
                path.append(b)
                edges.append(graph.edges[a, b]["edgeId"])
            path.append(goal["endNodeId"])
            edges.append(goal["edgeId"])
        return cost, path, edges

    def _route(self, serial: str, order: dict[str, Any]) -> dict[str, Any]:
        _, path, edges = self._plan(serial, [stop["goalEdgeIds"] for stop in order["stops"]])
        self.ends[serial] = path[-1]
        return self._order_message(serial, path, edges)
