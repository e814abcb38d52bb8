"""The JSON-lines planner protocol (``--planner exec:COMMAND``): message encoding and decoding.

fleetsim starts the planner process once per run and writes one JSON object per line to its stdin; the
planner answers each message with one JSON object per line on its stdout (anything it writes to stderr
is kept for error reports). Enum values are the words of the suite files (``forward``/``backward``,
``forward``/``reverse``, ``same``/``opposite``/``turn_in_place``...). The JSON Schemas of every message
are in ``schemas/planner-*.schema.json``.

Versions: ``fleetsim-planner/MAJOR.MINOR`` (``fleetsim-planner/1`` is 1.0). A minor version only adds
optional fields, so a client checks the major part; 1.1 added ``disturbed``; 1.2 planning rounds in one
message, which a client opts into (``fleetsim/exec/rounds.py``); 1.3 the segments' ``names``; 1.4 the
init message's ``planner_options`` and ``scenario_dir``; 1.5 the dispatcher's ``dispatch`` requests, which
a client opts into (``fleetsim/exec/dispatching.py``), the order, stop and deadline of a task made from a
transport order, and a fleet update's ``new_tasks``.

1. ``{"type": "init", "protocol": "fleetsim-planner/1.5", "layout": {...}, "scenario": {...}}``
   - ``layout``: exactly the layout part of what ``fleetsim inspect --json`` prints for the map (which
     adds the map file, its format and part, ``meters_per_pixel``, ``lint`` and ``warnings``):
     ``segments`` (``id, shape, direction, length, waypoints`` in metres, ``names``: what the site
     calls the segment, maybe nothing), ``connections``
     (``from: [segment, traverse], to: [segment, traverse], joint``; the successors of a state are its
     connections in this order), ``conflicts`` (``{segment, conflicts}``, each list sorted) and
     ``settings`` (``vehicle_radius, safety_margin, conflict_model, connection_tolerance,
     joint_angle_tolerance``).
   - ``scenario``: ``vehicle_types`` (``name, length, width, height, max_speed, acceleration,
     turn_capability, turn_rate``), ``vehicles`` (``id, type``) and ``tasks`` (``id, vehicle_id,
     goal_segment, goal_progress``; 1.5: a task made from a transport order's stop adds ``order_id``,
     ``stop``, the stop's index in its order, and ``deadline``, the order's, or null).
   - ``planner_options`` (1.4): the suite entry's options for the planner (a JSON object, ``{}`` when it
     gives none), and ``scenario_dir``: the scenario's folder on this machine (absolute), where the
     entry's data ``files`` are (on a sweep's worker, the folder they were sent to), or ``null`` when the
     scenario has none.

   Answer: ``{"type": "ready"}``, or (to a 1.2 init or later) ``{"type": "ready", "rounds": true}`` to be
   sent each planning round's calls in one ``round`` message instead of one request per call; and (to a
   1.5 init or later) ``"dispatches": true`` to be the run's dispatcher when it has transport orders and
   no other dispatcher is named: it is then sent ``dispatch`` requests (``fleetsim/exec/dispatching.py``).
2. ``{"type": "plan_routes" | "fix_legs", "id": N, "vehicle": V, "task": TASK, "fleet": FLEET}``, one
   per planner call, ``id`` counting from 1. ``fleet`` is the snapshot: ``time``, ``vehicles`` (each
   ``id, segment, traverse, progress, distance, speed, x, y, heading, type``, and ``disturbed``:
   ``stopped``/``slowed`` while a disturbance stops or slows it, absent otherwise), ``plans`` (each
   ``vehicle_id, legs``; a leg is ``segment, traverse, progress, fixed, goal_for_task``), ``tasks``
   (``[vehicle_id, [task ids, head first]]`` pairs) and ``routed`` (task ids). It is sent only when it
   changed since the last request; a request without ``fleet`` means "the same fleet as before". The
   first ``fleet`` of a run is complete; later ones hold ``time``, ``routed`` and only the vehicles,
   plans and queues that changed, each replacing the entry with the same vehicle id (vehicles never
   leave a run), so a client keeps the fleet by vehicle id and updates it. A fleet whose queues hold
   tasks the process has not been sent yet (made from transport orders as the dispatcher assigns them)
   lists them in ``new_tasks`` (1.5; absent when there are none).

   ``vehicle`` is the task's vehicle. Answer: ``{"id": N, "plans": [PLAN...], "route_errors":
   [{"vehicle_id": V|null, "message": S}...]}`` (both lists may be empty: nothing to change; plans are
   checked and applied in their order, route errors are reported), or ``{"id": N, "route_error":
   "message"}`` when the whole request cannot be routed (a raised ``RouteError``).
3. When the run ends fleetsim closes the planner's stdin; the process should exit (status 0). A process
   still running a second later is terminated, with everything it started.

Blank lines are ignored on both sides. Numbers are plain JSON (never NaN or infinite). Enum words:
traverse ``forward|backward``, progress ``forward|reverse``, joint ``same|opposite|turn_in_place``,
shape ``straight|curve|s_curve|path``, direction ``both|forward|backward``, turn capability
``curve|in_place``, conflict model ``swept|bbox``.

fleetsim writes compact JSON (no spaces) and reads any spelling, but the two commonest answers it
recognises by their bytes, without decoding or checking them: ``{"id":N,"plans":[],"route_errors":[]}``
and the same with one plan, the asked vehicle's plan in force handed back exactly as fleetsim last sent
it (its keys in fleetsim's order: what ``JSON.stringify`` or ``json.dumps(..., separators=(",", ":"))``
give for a plan kept as it was parsed). Both change nothing; a client that answers them so saves fleetsim
a few microseconds per call. Likewise a round's answer that answers every call with nothing to change
(``{"answers":[{"id":N,"plans":[],"route_errors":[]},...],"durations":[...]}``, compact, keys in this
order): only its durations are decoded.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from collections.abc import Set as AbstractSet
from typing import Any

import orjson

from fleetsim.enums import Disturbed, Progress, Traverse
from fleetsim.layout.layout import Layout
from fleetsim.planning.plans import FleetLeg, FleetPlan, RouteError
from fleetsim.planning.snapshot import FleetSnapshot, VehicleState
from fleetsim.planning.views import replaced
from fleetsim.scenario import Task, VehicleType

__all__ = [
    "PROTOCOL",
    "PROTOCOL_FAMILY",
    "FleetEncoder",
    "LegBook",
    "decode_disturbed",
    "decode_plan",
    "decode_progress",
    "decode_response",
    "decode_traverse",
    "dumps",
    "encode_fleet",
    "encode_init",
    "encode_layout",
    "encode_plan",
    "encode_task",
    "init_message",
    "loads",
]

PROTOCOL = "fleetsim-planner/1.5"
PROTOCOL_FAMILY = "fleetsim-planner/1"  # what a client checks: the same major version

# Both sides of every planner call encode and decode a message, so JSON is orjson's (compiled): a call's
# messages cost a microsecond or two instead of ten. Floats are written in their shortest round-trip form
# and read back exactly, as with the json module, so a served planner sees the very floats it would in
# process. orjson writes NaN and infinities as null rather than refusing them: no message holds one,
# since every number in a scenario is checked finite when it is loaded and motion keeps them so.
dumps = orjson.dumps  # one message as compact UTF-8 JSON, without the newline
loads = orjson.loads  # bytes or str; a JSONDecodeError (a ValueError) names what is wrong and where

# Enum words to members and back by dict lookup: an enum's call costs a microsecond and its ``.value`` a
# fifth of one, and a fleet update of a hundred vehicles holds hundreds of words.
decode_traverse: Mapping[str, Traverse] = {member.value: member for member in Traverse}
decode_progress: Mapping[str, Progress] = {member.value: member for member in Progress}
decode_disturbed: Mapping[str, Disturbed] = {member.value: member for member in Disturbed}
_TRAVERSE_WORD: Mapping[Traverse, str] = {member: member.value for member in Traverse}
_PROGRESS_WORD: Mapping[Progress, str] = {member: member.value for member in Progress}


def encode_layout(layout: Layout) -> dict[str, Any]:
    """The layout document: the init message's ``layout`` and the layout part of ``fleetsim inspect
    --json`` (which adds the map file's facts, lint and warnings around it)."""
    segments = [layout.segments[sid] for sid in sorted(layout.segments)]
    return {
        "segments": [
            {
                "id": s.id,
                "shape": s.shape.value,
                "direction": s.direction.value,
                "length": s.length,
                "waypoints": [[x, y] for x, y in s.waypoints],
                "names": list(s.names),
            }
            for s in segments
        ],
        "connections": [
            {
                "from": [c.from_segment, c.from_traverse.value],
                "to": [c.to_segment, c.to_traverse.value],
                "joint": c.joint.value,
            }
            for c in layout.connections
        ],
        "conflicts": [{"segment": s.id, "conflicts": sorted(layout.conflicts(s.id))} for s in segments],
        "settings": {
            "vehicle_radius": layout.vehicle_radius,
            "safety_margin": layout.safety_margin,
            "conflict_model": layout.conflict_model.value,
            "connection_tolerance": layout.connection_tolerance,
            "joint_angle_tolerance": layout.joint_angle_tolerance,
        },
    }


def _vehicle_type(kind: VehicleType) -> dict[str, Any]:
    return {
        "name": kind.name,
        "length": kind.length,
        "width": kind.width,
        "height": kind.height,
        "max_speed": kind.max_speed,
        "acceleration": kind.acceleration,
        "turn_capability": kind.turn_capability.value,
        "turn_rate": kind.turn_rate,
    }


def encode_task(task: Task) -> dict[str, Any]:
    progress = task.goal_progress.value if task.goal_progress is not None else None
    encoded: dict[str, Any] = {
        "id": task.id,
        "vehicle_id": task.vehicle_id,
        "goal_segment": task.goal_segment,
        "goal_progress": progress,
    }
    if task.order_id is not None:  # 1.5; a task of tasks.csv is written as before
        encoded.update(order_id=task.order_id, stop=task.stop, deadline=task.deadline)
    return encoded


def encode_init(
    layout: Layout,
    fleet: FleetSnapshot,
    planner_options: Mapping[str, Any] | None = None,
    scenario_dir: str | None = None,
) -> dict[str, Any]:
    """The init message, from what the first planner call knows (the layout and the fleet), and the
    suite entry's ``planner_options`` and the scenario's folder, which the planner process is made with."""
    tasks = [task for queue in fleet.tasks.values() for task in queue]
    types = {vid: state.type for vid, state in fleet.vehicles.items()}
    return init_message(layout, types, tasks, planner_options, scenario_dir)


def init_message(
    layout: Layout,
    vehicles: Mapping[int, VehicleType],
    tasks: Iterable[Task],
    planner_options: Mapping[str, Any] | None = None,
    scenario_dir: str | None = None,
) -> dict[str, Any]:
    """The init message of a run on ``layout`` whose ``vehicles`` (each's type, by id) have ``tasks`` at
    its start (a scenario's vehicles and tasks, or the first snapshot's: the same)."""
    types = {kind.name: kind for kind in vehicles.values()}
    return {
        "type": "init",
        "protocol": PROTOCOL,
        "layout": encode_layout(layout),
        "scenario": {
            "vehicle_types": [_vehicle_type(types[name]) for name in sorted(types)],
            "vehicles": [{"id": vid, "type": vehicles[vid].name} for vid in sorted(vehicles)],
            "tasks": [encode_task(task) for task in sorted(tasks, key=lambda task: task.id)],
        },
        "planner_options": dict(planner_options or {}),
        "scenario_dir": scenario_dir,
    }


def _leg(leg: FleetLeg) -> dict[str, Any]:
    return {
        "segment": leg.segment,
        "traverse": _TRAVERSE_WORD[leg.traverse],
        "progress": _PROGRESS_WORD[leg.progress],
        "fixed": leg.fixed,
        "goal_for_task": leg.goal_for_task,
    }


def encode_plan(plan: FleetPlan) -> dict[str, Any]:
    return {"vehicle_id": plan.vehicle_id, "legs": [_leg(leg) for leg in plan.legs]}


def _state(state: VehicleState) -> dict[str, Any]:
    encoded = {
        "id": state.id,
        "segment": state.segment,
        "traverse": _TRAVERSE_WORD[state.traverse],
        "progress": _PROGRESS_WORD[state.progress],
        "distance": state.distance,
        "speed": state.speed,
        "x": state.x,
        "y": state.y,
        "heading": state.heading,
        "type": state.type.name,
    }
    if state.disturbed is not None:  # absent when undisturbed: the messages of 1.0 where nothing is disturbed
        encoded["disturbed"] = state.disturbed.value
    return encoded


def _changes(fleet: FleetSnapshot, previous: FleetSnapshot | None) -> tuple[list[int], list[int], list[int]]:
    """The ids of the vehicles whose state, plan and queue ``fleet`` holds anew since ``previous``
    (every vehicle's when there is no ``previous``), each list sorted."""

    def changed(mapping: Mapping[int, Any], before: Mapping[int, Any] | None) -> list[int]:
        if before is None:
            return sorted(mapping)
        if mapping is before:
            return []  # snapshots share a mapping until something in it changes
        # Unchanged states and plans are the same objects from one snapshot to the next.
        old = before.get
        return sorted(vid for vid in replaced(mapping, before) if mapping[vid] != old(vid))

    if previous is None:
        return changed(fleet.vehicles, None), changed(fleet.plans, None), changed(fleet.tasks, None)
    return (
        changed(fleet.vehicles, previous.vehicles),
        changed(fleet.plans, previous.plans),
        changed(fleet.tasks, previous.tasks),
    )


def encode_fleet(
    fleet: FleetSnapshot, previous: FleetSnapshot | None = None, known: Mapping[int, Task] | None = None
) -> dict[str, Any]:
    """The snapshot, or with ``previous`` (the fleet the planner last saw) only what differs from it:
    the vehicles whose state, the plans and the queues that changed (``time`` and ``routed`` always).
    With ``known`` (the tasks the planner has been sent, by id), the changed queues' other tasks are
    listed in ``new_tasks`` (when there are any)."""
    vehicles, plans, queues = _changes(fleet, previous)
    encoded = {
        "time": fleet.time,
        "vehicles": [_state(fleet.vehicles[vid]) for vid in vehicles],
        "plans": [encode_plan(fleet.plans[vid]) for vid in plans],
        "tasks": [[vid, [task.id for task in fleet.tasks[vid]]] for vid in queues],
        "routed": sorted(fleet.routed),
    }
    new = [] if known is None else _new_tasks(fleet, queues, known)
    if new:
        encoded["new_tasks"] = [encode_task(task) for task in new]
    return encoded


def _new_tasks(fleet: FleetSnapshot, queues: list[int], known: Mapping[int, Task]) -> list[Task]:
    """The tasks of the ``queues`` (vehicle ids) that are not in ``known`` as they are, by id."""
    new = {
        task.id: task
        for vid in queues
        for task in fleet.tasks[vid]
        if (sent := known.get(task.id)) is not task and sent != task
    }
    return [new[tid] for tid in sorted(new)]


class FleetEncoder:
    """:func:`encode_fleet` as JSON, for the requests of one run: the same document, written as bytes
    with each plan encoded on its own and kept, so that an answer handing a plan back unchanged can be
    recognised by its bytes."""

    def __init__(self, tasks: Iterable[Task] | None = None) -> None:
        self.plans: dict[int, tuple[FleetPlan, bytes]] = {}  # vehicle -> its plan as last sent, and its JSON
        self._routed: tuple[AbstractSet[int], bytes] = (frozenset(), b"[]")  # the routed set last sent, as JSON
        # The tasks the process has been sent (the init message's ``tasks``, then ``new_tasks``), by id;
        # without ``tasks``, the init message was made from the first fleet encoded: its tasks.
        self.tasks: dict[int, Task] | None = None if tasks is None else {task.id: task for task in tasks}

    def encode(self, fleet: FleetSnapshot, previous: FleetSnapshot | None = None) -> bytes:
        vehicles, plans, queues = _changes(fleet, previous)
        if self.tasks is None:
            self.tasks = {task.id: task for queue in fleet.tasks.values() for task in queue}
        encoded = []
        for vid in plans:
            plan = fleet.plans[vid]
            self.plans[vid] = (plan, dumps(encode_plan(plan)))
            encoded.append(self.plans[vid][1])
        new = _new_tasks(fleet, queues, self.tasks) if queues else []
        self.tasks.update((task.id, task) for task in new)
        return b'{"time":%b,"vehicles":%b,"plans":[%b],"tasks":%b,"routed":%b%b}' % (
            dumps(fleet.time),
            dumps([_state(fleet.vehicles[vid]) for vid in vehicles]),
            b",".join(encoded),
            dumps([[vid, [task.id for task in fleet.tasks[vid]]] for vid in queues]),
            self._routed_json(fleet.routed),
            b',"new_tasks":' + dumps([encode_task(task) for task in new]) if new else b"",
        )

    def _routed_json(self, routed: AbstractSet[int]) -> bytes:
        """``routed`` as JSON, sorted: encoded again only when the set is another (it changes when a task is
        routed or done, not on every request)."""
        if routed is not self._routed[0]:
            self._routed = (routed, dumps(sorted(routed)))
        return self._routed[1]


def _decode_leg(leg: Mapping[str, Any]) -> FleetLeg:
    return FleetLeg(
        leg["segment"],
        decode_traverse[leg["traverse"]],
        decode_progress[leg["progress"]],
        leg["fixed"],
        leg.get("goal_for_task"),
    )


class LegBook:
    """The legs of a run's messages, each decoded once: a plan mostly repeats legs already seen (its
    fixed legs, a route planned before), and making a leg costs several times looking one up. A leg seen
    again is the same immutable object, which also makes comparing plans a matter of identity. Kept to
    ``LIMIT`` legs (then started afresh), so a long run's book stays small."""

    LIMIT = 1 << 16

    def __init__(self) -> None:
        self._legs: dict[tuple[Any, ...], FleetLeg] = {}

    def leg(self, data: Mapping[str, Any]) -> FleetLeg:
        segment, goal = data["segment"], data.get("goal_for_task")
        if type(segment) is not int or (goal is not None and type(goal) is not int):
            return _decode_leg(data)  # 1.0 for 1, say: made (and refused) as without the book
        key = (segment, data["traverse"], data["progress"], data["fixed"], goal)
        found = self._legs.get(key)
        if found is None:
            if len(self._legs) >= self.LIMIT:
                self._legs.clear()
            found = self._legs[key] = _decode_leg(data)
        return found


def decode_plan(data: Mapping[str, Any], book: LegBook | None = None) -> FleetPlan:
    """A plan from a schema-valid response (the schema has checked names, types and enum words); its legs
    from ``book`` when given."""
    decode = _decode_leg if book is None else book.leg
    return FleetPlan(data["vehicle_id"], tuple(map(decode, data["legs"])))


def decode_response(data: Mapping[str, Any], book: LegBook | None = None) -> list[FleetPlan | RouteError]:
    """The response items of a schema-valid answer; a whole-request route error is raised."""
    if "route_error" in data:
        raise RouteError(None, str(data["route_error"]))
    items: list[FleetPlan | RouteError] = [decode_plan(plan, book) for plan in data["plans"]]
    items += [RouteError(error.get("vehicle_id"), error["message"]) for error in data["route_errors"]]
    return items
