"""The scenario's vehicles as VDA 5050 vehicles on an MQTT broker: the planner a master control drives.

:class:`Vda5050Fleet` is a planner (SPEC §6) that plans nothing itself. Each vehicle is an MQTT client of
its own (``interfaceName/v2/manufacturer/serialNumber/...``, the serial number being the vehicle id) that
publishes ``connection`` (ONLINE, OFFLINE at the end, CONNECTIONBROKEN as its last will), ``factsheet``,
``state`` and ``visualization``, and takes ``order`` and ``instantActions``. Every step begins
(:meth:`begin_step`) with pacing the run at ``speed`` times real time, taking in what arrived, and
telling the master control where the fleet is; an order that makes a plan is handed to the harness at
the vehicle's next planner call, where fleetsim's checks judge it as any planner's. A vehicle moves only
along released base: until its first order is accepted it stands on its start edge (:meth:`awaiting_plan`).

Instant actions: ``stateRequest`` and ``factsheetRequest`` answer at once; ``startPause`` and
``stopPause`` hold a vehicle still and let it go (it brakes within its fixed legs); ``cancelOrder``
drops the horizon and finishes once the vehicle stands at the end of its base (a fixed leg is a
commitment fleetsim never takes back, so the base is driven to its end); ``initPosition`` fails (a
simulated vehicle stands where its scenario puts it), and so does an action of any other type, each
with an error in the state. Actions on an order's nodes and edges are not carried out: each ends FAILED
with an error, and the order is driven.

Beside the standard's topics, two of fleetsim's own under ``interfaceName/fleetsim/`` hand the master
control what a warehouse system and a map server would: ``site`` (retained: the nodes and edges of the
map, :mod:`.places`) and ``transportOrders/<taskId>`` (retained: each task when it becomes its vehicle's
next one, and again when it is done); fleetsim reads a third, ``master/connection``, where a master
control may tell its own presence as a vehicle does (its last will CONNECTIONBROKEN fails the run).
A run that ends stuck asks :meth:`Vda5050Fleet.explain_wait` which order each waiting vehicle waits for.

In a run with transport orders and no other dispatcher, the fleet is the dispatcher too (``dispatch``,
with the hooks ``wants_call`` and ``refused``): the master control sees the orders on
``transportOrders/<orderId>`` and claims them for its vehicles (:mod:`.transport`).
"""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from datetime import datetime, timedelta, timezone
from typing import Any

from fleetsim.dispatch.protocol import Assignment, OrderBoard
from fleetsim.enums import Disturbed, Progress, TurnCapability
from fleetsim.errors import MasterControlError
from fleetsim.layout.layout import Layout
from fleetsim.planning.checks import CheckContext, Rejection, RejectionCode, check_plans
from fleetsim.planning.plans import FleetLeg, FleetPlan, Response
from fleetsim.planning.snapshot import FleetSnapshot, VehicleState
from fleetsim.scenario import Task
from fleetsim.sim.result import Pacing
from fleetsim.vda5050.broker import BrokerAddress, EmbeddedBroker
from fleetsim.vda5050.link import MqttLink, Will
from fleetsim.vda5050.master import MasterProcess
from fleetsim.vda5050.messages import (
    MessageInvalid,
    decode_connection,
    decode_instant_actions,
    decode_order,
    encode,
    topic,
)
from fleetsim.vda5050.model import VERSIONS, Action, Edge, ErrorReference, Node, VdaError
from fleetsim.vda5050.orders import Join, OrderStatus, join_order, read_order, vda_error
from fleetsim.vda5050.places import SiteGraph, site_graph
from fleetsim.vda5050.state_model import (
    ActionState,
    ActionStatus,
    AgvAction,
    AgvGeometry,
    AgvPosition,
    BatteryState,
    Connection,
    ConnectionState,
    EdgeState,
    Envelope2d,
    EStop,
    Factsheet,
    InfoLevel,
    Information,
    NodeState,
    OperatingMode,
    PhysicalParameters,
    PolygonPoint,
    ProtocolFeatures,
    ProtocolLimits,
    SafetyState,
    State,
    Timing,
    TypeSpecification,
    Velocity,
    Visualization,
)
from fleetsim.vda5050.transport import TransportOrders, goal_places

__all__ = ["Vda5050Fleet", "Vda5050Settings"]

ARRIVED = 1e-6  # metres short of a leg's end that count as at its exit node
STILL = 1e-6  # metres per second below which a vehicle stands


@dataclass(frozen=True, slots=True)
class Vda5050Settings:
    """How the vehicles speak: protocol ``version`` (``"2.0"`` or ``"2.1"``), topic names, the broker
    (None: an embedded one on a free loopback port), pacing (``speed`` times real time), and how often a
    state and a visualization go out when nothing changed (simulated seconds)."""

    version: str = "2.0"
    interface_name: str = "uagv"
    manufacturer: str = "fleetsim"
    broker: BrokerAddress | None = None
    speed: float = 1.0
    state_interval: float = 5.0
    visualization_interval: float = 1.0
    connect_timeout: float = 10.0
    start_timeout: float = 30.0  # wall seconds the run waits at t = 0 for the master control's first message


@dataclass
class _Leg:
    """A leg of the vehicle's plan and the order's edge and end node it came from (None: not from an order)."""

    leg: FleetLeg
    edge: Edge | None
    end: Node | None


@dataclass
class _Vehicle:
    vehicle_id: int
    serial: str
    link: MqttLink
    status: OrderStatus = field(default_factory=OrderStatus)
    path: list[_Leg] = field(default_factory=list)  # aligned with the plan in force
    pending: FleetPlan | None = None  # an order's plan, for the next planner call
    pending_path: list[_Leg] | None = None
    pending_status: OrderStatus | None = None
    pending_last: tuple[str, int] | None = None  # a new order's first node: its last node once accepted
    handed: FleetPlan | None = None  # handed to the harness, its verdict not seen yet
    errors: list[VdaError] = field(default_factory=list)
    last_node: tuple[str, int] = ("", 0)
    headers: dict[str, int] = field(default_factory=dict)
    published: tuple[Any, ...] | None = None
    next_state: float = 0.0
    next_visualization: float = 0.0
    announced: set[int] = field(default_factory=set)  # tasks published to the master control
    actions: dict[str, ActionState] = field(default_factory=dict)  # by actionId, in arrival order
    paused: bool = False
    cancelling: str | None = None  # the actionId of a cancelOrder until the base is driven
    heard: float | None = None  # the simulated time of the master control's last message to it


class Vda5050Fleet:
    """The planner a VDA 5050 master control drives (see the module docstring). A fresh instance serves
    one run; :meth:`close` ends it (OFFLINE, disconnect, the embedded broker stopped)."""

    def __init__(self, settings: Vda5050Settings | None = None, *, master_command: Sequence[str] | None = None) -> None:
        self.settings = settings or Vda5050Settings()
        self.paced = self.settings.speed  # the run goes on a wall clock (RunResult.paced): its hash is not gated
        self.master_command = tuple(master_command) if master_command is not None else None
        self.master: MasterProcess | None = None
        self.broker: EmbeddedBroker | None = None
        self.address: BrokerAddress | None = self.settings.broker
        self.vehicles: dict[int, _Vehicle] = {}
        self.graph: SiteGraph | None = None  # the map's nodes and edges, from the first step on
        self.epoch = datetime.now(timezone.utc)
        self.started = 0.0  # time.monotonic() when the paced run began (after the master control spoke)
        self.finished = 0.0  # time.monotonic() when it ended
        self.latencies: list[float] = []  # seconds from an order's arrival to its plan's verdict
        self.lag = 0.0  # the most wall seconds a step began behind its paced time (0: the pace was kept)
        self.late_steps = 0  # steps that began more than one step's wall time behind
        self._arrived: dict[int, float] = {}
        self._site_link: MqttLink | None = None
        self.master_name = ""  # the serialNumber a master control announced on master/connection
        self.master_left = ""  # how and when it went OFFLINE with no task queued (the run may go on)
        self.dispatching = False  # the run's dispatcher too: the loop has asked wants_call() or dispatch()
        self.transport: TransportOrders | None = None  # the orders on the broker, once started (dispatching)
        self._first_board: OrderBoard | None = None  # a board shown before the start, published at it

    @property
    def site(self) -> SiteGraph:
        """The map's nodes and edges (made at the first step, when the layout is known)."""
        if self.graph is None:
            msg = "the VDA 5050 vehicles have not started: their first step has not begun"
            raise RuntimeError(msg)
        return self.graph

    # -- the planner protocol ------------------------------------------------------------------------

    def begin_step(self, fleet: FleetSnapshot, layout: Layout) -> Sequence[Rejection]:
        if self.graph is None:
            self._start(fleet, layout)
            self._await_master(fleet)
        self._pace(fleet.time)
        self._check_master(fleet)
        refused: list[Rejection] = []
        for vehicle in self.vehicles.values():
            self._verdict(vehicle, fleet)
            self._follow(vehicle, fleet)
            found = self._intake(vehicle, fleet, layout)
            if found:  # one rejection per vehicle and step, however many messages a flood brought
                more = f" (and {len(found) - 1} more refused messages this step)" if len(found) > 1 else ""
                refused.append(replace(found[0], message=found[0].message + more))
            self._announce(vehicle, fleet)
            self._report(vehicle, fleet)
        if self.transport is not None:
            self.transport.observe(fleet.tasks)
        return refused

    def pacing(self) -> Pacing:
        """How the run kept its pace and how soon orders took effect, for the run's result."""
        return Pacing(self.settings.speed, self.lag, self.late_steps, tuple(self.latencies))

    def paused(self) -> set[int]:
        """The vehicles a ``startPause`` holds still (the harness brakes them)."""
        return {vid for vid, vehicle in self.vehicles.items() if vehicle.paused}

    def awaiting_plan(self) -> set[int]:
        """The vehicles that have had no order: a VDA 5050 vehicle moves only along released base, so each
        stands on its start edge until an order's plan is accepted (the harness holds them still)."""
        return {vid for vid, vehicle in self.vehicles.items() if not vehicle.status.order_id}

    def explain_wait(self, vehicle_id: int, now: float) -> str:
        """For the stuck-fleet diagnosis, in VDA 5050's terms: which order the vehicle holds and what it
        waits for (an order update releasing its horizon, or a new order), when the master control last
        sent it anything, and whether it is paused or the master control is gone."""
        vehicle = self.vehicles.get(vehicle_id)
        if vehicle is None:
            return ""
        status = vehicle.status
        if not status.order_id:
            tasks = sorted(vehicle.announced)
            published = (
                f" (its task {tasks[0]} is on {self._own_topic(f'transportOrders/{tasks[0]}')})" if tasks else ""
            )
            parts = [f"VDA 5050: it has had no order{published}"]
        else:
            horizon = [e.edge.edge_id for e in vehicle.path if e.edge is not None and not e.edge.released]
            waits = (
                f"it waits for an order update releasing its horizon ({', '.join(horizon)})"
                if horizon
                else "its order has no horizon: it waits for an order update or a new order"
            )
            parts = [
                f"VDA 5050: order {status.order_id!r} (update {status.order_update_id}) is released up to node "
                f"{status.stitch_node_id!r} (sequence {status.stitch_sequence_id}); {waits}"
            ]
        if vehicle.heard is None:
            parts.append("the master control has sent it nothing")
        else:
            parts.append(f"the master control's last message to it came at t = {vehicle.heard:.1f} s")
        if vehicle.paused:
            parts.append("it is paused (startPause without stopPause)")
        if self.master_left:
            parts.append(self.master_left)
        return "; ".join(parts)

    # -- the dispatcher protocol: the master control claims orders (.transport) ----------------------

    def dispatch(self, board: OrderBoard, fleet: FleetSnapshot, layout: Layout) -> Sequence[Assignment]:
        """The next claim of the master control, as an answer (one a call), once what ``board`` shows has
        been published; before the vehicles start (the step's dispatch comes first), the board is kept."""
        self.dispatching = True
        if self.transport is None:
            self._first_board = board
            return []
        return self.transport.answer(board)

    def wants_call(self) -> bool:
        """Call me this step: a claim waits, or the orders' states have moved on (.transport)."""
        self.dispatching = True
        return self.transport is not None and self.transport.waiting()

    def refused(self, rejections: Sequence[Rejection]) -> None:
        """The claim just answered was refused: told back on the order's topic."""
        if self.transport is not None:
            self.transport.refuse(rejections)

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return self._hand(task.vehicle_id)

    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        return self._hand(task.vehicle_id)

    def close(self) -> None:
        self.finished = time.monotonic()  # the paced part ran from ``started`` to here
        for vehicle in self.vehicles.values():
            if vehicle.link.connected:
                self._publish(
                    vehicle, "connection", self._connection(vehicle, ConnectionState.OFFLINE), qos=1, retain=True
                )
                vehicle.link.disconnect()
        if self._site_link is not None and self._site_link.connected:
            self._site_link.disconnect()
        if self.transport is not None and self.transport.link.connected:
            self.transport.link.disconnect()
        if self.master is not None:
            self.master.stop()  # with everything it started
            self.master = None
        if self.broker is not None:
            self.broker.__exit__(None, None, None)
            self.broker = None

    # -- set-up -------------------------------------------------------------------------------------

    def _start(self, fleet: FleetSnapshot, layout: Layout) -> None:
        settings = self.settings
        if self.address is None:
            self.broker = EmbeddedBroker()
            self.address = self.broker.__enter__().address
        map_id = layout.source.stem if layout.source is not None else "fleetsim"
        self.graph = site_graph(layout, map_id=map_id)
        self._site_link = MqttLink(self.address, f"fleetsim-site-{id(self):x}")
        self._site_link.connect(settings.connect_timeout)
        self._site_link.subscribe(self._own_topic("master/connection"), qos=1)
        self._site_link.publish(self._own_topic("site"), self._site(fleet, layout), qos=1, retain=True)
        for vid in sorted(fleet.vehicles):
            serial = str(vid)
            broken = Connection(0, self._stamp(0.0), settings.manufacturer, serial, ConnectionState.CONNECTIONBROKEN)
            will = Will(self._topic(serial, "connection"), encode(broken, settings.version), qos=1, retain=True)
            link = MqttLink(self.address, f"fleetsim-{settings.manufacturer}-{serial}", will=will)
            vehicle = _Vehicle(vid, serial, link)
            link.connect(settings.connect_timeout)
            link.subscribe(self._topic(serial, "order"), self._topic(serial, "instantActions"), qos=0)
            plan = fleet.plans[vid]
            vehicle.path = [_Leg(leg, None, None) for leg in plan.legs]
            first = plan.legs[0]
            vehicle.last_node = (self.graph.entry_node(first.segment, first.traverse), 0)
            self.vehicles[vid] = vehicle
            self._publish(vehicle, "connection", self._connection(vehicle, ConnectionState.ONLINE), qos=1, retain=True)
            self._publish(vehicle, "factsheet", self._factsheet(vehicle, fleet), qos=1, retain=True)
        if self.dispatching:
            link = MqttLink(self.address, f"fleetsim-transport-{id(self):x}")
            link.connect(settings.connect_timeout)
            self.transport = TransportOrders(link, self._own_topic("transportOrders"), self.graph)
            self.transport.subscribe()
            if self._first_board is not None:
                self.transport.show(self._first_board)
                self._first_board = None
        print(
            f"fleetsim: {len(self.vehicles)} VDA 5050 {settings.version} vehicles on {self.address.url} "
            f"(topics {settings.interface_name}/v2/{settings.manufacturer}/<serialNumber>/..., "
            f"{settings.interface_name}/fleetsim/site and .../transportOrders/"
            + ("<orderId> (claims on .../<orderId>/claim))" if self.dispatching else "<taskId>)"),
            file=sys.stderr,
            flush=True,
        )
        if self.master_command is not None:
            self.master = self._start_master(self.master_command)
        self.started = time.monotonic()

    def _start_master(self, command: tuple[str, ...]) -> MasterProcess:
        """The master control as a child process in a session of its own, told where the broker is
        (``spec.ENVIRONMENT``)."""
        assert self.address is not None
        settings = self.settings
        environment = {
            "FLEETSIM_MQTT_URL": self.address.url,
            "FLEETSIM_VDA5050_INTERFACE": settings.interface_name,
            "FLEETSIM_VDA5050_MANUFACTURER": settings.manufacturer,
            "FLEETSIM_VDA5050_VERSION": VERSIONS[settings.version],
        }
        if self.address.username is not None:
            environment["FLEETSIM_MQTT_USERNAME"] = self.address.username
        if self.address.password is not None:
            environment["FLEETSIM_MQTT_PASSWORD"] = self.address.password
        return MasterProcess(command, environment)

    def _await_master(self, fleet: FleetSnapshot) -> None:
        """Hold the run at t = 0 until the master control sends its first message to any vehicle, telling it
        the vehicles' states once a second meanwhile (it may connect late); the run's clock starts then.
        A master control silent for ``start_timeout`` seconds fails the run, naming where it was awaited."""
        deadline = time.monotonic() + self.settings.start_timeout
        for vehicle in self.vehicles.values():
            self._announce(vehicle, fleet)  # the tasks it is to dispatch
        while not self._master_spoke():
            self._check_master(fleet)
            left = deadline - time.monotonic()
            if left <= 0:
                assert self.address is not None
                what = "sent no message to any vehicle"
                if self.transport is not None:  # with orders to claim, a claim or its presence will do
                    what += f", claimed no order and announced nothing on {self._own_topic('master/connection')}"
                msg = (
                    f"the master control {what} within {self.settings.start_timeout:g} s; the "
                    f"vehicles were ONLINE on {self.address.url} (uagv/v2/.../connection) and waited at t = 0"
                )
                raise MasterControlError(msg)
            for vehicle in self.vehicles.values():
                state = fleet.vehicles[vehicle.vehicle_id]
                self._publish(vehicle, "state", self._state(vehicle, state, 0.0))
            next(iter(self.vehicles.values())).link.wait(min(1.0, left))
        self.started = time.monotonic()

    def _master_spoke(self) -> bool:
        """A message to a vehicle waits; dispatching, a claim too, or the master control said ONLINE (the
        first order may come long after t = 0)."""
        if any(v.link.pending for v in self.vehicles.values()):
            return True
        return self.transport is not None and (self.transport.link.pending > 0 or bool(self.master_name))

    def _check_master(self, fleet: FleetSnapshot) -> None:
        """A master control that has gone ends the run with a :class:`MasterControlError` naming how:
        started with ``exec=`` and exited (whatever it started is stopped with it), or announced on
        ``master/connection`` and then CONNECTIONBROKEN (its last will: it crashed or its network failed)
        or OFFLINE while tasks are queued. Retained messages from before the run are history: only a
        retained ONLINE counts (the master control connected before the vehicles)."""
        now = fleet.time
        status = self.master.exit_status() if self.master is not None else None
        if self.master is not None and status is not None:
            self.master.stop()
            self.master = None
            raise MasterControlError(f"the master control exited with status {status} at t = {now:.1f} s")
        assert self._site_link is not None
        where = self._own_topic("master/connection")
        for inbound in self._site_link.drain():
            try:
                said = decode_connection(inbound.payload, self.settings.version)
            except MessageInvalid as invalid:
                problems = "; ".join(e.error_description for e in invalid.errors)
                print(f"fleetsim: ignored a message on {where} that is not a connection: {problems}", file=sys.stderr)
                continue
            state = said.connection_state
            if inbound.retained and state is not ConnectionState.ONLINE:
                continue  # a master control of an earlier run
            name = said.serial_number or self.master_name or "?"
            if state is ConnectionState.ONLINE:
                self.master_name, self.master_left = name, ""
                continue
            queued = sum(len(queue) for queue in fleet.tasks.values())
            if state is ConnectionState.CONNECTIONBROKEN:
                msg = (
                    f"the master control {name!r} lost its connection at t = {now:.1f} s (its last will on {where}: "
                    f"CONNECTIONBROKEN) with {queued} task(s) queued"
                )
                raise MasterControlError(msg)
            if queued:
                msg = f"the master control {name!r} went OFFLINE at t = {now:.1f} s with {queued} task(s) queued"
                raise MasterControlError(msg)
            self.master_left = f"the master control {name!r} went OFFLINE at t = {now:.1f} s"

    # -- each step ----------------------------------------------------------------------------------

    def _pace(self, now: float) -> None:
        """Wait until the wall clock reaches the simulation's time at ``speed`` times real time."""
        target = self.started + now / self.settings.speed
        wait = target - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        elif -wait > self.lag:
            self.lag = -wait
        if -wait > 0.1 / self.settings.speed:  # more than a (default) step behind
            self.late_steps += 1

    def _verdict(self, vehicle: _Vehicle, fleet: FleetSnapshot) -> None:
        """Whether the plan handed at the last call was accepted: the plan in force is what it became."""
        handed = vehicle.handed
        if handed is None:
            return
        vehicle.handed = None
        current = fleet.plans[vehicle.vehicle_id].legs
        accepted = len(current) <= len(handed.legs) and tuple(handed.legs[len(handed.legs) - len(current) :]) == current
        arrived = self._arrived.pop(vehicle.vehicle_id, None)
        if arrived is not None:
            self.latencies.append(time.monotonic() - arrived)
        if accepted and vehicle.pending_path is not None and vehicle.pending_status is not None:
            vehicle.path = vehicle.pending_path  # the legs it has left since are dropped by _follow
            vehicle.status = vehicle.pending_status
            vehicle.errors = [e for e in vehicle.errors if e.error_type != "orderUpdateError"]
            if vehicle.pending_last is not None:  # a new order
                vehicle.last_node = vehicle.pending_last
        vehicle.pending_path = vehicle.pending_status = vehicle.pending_last = None

    def _follow(self, vehicle: _Vehicle, fleet: FleetSnapshot) -> None:
        """Drop the legs the vehicle has left; each passed order node becomes its last node."""
        legs = fleet.plans[vehicle.vehicle_id].legs
        while len(vehicle.path) > len(legs):
            passed = vehicle.path.pop(0)
            if passed.end is not None:
                vehicle.last_node = (passed.end.node_id, passed.end.sequence_id)
            else:
                vehicle.last_node = (
                    self.site.exit_node(passed.leg.segment, passed.leg.traverse),
                    vehicle.last_node[1],
                )
        for entry, leg in zip(vehicle.path, legs, strict=True):
            entry.leg = leg  # goal markers, fixed flags as in force

    def _intake(self, vehicle: _Vehicle, fleet: FleetSnapshot, layout: Layout) -> list[Rejection]:
        refused: list[Rejection] = []
        for inbound in vehicle.link.drain():
            vehicle.heard = fleet.time
            name = inbound.topic.rsplit("/", 1)[-1]
            if name == "instantActions":
                refused += self._instant(vehicle, inbound.payload, fleet)
                continue
            try:
                order = decode_order(inbound.payload, self.settings.version)
            except MessageInvalid as invalid:
                refused.append(self._refuse(vehicle, invalid.errors))
                continue
            state = fleet.vehicles[vehicle.vehicle_id]
            reading = read_order(order, self.site, layout, state.type, state.progress)
            if reading.problems:
                refused.append(self._refuse(vehicle, reading.problems))
                continue
            join, plan, errors = join_order(order, reading, vehicle.status, fleet.plans[vehicle.vehicle_id], self.site)
            if join is Join.RESENT or plan is None:
                if errors:
                    refused.append(self._refuse(vehicle, errors))
                continue
            plan = _mark_goals(plan, fleet.tasks.get(vehicle.vehicle_id, ()), fleet.routed)
            vehicle.errors = [e for e in vehicle.errors if e.error_type == "orderUpdateError"] if errors else []
            vehicle.errors += errors
            verdict = self._check(plan, fleet, layout)
            fixed = len(plan.legs) - len(reading.legs)
            edges: list[Edge | None] = [None] * fixed + list(reading.edges)
            if isinstance(verdict, Rejection) and not errors:
                vehicle.errors.append(vda_error(verdict, order, edges))
            for action in [a for n in reading.nodes for a in n.actions] + [a for e in reading.edges for a in e.actions]:
                self._fail(
                    vehicle,
                    action,
                    "fleetsim's vehicles carry out no node or edge actions; the order is driven without it",
                )
            vehicle.pending = plan
            kept = vehicle.path[:fixed]  # a copy: the path in force stays as it is until the verdict
            vehicle.pending_last = None
            if join is Join.NEW and reading.nodes:
                # Sequence ids start again with a new orderId (VDA 5050 6.7): the order's first node is the
                # vehicle's last node at once (6.10.6: in the current order), and the end of the leg it is
                # on when the order begins there.
                first = reading.nodes[0]
                vehicle.pending_last = (first.node_id, first.sequence_id)
                if kept:
                    kept[-1] = replace(kept[-1], end=first)
            vehicle.pending_path = kept + [
                _Leg(leg, edge, node)
                for leg, edge, node in zip(plan.legs[fixed:], reading.edges, reading.nodes[1:], strict=False)
            ]
            last_base = [n for n in reading.nodes if n.released]
            stitch = last_base[-1] if last_base else reading.nodes[0]
            vehicle.pending_status = OrderStatus(
                order.order_id, order.order_update_id, stitch.node_id, stitch.sequence_id
            )
            self._arrived[vehicle.vehicle_id] = inbound.received
        return refused

    def _instant(self, vehicle: _Vehicle, payload: bytes, fleet: FleetSnapshot) -> list[Rejection]:
        try:
            message = decode_instant_actions(payload, self.settings.version)
        except MessageInvalid as invalid:
            return [self._refuse(vehicle, invalid.errors)]
        for action in message.actions:
            kind = action.action_type
            if kind == "stateRequest":
                vehicle.published = None  # the state goes out this step
                self._done(vehicle, action)
            elif kind == "factsheetRequest":
                self._publish(vehicle, "factsheet", self._factsheet(vehicle, fleet))
                self._done(vehicle, action)
            elif kind in ("startPause", "stopPause"):
                vehicle.paused = kind == "startPause"
                self._done(vehicle, action)
            elif kind == "cancelOrder":
                self._cancel(vehicle, action, fleet)
            elif kind == "initPosition":
                self._fail(
                    vehicle, action, "a simulated vehicle stands where its scenario puts it; it cannot be moved by hand"
                )
            else:
                self._fail(
                    vehicle, action, f"fleetsim's vehicles know no action {kind!r}", error_type="unknownActionError"
                )
        return []

    def _cancel(self, vehicle: _Vehicle, action: Action, fleet: FleetSnapshot) -> None:
        """Drop the horizon (the base is a commitment: it is driven to its end, then the cancel finishes)."""
        plan = fleet.plans[vehicle.vehicle_id]
        if not vehicle.status.order_id or (len(plan.legs) == 1 and self._at_exit(fleet.vehicles[vehicle.vehicle_id])):
            self._fail(vehicle, action, "there is no order to cancel", error_type="noOrderToCancel")
            return
        fixed = tuple(leg for leg in plan.legs if leg.fixed)
        if len(fixed) < len(plan.legs):  # a horizon to drop, at the vehicle's next planner call
            vehicle.pending = FleetPlan(vehicle.vehicle_id, fixed)
            vehicle.pending_path = vehicle.path[: len(fixed)]
            vehicle.pending_status = vehicle.status
        vehicle.cancelling = action.action_id
        vehicle.actions[action.action_id] = ActionState(action.action_id, ActionStatus.RUNNING, action.action_type)

    def _done(self, vehicle: _Vehicle, action: Action) -> None:
        vehicle.actions[action.action_id] = ActionState(action.action_id, ActionStatus.FINISHED, action.action_type)

    def _fail(self, vehicle: _Vehicle, action: Action, why: str, *, error_type: str = "actionError") -> None:
        vehicle.actions[action.action_id] = ActionState(
            action.action_id, ActionStatus.FAILED, action.action_type, result_description=why
        )
        references = (ErrorReference("actionId", action.action_id), ErrorReference("actionType", action.action_type))
        vehicle.errors.append(VdaError(error_type, f"{action.action_type}: {why}", error_references=references))

    def _refuse(self, vehicle: _Vehicle, errors: Sequence[VdaError]) -> Rejection:
        vehicle.errors = list(errors)
        words = "; ".join(e.error_description for e in errors[:3]) + (
            f"; and {len(errors) - 3} more" if len(errors) > 3 else ""
        )
        return Rejection(RejectionCode.ORDER_INVALID, vehicle.vehicle_id, None, None, words)

    def _check(self, plan: FleetPlan, fleet: FleetSnapshot, layout: Layout) -> FleetPlan | Rejection:
        types = {vid: state.type for vid, state in fleet.vehicles.items()}
        context = CheckContext(layout, types, fleet.plans, fleet.tasks, fleet.routed)
        return check_plans([plan], context)[0]

    def _hand(self, vehicle_id: int) -> Response:
        vehicle = self.vehicles.get(vehicle_id)
        if vehicle is None or vehicle.pending is None:
            return []
        plan, vehicle.pending = vehicle.pending, None
        vehicle.handed = plan
        return [plan]

    def _announce(self, vehicle: _Vehicle, fleet: FleetSnapshot) -> None:
        """Publish each task when it becomes the vehicle's next; a task no longer queued is done."""
        assert self._site_link is not None
        queue = fleet.tasks.get(vehicle.vehicle_id, ())
        if self.transport is not None:  # an order's stops are on its own topic (.transport), not as tasks
            queue = tuple(task for task in queue if task.order_id is None)
        for task_id in sorted(vehicle.announced - {t.id for t in queue}):
            vehicle.announced.discard(task_id)
            document = {
                "taskId": str(task_id),
                "serialNumber": vehicle.serial,
                "state": "FINISHED",
                "time": round(fleet.time, 6),
            }
            self._site_link.publish(self._own_topic(f"transportOrders/{task_id}"), _json(document), qos=1, retain=True)
        if queue and queue[0].id not in vehicle.announced:
            task = queue[0]
            vehicle.announced.add(task.id)
            self._site_link.publish(
                self._own_topic(f"transportOrders/{task.id}"),
                _json(self._transport_order(task, vehicle, fleet.time)),
                qos=1,
                retain=True,
            )

    def _transport_order(self, task: Task, vehicle: _Vehicle, now: float) -> dict[str, Any]:
        edges, nodes = goal_places(self.site, task.goal_segment)
        return {
            "taskId": str(task.id),
            "serialNumber": vehicle.serial,
            "state": "OPEN",
            "goalEdgeIds": edges,
            "goalNodeIds": nodes,
            "goalProgress": task.goal_progress.value if task.goal_progress is not None else None,
            "time": round(now, 6),
        }

    def _report(self, vehicle: _Vehicle, fleet: FleetSnapshot) -> None:
        now = fleet.time
        state = fleet.vehicles[vehicle.vehicle_id]
        if vehicle.cancelling is not None and self._base_driven(vehicle, fleet):
            done = vehicle.actions[vehicle.cancelling]
            vehicle.actions[vehicle.cancelling] = replace(done, action_status=ActionStatus.FINISHED)
            vehicle.cancelling = None
        key = (
            vehicle.status,
            vehicle.last_node,
            self._at_exit(state),
            tuple(e.leg for e in vehicle.path),
            tuple(vehicle.errors),
            tuple(vehicle.actions.values()),
            vehicle.paused,
            state.disturbed,
            _moving(state),
        )
        if key != vehicle.published or now >= vehicle.next_state:
            vehicle.published = key
            vehicle.next_state = now + self.settings.state_interval
            self._publish(vehicle, "state", self._state(vehicle, state, now))
        if now >= vehicle.next_visualization:
            vehicle.next_visualization = now + self.settings.visualization_interval
            message = Visualization(
                self._header(vehicle, "visualization"), self._stamp(now), self.settings.manufacturer, vehicle.serial,
                agv_position=self._position(state), velocity=self._velocity(state),
            )  # fmt: skip
            self._publish(vehicle, "visualization", message)

    def _base_driven(self, vehicle: _Vehicle, fleet: FleetSnapshot) -> bool:
        """The cancelled order's plan is in force and the vehicle stands at the end of its base."""
        state = fleet.vehicles[vehicle.vehicle_id]
        settled = vehicle.pending is None and vehicle.handed is None
        return (
            settled and len(fleet.plans[vehicle.vehicle_id].legs) == 1 and self._at_exit(state) and not _moving(state)
        )

    # -- messages -----------------------------------------------------------------------------------

    def _state(self, vehicle: _Vehicle, state: VehicleState, now: float) -> State:
        at_exit = bool(vehicle.path) and self._at_exit(state)
        ahead = vehicle.path[1:] if at_exit else vehicle.path
        node_states = tuple(
            NodeState(entry.end.node_id, entry.end.sequence_id, entry.end.released)
            for entry in ahead
            if entry.end is not None
        )
        edge_states = tuple(
            EdgeState(entry.edge.edge_id, entry.edge.sequence_id, entry.edge.released)
            for entry in ahead
            if entry.edge is not None
        )
        last_id, last_sequence = vehicle.last_node
        if at_exit:  # at the end of the leg it is on: that leg's exit node is its last node
            end = vehicle.path[0].end
            if end is not None:
                last_id, last_sequence = end.node_id, end.sequence_id
            else:
                last_id = self.site.exit_node(state.segment, state.traverse)
        return State(
            header_id=self._header(vehicle, "state"),
            timestamp=self._stamp(now),
            manufacturer=self.settings.manufacturer,
            serial_number=vehicle.serial,
            order_id=vehicle.status.order_id,
            order_update_id=vehicle.status.order_update_id,
            last_node_id=last_id,
            last_node_sequence_id=last_sequence,
            driving=_moving(state),
            operating_mode=OperatingMode.AUTOMATIC,
            battery_state=BatteryState(battery_charge=100.0, charging=False),
            # A disturbance (fleetsim.sim.disturbances) is what a real vehicle meets on the floor: a stop
            # is its protective field tripped, a slow-down a warning field; both are told as information.
            safety_state=SafetyState(e_stop=EStop.NONE, field_violation=state.disturbed is Disturbed.STOPPED),
            information=_disturbance_information(state),
            node_states=node_states,
            edge_states=edge_states,
            errors=tuple(vehicle.errors),
            action_states=tuple(vehicle.actions.values()),
            paused=vehicle.paused,
            new_base_request=False,
            agv_position=self._position(state),
            velocity=self._velocity(state),
        )

    def _at_exit(self, state: VehicleState) -> bool:
        return state.distance >= self.site.segment_length(state.segment) - ARRIVED

    def _position(self, state: VehicleState) -> AgvPosition:
        return AgvPosition(
            state.x, state.y, math.remainder(state.heading, math.tau), self.site.map_id, position_initialized=True
        )

    @staticmethod
    def _velocity(state: VehicleState) -> Velocity:
        return Velocity(vx=state.speed if state.progress is Progress.FORWARD else -state.speed, vy=0.0, omega=0.0)

    def _connection(self, vehicle: _Vehicle, connection_state: ConnectionState) -> Connection:
        return Connection(
            self._header(vehicle, "connection"),
            self._stamp(0.0),
            self.settings.manufacturer,
            vehicle.serial,
            connection_state,
        )

    def _factsheet(self, vehicle: _Vehicle, fleet: FleetSnapshot) -> Factsheet:
        """What the vehicle is, from its type: dimensions, speeds, how often it reports, what it can do."""
        kind = fleet.vehicles[vehicle.vehicle_id].type
        half_length, half_width = kind.length / 2, kind.width / 2
        outline = tuple(
            PolygonPoint(x, y)
            for x, y in (
                (half_length, half_width),
                (-half_length, half_width),
                (-half_length, -half_width),
                (half_length, -half_width),
            )
        )
        instant = ("INSTANT",)
        supported = tuple(
            AgvAction(name, instant, description)
            for name, description in (
                ("stateRequest", "a state now"),
                ("factsheetRequest", "this factsheet now"),
                ("startPause", "brake to rest within the base, and stay"),
                ("stopPause", "drive on"),
                ("cancelOrder", "drop the horizon; finished once the base is driven"),
            )
        )
        return Factsheet(
            header_id=self._header(vehicle, "factsheet"),
            timestamp=self._stamp(fleet.time),
            manufacturer=self.settings.manufacturer,
            serial_number=vehicle.serial,
            type_specification=TypeSpecification(
                series_name=kind.name,
                agv_kinematic="DIFF" if kind.turn_capability is TurnCapability.IN_PLACE else "THREEWHEEL",
                agv_class="CARRIER",
                max_load_mass=0.0,
                localization_types=("NATURAL",),
                navigation_types=("VIRTUAL_LINE_GUIDED",),
                series_description="a fleetsim vehicle",
            ),
            physical_parameters=PhysicalParameters(
                speed_min=0.0,
                speed_max=kind.max_speed,
                acceleration_max=kind.acceleration,
                deceleration_max=kind.acceleration,
                height_max=kind.height,
                width=kind.width,
                length=kind.length,
            ),
            protocol_limits=ProtocolLimits(
                timing=Timing(
                    min_order_interval=0.0,
                    min_state_interval=0.0,
                    default_state_interval=self.settings.state_interval / self.settings.speed,
                    visualization_interval=self.settings.visualization_interval / self.settings.speed,
                )
            ),
            protocol_features=ProtocolFeatures(agv_actions=supported),
            agv_geometry=AgvGeometry(envelopes2d=(Envelope2d("footprint", outline, "the type's length x width"),)),
        )

    def _site(self, fleet: FleetSnapshot, layout: Layout) -> bytes:
        graph = self.site
        nodes = [{"nodeId": p.node_id, "x": p.x, "y": p.y} for p in graph.places.values()]
        edges = []
        for sid in sorted(layout.segments):
            for traverse in graph.traverses(sid):
                # What may follow this edge: a vehicle that cannot turn in place takes no turn_in_place joint,
                # and at an opposite one (a cusp) it changes between nose first and backing.
                following = [
                    {
                        "edgeId": graph.edge_id(nsid, ntraverse),
                        "endNodeId": graph.exit_node(nsid, ntraverse),
                        "joint": joint.value,
                    }
                    for nsid, ntraverse, joint in layout.successors(sid, traverse)
                    if ntraverse in graph.traverses(nsid)
                ]
                edges.append(
                    {
                        "edgeId": graph.edge_id(sid, traverse),
                        "startNodeId": graph.entry_node(sid, traverse),
                        "endNodeId": graph.exit_node(sid, traverse),
                        "length": layout.segments[sid].length,
                        "next": following,
                    }
                )
        vehicles = [
            {
                "serialNumber": str(vid),
                "turnInPlace": s.type.turn_capability is TurnCapability.IN_PLACE,
                # It stands on this edge, facing along it: its first order starts at the edge's start node.
                "startEdgeId": graph.edge_id(s.segment, s.traverse),
                "startNodeId": graph.entry_node(s.segment, s.traverse),
            }
            for vid, s in sorted(fleet.vehicles.items())
        ]
        return _json({"mapId": graph.map_id, "nodes": nodes, "edges": edges, "vehicles": vehicles})

    def _publish(self, vehicle: _Vehicle, name: str, message: Any, *, qos: int = 0, retain: bool = False) -> None:
        vehicle.link.publish(
            self._topic(vehicle.serial, name), encode(message, self.settings.version), qos=qos, retain=retain
        )

    def _header(self, vehicle: _Vehicle, name: str) -> int:
        vehicle.headers[name] = vehicle.headers.get(name, -1) + 1
        return vehicle.headers[name]

    def _stamp(self, now: float) -> str:
        """The simulation's clock: the run's start on the wall clock plus the simulated seconds."""
        moment = self.epoch + timedelta(seconds=now)
        return moment.strftime("%Y-%m-%dT%H:%M:%S.") + f"{moment.microsecond // 10000:02d}Z"

    def _topic(self, serial: str, name: str) -> str:
        s = self.settings
        return topic(s.interface_name, s.version, s.manufacturer, serial, name)

    def _own_topic(self, name: str) -> str:
        return f"{self.settings.interface_name}/fleetsim/{name}"


def _moving(state: VehicleState) -> bool:
    """Driving: faster than a rounding residue (a vehicle braked to rest may keep 1e-14 m/s)."""
    return state.speed > STILL


def _disturbance_information(state: VehicleState) -> tuple[Information, ...]:
    if state.disturbed is None:
        return ()
    words = "stopped by an obstacle" if state.disturbed is Disturbed.STOPPED else "slowed down"
    return (Information("disturbance", InfoLevel.INFO, f"the vehicle is {words} (a disturbance of the scenario)"),)


def _mark_goals(plan: FleetPlan, queue: tuple[Task, ...], routed: Any) -> FleetPlan:
    """The order's plan with goal markers: the queued tasks in order, each on the first leg after the last
    marker that drives its goal segment (with its progress, if the task asks for one)."""
    legs = list(plan.legs)
    marked = {leg.goal_for_task for leg in legs if leg.goal_for_task is not None}
    cursor = max((i for i, leg in enumerate(legs) if leg.goal_for_task is not None), default=-1) + 1
    for task in queue:
        if task.id in marked:
            continue
        found = next(
            (
                i
                for i in range(cursor, len(legs))
                if legs[i].segment == task.goal_segment
                and (task.goal_progress is None or legs[i].progress is task.goal_progress)
            ),
            None,
        )
        if found is None:
            break
        legs[found] = replace(legs[found], goal_for_task=task.id)
        cursor = found + 1
    return FleetPlan(plan.vehicle_id, tuple(legs))


def _json(document: Any) -> bytes:
    return json.dumps(document, separators=(",", ":")).encode()
