"""A minimal VDA 5050 master control: an independent fleet manager on paho-mqtt and networkx alone (none of
fleetsim's code), to drive fleetsim's VDA 5050 vehicles (``--planner 'vda5050:...,exec=python THIS'``).

What it does:

- It reads the map from ``<interface>/fleetsim/site``, the tasks from ``<interface>/fleetsim/transportOrders/+``
  and each vehicle's ``state``.
- Each OPEN task is routed by shortest path over *directed edge states*: an edge may follow another only as
  the site's ``next`` says, and a vehicle that cannot turn in place takes no ``turn_in_place`` joint. Such a
  vehicle changes between nose first and backing at an ``opposite`` joint (a cusp), so its search also carries
  whether it backs, and its order gives every edge its orientation (0 nose first, pi backing); another
  vehicle's order gives one only on the goal edge, when the task has a ``goalProgress``. The route ends with
  a goal edge: the task is done when the vehicle drives onto it.
- The route is sent as one order whose base is only as far as the vehicle may go now, the rest horizon;
  order updates (same orderId, orderUpdateId + 1, from the stitching node) release more as the vehicle
  advances and locks free up.

The reservation rule: a vehicle has at most :data:`AHEAD` released edges ahead of the node it last passed;
it holds the edge it is on and every edge of its released base it has not driven (standing still, the edge
it stands on). An edge is released only when it conflicts with no edge another vehicle holds: fleetsim's
reservation check is geometric, so two edges conflict when they meet at a node or come closer than
:data:`CLEARANCE` (taken between the straight lines from node to node).

Deadlock avoidance, the simple fallback: routes are costed so that a vehicle keeps off edges another means
to drive the other way (:data:`HEAD_ON`: its remaining route, or its next task's plain shortest route), off
nodes where a vehicle without an order stands (:data:`OCCUPIED`) and, for a higher serial number, off the
rest of a lower one's route (:data:`YIELD`); a turn-in-place vehicle's horizon is re-routed at every update.
And a vehicle of a higher serial number that has reached an edge clear of a lower one's remaining route
releases nothing beyond it that is not clear too: it waits out of the way (in a passing bay) until the
lower one has passed. The lower serial number goes first.
"""

from __future__ import annotations

import json
import math
import os
import signal
import sys
import threading
from dataclasses import dataclass, field
from datetime import datetime, timezone
from typing import Any
from urllib.parse import urlsplit

import networkx as nx
from paho.mqtt.client import Client, MQTTMessage, MQTTv311
from paho.mqtt.enums import CallbackAPIVersion

AHEAD = 2  # released edges a vehicle may have ahead of the last node it passed
OCCUPIED = 1000.0  # extra cost of a node where another vehicle stands without an order
CLEARANCE = 1.6  # metres: edges closer than this conflict (two vehicles on them could touch)
YIELD = 50.0
HEAD_ON = 200.0  # extra cost of an edge another vehicle means to drive the other way  # extra cost, for a higher serial number, of a node on a lower one's remaining route

EdgeKey = tuple[str, str]  # (edgeId, startNodeId): one direction of an edge
SearchState = tuple[EdgeKey, bool]  # the edge and whether the vehicle backs along it


@dataclass
class Leg:
    """One edge of a route: the edge, its nodes, and the orientation to send (None: leave it out)."""

    edge_id: str
    start: str
    end: str
    orientation: float | None


@dataclass
class Job:
    """A vehicle's current order: its route, how many edges are released, and the updates sent."""

    task_id: str
    order_id: str
    start: str
    legs: list[Leg]
    released: int = 0
    update_id: int = -1
    goal_edges: frozenset[str] = frozenset()
    goal_progress: str | None = None


@dataclass
class Vehicle:
    serial: str
    turn_in_place: bool
    start_edge: EdgeKey
    standing: EdgeKey  # the edge it stands on once its base is driven
    orders: int = 0
    backing: bool = False  # the progress at the end of the last order sent
    job: Job | None = None
    done: set[str] = field(default_factory=set)


class MasterControl:
    """Connects to the broker at ``host:port`` and drives the vehicles of ``interface``/``manufacturer``."""

    def __init__(self, host: str, port: int, interface: str, manufacturer: str, version: str) -> None:
        self.interface, self.manufacturer, self.version = interface, manufacturer, version
        self.edges: dict[EdgeKey, dict[str, Any]] = {}
        self.conflicts: dict[str, set[str]] = {}
        self.vehicles: dict[str, Vehicle] = {}
        self.states: dict[str, dict[str, Any]] = {}
        self.tasks: dict[str, dict[str, Any]] = {}
        self.headers = 0
        self.lock = threading.RLock()
        self.client = Client(
            callback_api_version=CallbackAPIVersion.VERSION2, client_id="example-master-control", protocol=MQTTv311
        )
        user = os.environ.get("FLEETSIM_MQTT_USERNAME")
        if user:
            self.client.username_pw_set(user, os.environ.get("FLEETSIM_MQTT_PASSWORD"))
        self.client.on_message = self._on_message
        # fleetsim's master/connection: ONLINE while it runs, OFFLINE when it stops, CONNECTIONBROKEN (its
        # last will, sent by the broker) when it crashes: fleetsim then fails the run, naming it.
        self.presence = f"{interface}/fleetsim/master/connection"
        self.client.will_set(self.presence, self._connection("CONNECTIONBROKEN"), qos=1, retain=True)
        self.client.connect(host, port)
        self.client.publish(self.presence, self._connection("ONLINE"), qos=1, retain=True)
        self.client.subscribe(
            [
                (f"{interface}/fleetsim/site", 1),
                (f"{interface}/fleetsim/transportOrders/+", 1),
                (f"{interface}/v2/{manufacturer}/+/state", 0),
            ]
        )
        self.client.loop_start()

    def close(self) -> None:
        self.client.publish(self.presence, self._connection("OFFLINE"), qos=1, retain=True).wait_for_publish(5.0)
        self.client.loop_stop()
        self.client.disconnect()

    def _connection(self, state: str) -> bytes:
        message = {
            "headerId": 0,
            "timestamp": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-4] + "Z",
            "version": self.version,
            "manufacturer": self.manufacturer,
            "serialNumber": "example-master-control",
            "connectionState": state,
        }
        return json.dumps(message).encode()

    # -- input --------------------------------------------------------------------------------------

    def _on_message(self, client: Client, userdata: Any, message: MQTTMessage) -> None:
        try:
            document = json.loads(message.payload)
        except ValueError:
            print(f"master control: {message.topic}: not JSON, ignored", file=sys.stderr)
            return
        with self.lock:
            if message.topic.endswith("/fleetsim/site"):
                self._read_site(document)
            elif "/transportOrders/" in message.topic:
                if "taskId" in document:  # a transport order to claim (docs/vda5050.md) is not its business
                    self.tasks[document["taskId"]] = document
            else:
                self.states[document["serialNumber"]] = document
            if self.vehicles:
                self._dispatch()

    def _read_site(self, site: dict[str, Any]) -> None:
        self.edges = {(e["edgeId"], e["startNodeId"]): e for e in site["edges"]}
        places = {n["nodeId"]: (float(n["x"]), float(n["y"])) for n in site["nodes"]}
        lines = {e["edgeId"]: (places[e["startNodeId"]], places[e["endNodeId"]]) for e in site["edges"]}
        self.conflicts = {
            a: {b for b, other in lines.items() if _distance(line, other) < CLEARANCE} for a, line in lines.items()
        }
        for v in site["vehicles"]:
            key = (v["startEdgeId"], v["startNodeId"])
            self.vehicles.setdefault(v["serialNumber"], Vehicle(v["serialNumber"], v["turnInPlace"], key, key))

    # -- dispatching ---------------------------------------------------------------------------------

    def _dispatch(self) -> None:
        for serial in sorted(self.vehicles, key=_serial_order):
            vehicle = self.vehicles[serial]
            state = self.states.get(serial)
            if state is None:
                continue
            job = vehicle.job
            if job is not None and self._finished(vehicle, job, state):
                vehicle.job = None
                job = None
            if job is None:
                task = self._next_task(vehicle, state)
                if task is None:
                    continue
                job = self._plan(vehicle, task)
                if job is None:
                    continue
                vehicle.job = job
            self._release(vehicle, job, state)

    def _finished(self, vehicle: Vehicle, job: Job, state: dict[str, Any]) -> bool:
        task = self.tasks.get(job.task_id)
        finished = task is not None and task["state"] == "FINISHED"
        if finished:
            vehicle.done.add(job.task_id)
        # A new order only once the vehicle has no base left.
        return finished and not state.get("nodeStates") and not state.get("edgeStates")

    def _next_task(self, vehicle: Vehicle, state: dict[str, Any]) -> dict[str, Any] | None:
        if vehicle.orders > 0 and (state.get("nodeStates") or state.get("edgeStates")):
            return None
        open_tasks = [
            t
            for t in self.tasks.values()
            if t["state"] == "OPEN" and t["serialNumber"] == vehicle.serial and t["taskId"] not in vehicle.done
        ]
        return min(open_tasks, key=lambda t: _serial_order(t["taskId"]), default=None)

    def _plan(self, vehicle: Vehicle, task: dict[str, Any]) -> Job | None:
        if vehicle.orders == 0:  # it stands on its start edge: the order begins with it
            start: SearchState = (vehicle.start_edge, vehicle.backing)
            start_node = vehicle.start_edge[1]
            legs = self._route(vehicle, start, task, begin=True)
        else:
            start_node = self.edges[vehicle.standing]["endNodeId"]  # its lastNodeId, once the base is driven
            legs = self._route(vehicle, (vehicle.standing, vehicle.backing), task, begin=False)
        if not legs:
            print(f"master control: task {task['taskId']}: no route for vehicle {vehicle.serial}", file=sys.stderr)
            vehicle.done.add(task["taskId"])
            return None
        vehicle.orders += 1
        return Job(
            task["taskId"],
            f"order-{vehicle.serial}-{vehicle.orders}",
            start_node,
            legs,
            goal_edges=frozenset(task["goalEdgeIds"]),
            goal_progress=task.get("goalProgress"),
        )

    # -- routing -------------------------------------------------------------------------------------

    def _route(
        self,
        vehicle: Vehicle,
        first: SearchState,
        task: dict[str, Any],
        *,
        begin: bool,
        plain: bool = False,
    ) -> list[Leg] | None:
        """The cheapest legs onto a goal edge from ``first``: beginning with it (``begin``: the edge it
        stands on at its start) or with what may follow it (the edge it stands on after an order)."""
        goals = set(task["goalEdgeIds"])
        want = task.get("goalProgress")
        costs, head_on = ({}, set()) if plain else self._costs(vehicle)
        graph: nx.DiGraph[Any] = nx.DiGraph()
        source, sink = "source", "sink"
        for key, edge in self.edges.items():
            for backing in (False, True):
                here: SearchState = (key, backing)
                for nxt in edge["next"]:
                    if nxt["joint"] == "turn_in_place" and not vehicle.turn_in_place:
                        continue
                    after = (nxt["edgeId"], edge["endNodeId"])
                    if after not in self.edges:
                        continue
                    flips = nxt["joint"] == "opposite" and not vehicle.turn_in_place
                    there: SearchState = (after, backing != flips)
                    weight = self._weight(after, costs, head_on)
                    graph.add_edge(here, there, weight=weight)
                if key[0] in goals and (want is None or vehicle.turn_in_place or backing == (want == "reverse")):
                    graph.add_edge(here, sink, weight=0.0)
        if begin:
            graph.add_edge(source, first, weight=0.0)
        elif first in graph:
            for after in list(graph.successors(first)):
                if after != sink:
                    graph.add_edge(source, after, weight=graph.edges[first, after]["weight"])
        try:
            path = nx.shortest_path(graph, source, sink, weight="weight")
        except (nx.NetworkXNoPath, nx.NodeNotFound):
            return None
        legs = []
        for index, (key, backing) in enumerate(path[1:-1]):
            edge = self.edges[key]
            last = index == len(path) - 3
            orientation: float | None = None
            if not vehicle.turn_in_place:
                orientation = math.pi if backing else 0.0
            elif last and want is not None:
                orientation = math.pi if want == "reverse" else 0.0
            legs.append(Leg(key[0], key[1], edge["endNodeId"], orientation))
        vehicle.backing = path[-2][1] if not vehicle.turn_in_place else False
        return legs

    def _weight(self, key: EdgeKey, costs: dict[str, float], head_on: set[EdgeKey]) -> float:
        edge = self.edges[key]
        return float(edge["length"]) + costs.get(edge["endNodeId"], 0.0) + (HEAD_ON if key in head_on else 0.0)

    def _costs(self, vehicle: Vehicle) -> tuple[dict[str, float], set[EdgeKey]]:
        """Extra costs of nodes others hold or (lower serial numbers) still drive to, and the edges others
        mean to drive the other way (head-on, where neither could pass)."""
        costs: dict[str, float] = {}
        head_on: set[EdgeKey] = set()
        for other in self.vehicles.values():
            if other.serial == vehicle.serial:
                continue
            for edge_id in self._holds(other) if other.job is None else ():
                for key, edge in self.edges.items():
                    if key[0] == edge_id:
                        costs[edge["endNodeId"]] = costs.get(edge["endNodeId"], 0.0) + OCCUPIED
            if _serial_order(other.serial) < _serial_order(vehicle.serial) and other.job is not None:
                passed = self._passed(other, other.job)
                for leg in other.job.legs[passed:]:
                    costs[leg.end] = costs.get(leg.end, 0.0) + YIELD
            head_on |= {(leg.edge_id, leg.end) for leg in self._intended(other)}
        return costs, head_on

    def _intended(self, vehicle: Vehicle) -> list[Leg]:
        """The legs the vehicle is still to drive: its job's, or else its next task's plain shortest route."""
        job = vehicle.job
        if job is not None:
            return job.legs[max(self._passed(vehicle, job) - 1, 0) :]
        state = self.states.get(vehicle.serial)
        if state is None:
            return []
        task = self._next_task(vehicle, state)
        if task is None:
            return []
        backing = vehicle.backing
        if vehicle.orders == 0:
            legs = self._route(vehicle, (vehicle.start_edge, vehicle.backing), task, begin=True, plain=True)
        else:
            legs = self._route(vehicle, (vehicle.standing, vehicle.backing), task, begin=False, plain=True)
        vehicle.backing = backing
        return legs or []

    # -- reservations --------------------------------------------------------------------------------

    def _passed(self, vehicle: Vehicle, job: Job) -> int:
        """The index in the job's nodes of the last node the vehicle passed (0 before the order runs)."""
        state = self.states.get(vehicle.serial)
        if state is None or state.get("orderId") != job.order_id:
            return 0
        passed = int(state.get("lastNodeSequenceId", 0)) // 2
        nodes = [job.start, *(leg.end for leg in job.legs)]
        # The node named must be this order's own (VDA 5050 §6.10.6: the current order's ids); else none is passed.
        return passed if passed < len(nodes) and nodes[passed] == state.get("lastNodeId") else 0

    def _holds(self, vehicle: Vehicle) -> list[str]:
        """The edges the vehicle stands on or may drive without asking again, in order."""
        job = vehicle.job
        if job is None or job.released == 0:
            return [vehicle.standing[0]]
        passed = self._passed(vehicle, job)
        held = [leg.edge_id for leg in job.legs[max(passed - 1, 0) : job.released]]
        return [vehicle.standing[0], *held] if passed == 0 else held

    def _remaining(self, vehicle: Vehicle) -> list[str]:
        """The edges the vehicle holds and those it is still to drive."""
        job = vehicle.job
        if job is None or job.released == 0:
            return (
                [vehicle.standing[0], *(leg.edge_id for leg in job.legs)] if job is not None else [vehicle.standing[0]]
            )
        return [*self._holds(vehicle), *(leg.edge_id for leg in job.legs[job.released :])]

    def _clashes(self, edge_id: str, edges: set[str]) -> bool:
        return bool(self.conflicts.get(edge_id, {edge_id}) & edges)

    def _may_release(self, vehicle: Vehicle, job: Job, index: int, current: int) -> bool:
        edge_id = job.legs[index].edge_id
        for other in self.vehicles.values():
            if other.serial == vehicle.serial:
                continue
            if self._clashes(edge_id, set(self._holds(other))):
                return False
            if _serial_order(other.serial) < _serial_order(vehicle.serial):
                # Yield to a lower serial number: out of its way, wait for it to pass.
                way = set(self._remaining(other))
                if self._clashes(edge_id, way) and any(
                    not self._clashes(job.legs[k].edge_id, way) for k in range(current, index)
                ):
                    return False
        return True

    def _release(self, vehicle: Vehicle, job: Job, state: dict[str, Any]) -> None:
        passed = self._passed(vehicle, job) if job.released else 0
        current = max(passed - 1, 0)
        target = job.released
        while target < len(job.legs) and target < passed + AHEAD and self._may_release(vehicle, job, target, current):
            target += 1
        if job.update_id >= 0 and target == job.released:
            return
        if target == 0:
            return  # nothing may be released yet: send nothing (the order would have an empty base)
        if job.update_id >= 0:
            # Re-route the horizon from the last node the new base ends at: others may have moved.
            self._reroute(vehicle, job, target)
        first = 0 if job.update_id < 0 else job.released
        job.update_id += 1
        self._send(vehicle, job, first, target)
        job.released = target
        if target == len(job.legs):
            vehicle.standing = (job.legs[-1].edge_id, job.legs[-1].start)

    def _reroute(self, vehicle: Vehicle, job: Job, target: int) -> None:
        if vehicle.turn_in_place is False:
            return  # its progress is bound to the route: keep it
        task = self.tasks.get(job.task_id)
        if task is None or job.legs[target - 1].edge_id in job.goal_edges:
            return
        backing = vehicle.backing  # always nose first: it turns in place
        last = job.legs[target - 1]
        rest = self._route(vehicle, ((last.edge_id, last.start), backing), task, begin=False)
        vehicle.backing = backing
        if rest:
            job.legs = job.legs[:target] + rest

    # -- output --------------------------------------------------------------------------------------

    def _send(self, vehicle: Vehicle, job: Job, first: int, released: int) -> None:
        """The job's route from node ``first`` on, the first ``released`` edges base."""
        nodes = [job.start, *(leg.end for leg in job.legs)]
        now = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%f")[:-4] + "Z"
        edges = []
        for k in range(first, len(job.legs)):
            leg = job.legs[k]
            entry: dict[str, Any] = {
                "edgeId": leg.edge_id,
                "sequenceId": 2 * k + 1,
                "released": k < released,
                "startNodeId": leg.start,
                "endNodeId": leg.end,
                "actions": [],
            }
            if leg.orientation is not None:
                entry["orientation"] = leg.orientation
            edges.append(entry)
        order = {
            "headerId": self.headers,
            "timestamp": now,
            "version": self.version,
            "manufacturer": self.manufacturer,
            "serialNumber": vehicle.serial,
            "orderId": job.order_id,
            "orderUpdateId": job.update_id,
            "nodes": [
                {"nodeId": nodes[k], "sequenceId": 2 * k, "released": k <= released, "actions": []}
                for k in range(first, len(nodes))
            ],
            "edges": edges,
        }
        self.headers += 1
        topic = f"{self.interface}/v2/{self.manufacturer}/{vehicle.serial}/order"
        self.client.publish(topic, json.dumps(order).encode(), qos=0)


def _distance(
    a: tuple[tuple[float, float], tuple[float, float]], b: tuple[tuple[float, float], tuple[float, float]]
) -> float:
    """The least distance between two straight lines from point to point."""
    if _crosses(a, b):
        return 0.0
    return min(_to_line(a[0], b), _to_line(a[1], b), _to_line(b[0], a), _to_line(b[1], a))


def _to_line(p: tuple[float, float], line: tuple[tuple[float, float], tuple[float, float]]) -> float:
    (ax, ay), (bx, by) = line
    dx, dy = bx - ax, by - ay
    span = dx * dx + dy * dy
    t = 0.0 if span == 0.0 else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / span))
    return math.hypot(p[0] - ax - t * dx, p[1] - ay - t * dy)


def _crosses(
    a: tuple[tuple[float, float], tuple[float, float]], b: tuple[tuple[float, float], tuple[float, float]]
) -> bool:
    def side(p: tuple[float, float], q: tuple[float, float], r: tuple[float, float]) -> float:
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    return side(*a, b[0]) * side(*a, b[1]) < 0 and side(*b, a[0]) * side(*b, a[1]) < 0


def _serial_order(name: str) -> tuple[int, str]:
    return (int(name), name) if name.isdigit() else (sys.maxsize, name)


def main() -> int:
    """Run until SIGTERM, the broker and topics from the environment fleetsim's ``exec=`` gives."""
    missing = [
        n
        for n in ("FLEETSIM_MQTT_URL", "FLEETSIM_VDA5050_INTERFACE", "FLEETSIM_VDA5050_MANUFACTURER")
        if n not in os.environ
    ]
    if missing:
        print(f"master control: {', '.join(missing)} not set (start it with fleetsim's exec=)", file=sys.stderr)
        return 2
    url = urlsplit(os.environ["FLEETSIM_MQTT_URL"])
    if url.scheme != "mqtt":
        print(f"master control: FLEETSIM_MQTT_URL {url.geturl()!r} is not mqtt://host:port", file=sys.stderr)
        return 2
    stopped = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stopped.set())
    master = MasterControl(
        url.hostname or "127.0.0.1",
        url.port or 1883,
        os.environ["FLEETSIM_VDA5050_INTERFACE"],
        os.environ["FLEETSIM_VDA5050_MANUFACTURER"],
        os.environ.get("FLEETSIM_VDA5050_VERSION", "2.0.0"),
    )
    stopped.wait()
    master.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
