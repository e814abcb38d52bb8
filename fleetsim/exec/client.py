"""The planner side of the JSON-lines protocol, for planners written in Python.

:func:`serve` runs any in-process planner (an object with ``plan_routes`` and ``fix_legs``) as a planner
process: it reads the init message, rebuilds the layout and the scenario's types and tasks, and answers
each request by calling the planner with the same objects an in-process run would pass (``Task``,
``FleetSnapshot``, ``Layout``). Floats travel as JSON's shortest round-trip form, so a planner served
this way makes the same decisions, and the run the same trace hash, as in process. From a shell::

    python -m fleetsim.exec mypackage.planner:MyPlanner        # a planner class or factory
    fleetsim run SUITE --planner "exec:python -m fleetsim.exec mypackage.planner:MyPlanner"

Served from a factory, the planner is made when the init message has come, with its ``planner_options``
(protocol 1.4) as keyword arguments and ``scenario_dir`` if the factory declares it, as in process.

A planner that raises a ``RouteError`` answers with a route error; any other exception is printed to
stderr with its traceback and ends the process with status 1 (the run then fails with a
``planner-error`` showing that stderr).

The client answers planning rounds in one message (protocol 1.2, ``fleetsim/exec/rounds.py``) when
fleetsim speaks 1.2 or later, unless served with ``rounds=False`` (``python -m fleetsim.exec
--no-rounds``): then it answers one request per call, as a 1.1 client.

A served planner that has a ``dispatch`` method is a dispatcher too (one object, both jobs): to fleetsim
1.5 or later the client says so in its ready message and answers ``dispatch`` requests
(``fleetsim/exec/dispatching.py``) by calling it with the same ``OrderBoard`` an in-process run would pass.
Its answer is checked as in process (a list of ``Assignment`` items): anything else is printed to stderr
and ends the process with status 1, as a planner's exception does.
"""

from __future__ import annotations

import os
import sys
import time
import traceback
from collections.abc import Callable, Mapping
from pathlib import Path
from types import MappingProxyType
from typing import IO, Any

from fleetsim.dispatch.checks import validate_answer
from fleetsim.enums import ConflictModel, Direction, Shape, TurnCapability
from fleetsim.errors import PlannerError
from fleetsim.exec.dispatching import BoardReader, encode_assignments
from fleetsim.exec.protocol import (
    PROTOCOL_FAMILY,
    LegBook,
    decode_disturbed,
    decode_plan,
    decode_progress,
    decode_traverse,
    dumps,
    encode_plan,
    loads,
)
from fleetsim.layout.layout import Layout, build_layout
from fleetsim.layout.segment import Segment
from fleetsim.planning.plans import FleetPlan, RouteError, hands_back
from fleetsim.planning.protocol import Planner
from fleetsim.planning.snapshot import FleetSnapshot, VehicleState
from fleetsim.scenario import PlannerSetup, Task, VehicleType
from fleetsim.specs.python import PlannerFactory, PlannerSpecError

__all__ = ["ProtocolError", "serve"]


class ProtocolError(Exception):
    """fleetsim sent something this client does not understand (a version mismatch, most likely)."""


def _layout(data: Mapping[str, Any]) -> Layout:
    segments = [
        Segment(
            s["id"],
            Shape(s["shape"]),
            Direction(s["direction"]),
            tuple((x, y) for x, y in s["waypoints"]),
            tuple(s.get("names", ())),  # 1.3; before, segments came without names
        )
        for s in data["segments"]
    ]
    settings = data["settings"]
    layout = build_layout(
        segments,
        vehicle_radius=settings["vehicle_radius"],
        connection_tolerance=settings["connection_tolerance"],
        joint_angle_tolerance=settings["joint_angle_tolerance"],
        safety_margin=settings["safety_margin"],
        conflict_model=ConflictModel(settings["conflict_model"]),
    )
    # The layout is rebuilt from the same segments and settings; it must come out the same.
    connections = [
        [[c.from_segment, c.from_traverse.value], [c.to_segment, c.to_traverse.value], c.joint.value]
        for c in layout.connections
    ]
    if connections != [[c["from"], c["to"], c["joint"]] for c in data["connections"]]:
        msg = "the rebuilt layout's connections differ from fleetsim's (different fleetsim versions?)"
        raise ProtocolError(msg)
    return layout


def _task(data: Mapping[str, Any]) -> Task:
    progress = data["goal_progress"]
    return Task(
        data["id"],
        data["vehicle_id"],
        data["goal_segment"],
        decode_progress[progress] if progress else None,
        data.get("order_id"),  # 1.5: a stop of a transport order
        data.get("stop"),
        data.get("deadline"),
    )


class _Session:
    """What the init message said, and the fleet the requests refer to."""

    def __init__(self, init: Mapping[str, Any]) -> None:
        protocol = str(init.get("protocol"))
        family, _, minor = protocol.partition(".")
        if init.get("type") != "init" or family != PROTOCOL_FAMILY:
            msg = f"expected the init message of {PROTOCOL_FAMILY}.x, got type={init.get('type')!r} protocol={init.get('protocol')!r}"
            raise ProtocolError(msg)
        # Rounds came with 1.2 and dispatch requests with 1.5: an earlier fleetsim would refuse a ready
        # answer that asks for them.
        self.speaks_rounds = minor.isdigit() and int(minor) >= 2
        self.speaks_dispatch = minor.isdigit() and int(minor) >= 5
        self.layout = _layout(init["layout"])
        scenario = init["scenario"]
        self.types = {
            t["name"]: VehicleType(
                t["name"], t["length"], t["width"], t["height"], t["max_speed"], t["acceleration"],
                TurnCapability(t["turn_capability"]), t["turn_rate"],
            )
            for t in scenario["vehicle_types"]
        }  # fmt: skip
        self.tasks = {task.id: task for task in map(_task, scenario["tasks"])}
        self.fleet: FleetSnapshot | None = None
        self.vehicles: dict[int, VehicleState] = {}
        self.plans: dict[int, FleetPlan] = {}
        self.queues: dict[int, tuple[Task, ...]] = {}
        # The plans of the last answer, by vehicle, with their JSON: one that comes back in a fleet update
        # (fleetsim accepted it) becomes the planner's own object again, as in process, where a planner
        # that keeps state by plan identity (FleetIndex) then recounts nothing.
        self.answered: dict[int, tuple[FleetPlan, dict[str, Any]]] = {}
        self.legs = LegBook()  # the fleet updates' legs, each decoded once
        self.boards = BoardReader()

    def snapshot(self, data: Mapping[str, Any]) -> FleetSnapshot:
        """The fleet after ``data`` (complete the first time, then the entries that changed)."""
        previous, types = self.fleet, self.types
        traverse, progress, disturbed = decode_traverse, decode_progress, decode_disturbed
        state = VehicleState._make  # from a tuple: half the cost of the call with eleven arguments
        for task in data.get("new_tasks", ()):  # 1.5: tasks made from transport orders as they are assigned
            self.tasks[task["id"]] = _task(task)
        for v in data["vehicles"]:
            word = v.get("disturbed")
            self.vehicles[v["id"]] = state((
                v["id"], v["segment"], traverse[v["traverse"]], progress[v["progress"]], v["distance"], v["speed"],
                v["x"], v["y"], v["heading"], types[v["type"]], None if word is None else disturbed[word],
            ))  # fmt: skip
        for encoded in data["plans"]:
            mine = self.answered.get(encoded["vehicle_id"])
            plan = mine[0] if mine is not None and mine[1] == encoded else decode_plan(encoded, self.legs)
            self.plans[plan.vehicle_id] = plan  # an unchanged plan stays the same object, as in process
        for vehicle_id, ids in data["tasks"]:
            self.queues[vehicle_id] = tuple(self.tasks[task_id] for task_id in ids)
        # A mapping with nothing changed is the previous snapshot's, as fleetsim's own snapshots share theirs.
        return FleetSnapshot(
            time=data["time"],
            vehicles=_view(self.vehicles, data["vehicles"], None if previous is None else previous.vehicles),
            plans=_view(self.plans, data["plans"], None if previous is None else previous.plans),
            tasks=_view(self.queues, data["tasks"], None if previous is None else previous.tasks),
            routed=frozenset(data["routed"]),
        )

    def answer(self, planner: Planner, request: Mapping[str, Any]) -> dict[str, Any]:
        if "fleet" in request:
            self.fleet = self.snapshot(request["fleet"])
        if self.fleet is None:
            msg = f"request {request.get('id')!r} has no fleet and none came before"
            raise ProtocolError(msg)
        method = request["type"]
        if method == "fix_legs":
            call = planner.fix_legs
        elif method == "plan_routes":
            call = planner.plan_routes
        else:
            msg = f"request type={method!r} must be plan_routes or fix_legs"
            raise ProtocolError(msg)
        try:
            items = call(self.tasks.get(request["task"]["id"]) or _task(request["task"]), self.fleet, self.layout)
        except RouteError as error:
            return {"id": request["id"], "route_error": error.message}
        if not items or (isinstance(items, (list, tuple)) and hands_back(items, self.fleet.plans)):
            return {"id": request["id"], "plans": [], "route_errors": []}
        plans = []
        for item in items:
            if isinstance(item, FleetPlan):
                encoded = encode_plan(item)
                self.answered[item.vehicle_id] = (item, encoded)
                plans.append(encoded)
        errors = [
            {"vehicle_id": item.vehicle_id, "message": item.message} for item in items if isinstance(item, RouteError)
        ]
        return {"id": request["id"], "plans": plans, "route_errors": errors}

    def answer_dispatch(self, planner: Planner, request: Mapping[str, Any]) -> dict[str, Any]:
        """A dispatch request answered by the planner's ``dispatch`` with the board and fleet it describes."""
        if "fleet" in request:
            self.fleet = self.snapshot(request["fleet"])
        dispatch = getattr(planner, "dispatch", None)
        if self.fleet is None or not callable(dispatch):
            msg = f"dispatch request {request.get('id')!r}: " + (
                "no fleet came before" if self.fleet is None else "the planner has no dispatch method"
            )
            raise ProtocolError(msg)
        answer = validate_answer(dispatch(self.boards.board(request["board"]), self.fleet, self.layout))
        return encode_assignments(request["id"], answer)

    def answer_round(self, planner: Planner, message: Mapping[str, Any]) -> dict[str, Any]:
        """The round's calls answered in order, up to the first answer that changes something, each with its
        duration."""
        if "fleet" in message:
            self.fleet = self.snapshot(message["fleet"])
        answers: list[dict[str, Any]] = []
        durations: list[float] = []
        clock, answer = time.perf_counter, self.answer
        for call in message["calls"]:
            started = clock()
            reply = answer(planner, call)
            durations.append(clock() - started)
            answers.append(reply)
            if "route_error" in reply or reply["plans"] or reply["route_errors"]:
                break  # it changes something: the calls after it must see the fleet as changed
        return {"answers": answers, "durations": durations}


def _view(entries: dict[int, Any], changed: list[Any], before: Mapping[int, Any] | None) -> Mapping[int, Any]:
    """A read-only copy of ``entries``, or ``before`` itself when no entry ``changed``."""
    return before if before is not None and not changed else MappingProxyType(dict(entries))


def serve(
    planner: Planner | PlannerFactory,
    stdin: IO[str] | None = None,
    stdout: IO[str] | None = None,
    *,
    rounds: bool = True,
) -> int:
    """Answer fleetsim's messages on ``stdin`` (default: the process's) until it closes; the exit status.
    With ``rounds`` (and fleetsim 1.2 or later) a planning round comes in one message. A
    :class:`~fleetsim.specs.python.PlannerFactory` makes the planner once the init message has come, with
    its ``planner_options`` and ``scenario_dir``; a factory that refuses them ends the process (status 1).

    The process's own streams are read as bytes (JSON is UTF-8) and answers written straight to its
    stdout's file descriptor: a call then costs no text layer and no buffer to fill and flush."""
    source: IO[Any] = stdin if stdin is not None else sys.stdin.buffer
    send = _writer(stdout)
    session: _Session | None = None
    made = None if isinstance(planner, PlannerFactory) else planner
    for line in source:
        if line.isspace():
            continue
        try:
            message = loads(line)
            if session is None:
                session = _Session(message)
                if isinstance(planner, PlannerFactory):
                    made = planner(_setup(message))
                answer: dict[str, Any] = {"type": "ready"}
                if rounds and session.speaks_rounds:
                    answer["rounds"] = True
                if session.speaks_dispatch and callable(getattr(made, "dispatch", None)):
                    answer["dispatches"] = True
            else:
                assert made is not None  # made with the session
                kind = message.get("type")
                ask = session.answer_round if kind == "round" else session.answer
                answer = session.answer_dispatch(made, message) if kind == "dispatch" else ask(made, message)
        except (ProtocolError, PlannerSpecError, PlannerError) as error:
            print(f"fleetsim.exec: {error}", file=sys.stderr)
            return 1
        except Exception:  # the planner's own error: its traceback goes to fleetsim's report via stderr
            traceback.print_exc(file=sys.stderr)
            return 1
        send(dumps(answer) + b"\n")
    return 0


def _setup(init: Mapping[str, Any]) -> PlannerSetup:
    """What the planner is made with: the init message's planner options and scenario folder (1.4)."""
    options, folder = init.get("planner_options") or {}, init.get("scenario_dir")
    return PlannerSetup(MappingProxyType(dict(options)), None if folder is None else Path(folder))


def _writer(stdout: IO[str] | None) -> Callable[[bytes], None]:
    """How an answer's line is written: to ``stdout`` as text, or else to the process's stdout as bytes."""
    if stdout is not None:

        def write_text(line: bytes) -> None:
            stdout.write(line.decode("utf-8"))
            stdout.flush()

        return write_text
    sys.stdout.flush()  # anything printed before the first answer goes first
    descriptor = sys.stdout.fileno()

    def write(line: bytes) -> None:
        written = os.write(descriptor, line)
        if written < len(line):  # a long answer may take several writes
            rest = memoryview(line)[written:]
            while rest:
                rest = rest[os.write(descriptor, rest) :]

    return write
