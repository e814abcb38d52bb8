"""Recording a run as one MCAP file that RViz 2 (through ``ros2 bag play``) and Foxglove replay (SPEC §11).

The recording is drawn from the run's trace (:mod:`fleetsim.recording.replay`), so it shows exactly what
the hashed trace says happened and costs nothing while the simulation runs. The file follows the ros2
profile: CDR messages, ``ros2msg`` schemas named ``pkg/msg/Type``, zstd chunks, a statistics record, and
on every channel the ``offered_qos_profiles`` metadata in the integer YAML form that rosbag2 on Humble
and Jazzy both parse (without it nothing latches on playback). Every message's log time equals its
header stamp and the ``/clock`` value of its step: never 0, never decreasing.

Topics:

- ``/clock``; ``/tf`` (map → ``vehicle_<id>`` every recorded step); ``/tf_static`` (map → ``fleet``).
- ``/robot_description``: one URDF for the fleet — root link ``fleet``, one link per vehicle (box body,
  cylinder rear bumper showing the heading, in the vehicle's colour) joined to it by a floating joint
  (RViz draws nothing for a URDF with several roots).
- ``/fleetsim/map``: the segments (LINE_LIST); ``/fleetsim/labels``: vehicle ids, locked to their frames.
- ``/fleetsim/plans``: each vehicle's plan in its colour, fixed legs thick, planned legs thin.
- ``/fleetsim/alerts``: segments of the collision alerts in force, orange, each with a short label
  (``segment 7: 1 ⟂ 2``) beside its middle, placed so that labels do not overlap; a label pushed further
  out gets a leader line back to the segment's middle (namespace ``alert_leaders``).
- ``/fleetsim/sim_time``: a text marker with the simulated time.
- ``/fleetsim/disturbed``: a magenta outline and ``STOP``/``SLOW`` round each vehicle a disturbance
  stops or slows, locked to its frame, replaced whenever a disturbance begins or ends.
- ``/fleetsim/stuck``: at the end of a run that deadlocked or ran out of time with tasks pending, who waits
  for whom (namespace ``wait_for``, arrows; ``wait_for_cycle`` red; ``planned_near`` thin), the root-cause
  vehicles (``root_cause``, red discs), the contested segments (``contested``, purple) and the headline
  (``stuck_text``).
- ``/fleetsim/contacts``: a red disc where each contact began (``contact``) and ``contact 1 ⟂ 2`` above it
  (``contact_label``), from the step the contact began in on (the contact check of :mod:`fleetsim.contact`).
- ``/fleetsim/orders``: in a run with transport orders (:mod:`fleetsim.recording.orders`), an amber disc
  and ``3 waiting: s4 s7 s9`` at each station where orders wait (``waiting``, ``waiting_text``) and each
  vehicle's order above it, locked to its frame, in its colour (``order_labels``: ``s12 1/2 loaded
  dwell``; ``STALLED`` in red), replaced whenever they change.
- ``/rosout``: rejections, route errors, alerts, an interruption and stalls (with the orders held up)
  (warnings), planner errors and contacts (errors), completed tasks, released, assigned and completed
  orders and served stops.

The file is written under a temporary name and renamed when complete, so an interrupted recording never
leaves a half-written file where a reviewer looks.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

from mcap.writer import CompressionType, Writer

from fleetsim.planning.reservations import CollisionAlert
from fleetsim.recording import messages as m
from fleetsim.recording.cdr import pack_clock
from fleetsim.recording.colours import vehicle_colours
from fleetsim.recording.orders import OrderChanges, OrderTracker
from fleetsim.recording.replay import Frame, collector_paused, replay
from fleetsim.recording.scene import Scene, frame_name
from fleetsim.scenario import Scenario
from fleetsim.version import __version__

__all__ = [
    "QOS_TRANSIENT_LOCAL",
    "QOS_VOLATILE",
    "TOPICS",
    "Recording",
    "fleet_urdf",
    "partial_path",
    "record_mcap",
    "write_frame",
]


def _qos(durability: int, depth: int) -> str:
    # rmw enums as integers: history 1 keep_last, reliability 1 reliable, durability 1 transient_local /
    # 2 volatile, liveliness 1 automatic; zero durations mean "default" (no deadline, no lifespan).
    return (
        f"- history: 1\n  depth: {depth}\n  reliability: 1\n  durability: {durability}\n"
        "  deadline:\n    sec: 0\n    nsec: 0\n  lifespan:\n    sec: 0\n    nsec: 0\n"
        "  liveliness: 1\n  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
        "  avoid_ros_namespace_conventions: false\n"
    )


QOS_TRANSIENT_LOCAL = _qos(1, 1)
QOS_VOLATILE = _qos(2, 10)

_ARRAY = "visualization_msgs/msg/MarkerArray"
# topic -> (message type, latched)
TOPICS: dict[str, tuple[str, bool]] = {
    "/clock": ("rosgraph_msgs/msg/Clock", False),
    "/robot_description": ("std_msgs/msg/String", True),
    "/tf_static": ("tf2_msgs/msg/TFMessage", True),
    "/tf": ("tf2_msgs/msg/TFMessage", False),
    "/fleetsim/map": (_ARRAY, True),
    "/fleetsim/labels": (_ARRAY, True),
    "/fleetsim/plans": (_ARRAY, False),
    "/fleetsim/alerts": (_ARRAY, False),
    "/fleetsim/sim_time": (_ARRAY, False),
    "/fleetsim/stuck": (_ARRAY, False),
    "/fleetsim/disturbed": (_ARRAY, False),
    "/fleetsim/contacts": (_ARRAY, False),
    "/fleetsim/orders": (_ARRAY, False),
    "/rosout": ("rcl_interfaces/msg/Log", False),
}

_INFO, _WARN, _ERROR = 20, 30, 40


@dataclass(frozen=True, slots=True)
class Recording:
    """What a recording wrote."""

    path: Path
    messages: int
    frames: int  # steps recorded in full (with every vehicle's transform)
    size: int  # bytes


def fleet_urdf(scenario: Scenario) -> str:
    """One robot for the whole fleet: root link ``fleet``, one floating-jointed link per vehicle."""
    colours = vehicle_colours(scenario)
    parts = [
        '<?xml version="1.0"?>',
        f"<robot name={quoteattr('fleetsim_' + scenario.name)}>",
        '  <link name="fleet"/>',
    ]
    for vehicle in sorted(scenario.vehicles, key=lambda v: v.id):
        kind = vehicle.type
        name = frame_name(vehicle.id)
        rgba = " ".join(f"{c:.3f}" for c in colours[vehicle.id])
        bumper = min(kind.width, kind.length) / 4.0
        parts += [
            f'  <link name="{name}">',
            f'    <visual name="body"><origin xyz="0 0 {kind.height / 2:.4f}"/>'
            f'<geometry><box size="{kind.length:.4f} {kind.width:.4f} {kind.height:.4f}"/></geometry>'
            f'<material name="{name}_colour"><color rgba="{rgba}"/></material></visual>',
            f'    <visual name="rear_bumper"><origin xyz="{-kind.length / 2:.4f} 0 {kind.height / 2:.4f}"/>'
            f'<geometry><cylinder radius="{bumper:.4f}" length="{kind.height:.4f}"/></geometry>'
            f'<material name="{name}_colour"><color rgba="{rgba}"/></material></visual>',
            "  </link>",
            f'  <joint name="{name}_joint" type="floating"><parent link="fleet"/><child link="{name}"/></joint>',
        ]
    parts.append("</robot>")
    return "\n".join(parts) + "\n"


class _Bag:
    """The MCAP writer with the ros2 channels registered and per-channel sequence numbers."""

    def __init__(self, stream: Any) -> None:
        self.writer = Writer(stream, compression=CompressionType.ZSTD)
        self.writer.start(profile="ros2", library=f"fleetsim {__version__}")
        self.channels: dict[str, int] = {}
        self.sequence: dict[str, int] = {}
        self.count = 0
        schemas: dict[str, int] = {}
        for topic, (typename, latched) in TOPICS.items():
            if typename not in schemas:
                schemas[typename] = self.writer.register_schema(typename, "ros2msg", m.schema_text(typename))
            qos = QOS_TRANSIENT_LOCAL if latched else QOS_VOLATILE
            self.channels[topic] = self.writer.register_channel(
                topic, "cdr", schemas[typename], {"offered_qos_profiles": qos}
            )
            self.sequence[topic] = 0

    def write(self, topic: str, time_ns: int, message: Any) -> None:
        self.write_bytes(topic, time_ns, m.serialise(message))

    def write_bytes(self, topic: str, time_ns: int, data: bytes) -> None:
        self.sequence[topic] += 1
        self.writer.add_message(self.channels[topic], time_ns, data, time_ns, self.sequence[topic])
        self.count += 1


def _log_lines(event: Sequence[Any], orders: OrderTracker | None = None) -> tuple[int, str] | None:
    kind = event[0]
    if kind in ("release", "assign", "served", "order-done", "stall"):
        return _order_line(event, orders)
    if kind == "complete":
        return _INFO, f"task {event[1]} completed"
    if kind == "reject":
        return _WARN, f"plan rejected: {event[1]} (vehicle {event[2]}, leg {event[3]})"
    if kind == "route-error":
        return _WARN, f"route error for vehicle {event[1]}: {event[2]}"
    if kind == "alert":
        alert = CollisionAlert(event[1], tuple(event[2]), tuple(event[3]))
        return _WARN, alert.text()
    if kind == "planner-error":
        return _ERROR, f"planner error for vehicle {event[1]}"
    if kind == "interrupted":
        return _WARN, f"run interrupted by {event[1]}: it ends here"
    if kind in ("disturb", "resume"):
        return _INFO, f"vehicle {event[1]} {'disturbed' if kind == 'disturb' else 'resumes'}: {event[2]}"
    return None


def _order_line(event: Sequence[Any], orders: OrderTracker | None) -> tuple[int, str]:
    kind = event[0]
    if kind == "release":
        return _INFO, f"order {event[1]} released"
    if kind == "assign":
        return _INFO, f"vehicle {event[1]} assigned orders: {', '.join(event[2]) if event[2] else 'none'}"
    if kind == "served":
        return _INFO, f"vehicle {event[1]} served stop {event[3] + 1} of order {event[2]}"
    if kind == "order-done":
        return _INFO, f"order {event[1]} completed"
    held = orders.carry_of(int(event[1])).orders if orders is not None else ()
    return (
        _WARN,
        f"vehicle {event[1]} stalled: it has work and has not moved; orders held up: {', '.join(held) or 'none'}",
    )


def _with_last(frames: Iterable[Frame]) -> Iterator[tuple[Frame, bool]]:
    """Each frame, and whether it is the last."""
    previous: Frame | None = None
    for frame in frames:
        if previous is not None:
            yield previous, False
        previous = frame
    if previous is not None:
        yield previous, True


def _write_frames(
    bag: _Bag,
    scenario: Scenario,
    frames: Iterable[Frame],
    every: int,
    stuck: Mapping[str, Any] | None = None,
    contacts: Sequence[Mapping[str, Any]] = (),
    orders: OrderTracker | None = None,
) -> int:
    """Write the frames; the number written in full (with ``/tf``). ``orders``: the run's orders, followed
    frame by frame (a run with transport orders).

    Every ``every``-th step, the first and the last are written in full: the clock, every vehicle's
    transform, the sim time. Steps in between write the clock and what changed (plans, alerts, log
    lines) and nothing else, so a change is shown when it happened whatever the rate.
    """
    scene = Scene(scenario)
    full = 0
    shown_alerts: tuple[CollisionAlert, ...] | None = None
    pending = sorted(contacts, key=lambda c: float(c["time"]))
    shown = 0  # contacts marked so far
    for frame, last in _with_last(frames):
        first = shown_alerts is None
        tick = first or last or frame.step % every == 0
        alerts_changed = frame.alerts != shown_alerts
        due = shown
        while due < len(pending) and float(pending[due]["time"]) <= frame.time + 1e-9:
            due += 1  # a contact belongs to the step it began in: the one that ends at or after it
        changes = orders.follow(frame) if orders is not None and orders.active else None
        if tick or frame.plans_changed or frame.events or alerts_changed or due > shown or changes:
            write_frame(
                bag, scene, frame, first=first, tick=tick, alerts_changed=alerts_changed, orders=orders, changes=changes
            )
            shown_alerts = frame.alerts
            full += tick
        if due > shown:
            time_ns = round(frame.time * 1e9)
            time = m.stamp(time_ns)
            bag.write("/fleetsim/contacts", time_ns, scene.contacts(time, pending[:due]))
            for contact in pending[shown:due]:
                a, b = contact["vehicles"]
                words = f"contact: vehicles {a} and {b} touched at t = {float(contact['time']):.2f} s at ({float(contact['x']):.2f}, {float(contact['y']):.2f})"
                bag.write("/rosout", time_ns, m.log(time, _ERROR, words))
            shown = due
        if last and stuck:
            time_ns = round(frame.time * 1e9)
            time = m.stamp(time_ns)
            bag.write("/fleetsim/stuck", time_ns, scene.stuck(time, frame.poses, stuck))
            if stuck.get("headline"):
                bag.write("/rosout", time_ns, m.log(time, _ERROR, str(stuck["headline"])))
    return full


def write_frame(
    bag: Any,
    scene: Scene,
    frame: Frame,
    *,
    first: bool,
    tick: bool,
    alerts_changed: bool,
    orders: OrderTracker | None = None,
    changes: OrderChanges | None = None,
) -> None:
    """One frame's messages into ``bag`` (anything with ``write(topic, time_ns, message)`` and
    ``write_bytes(topic, time_ns, data)``: this module's MCAP writer, or a live Foxglove server):
    ``first`` adds the latched topics, ``tick`` the transforms and sim time. ``orders``: the run's orders
    after this frame, and ``changes`` what it changed of them (a run with transport orders)."""
    time_ns = round(frame.time * 1e9)
    time = m.stamp(time_ns)
    bag.write_bytes("/clock", time_ns, pack_clock(time))
    if first:
        bag.write("/robot_description", time_ns, m.string(fleet_urdf(scene.scenario)))
        bag.write("/tf_static", time_ns, m.tf_message([m.transform(time, "map", "fleet", 0.0, 0.0, 0.0)]))
        bag.write("/fleetsim/map", time_ns, scene.map_markers(time))
        bag.write("/fleetsim/labels", time_ns, scene.labels(time))
    if tick:
        poses = frame.poses
        planar = [poses[vehicle_id][3:6] for vehicle_id in scene.ids]  # Pose fields 3-5: (x, y, heading)
        bag.write_bytes("/tf", time_ns, scene.transforms.serialise(time_ns, planar))
    if first or frame.plans_changed:
        plans = scene.plans(time, frame.plans, scene.ids if first else frame.replanned)
        if plans is not None:
            bag.write("/fleetsim/plans", time_ns, plans)
    if first or alerts_changed:
        bag.write("/fleetsim/alerts", time_ns, scene.alerts(time, frame.alerts))
    if tick:
        bag.write("/fleetsim/sim_time", time_ns, scene.sim_time(time, frame.time))
    if any(event[0] in ("disturb", "resume") for event in frame.events):
        bag.write("/fleetsim/disturbed", time_ns, scene.disturbed(time, frame.disturbed))
    if (
        orders is not None
        and orders.active
        and (first or (changes is not None and (changes.vehicles or changes.stations)))
    ):
        bag.write("/fleetsim/orders", time_ns, scene.orders(time, orders))
    for event in frame.events:
        line = _log_lines(event, orders)
        if line is not None:
            bag.write("/rosout", time_ns, m.log(time, line[0], line[1]))


def partial_path(path: Path) -> Path:
    """Where the recording for ``path`` is written until it is complete: ``.run.mcap.partial`` beside it.
    A writer killed outright leaves it; ``fleetsim record --trace`` replaces it with a complete file."""
    return path.with_name(f".{path.name}.partial")


def record_mcap(
    path: Path,
    scenario: Scenario,
    trace_lines: Sequence[str],
    *,
    every: int = 1,
    stuck: Mapping[str, Any] | None = None,
    contacts: Sequence[Mapping[str, Any]] = (),
) -> Recording:
    """Write the run of ``scenario`` whose trace is ``trace_lines`` to ``path`` (``.mcap``).

    ``every``: record every N-th step in full (the first and the last always); the steps between write
    only what changed in them (plans, alerts, log lines), so no change is lost at a lower rate.
    ``stuck``: the details of the run's deadlock or timeout failure (as in ``result.json``, with its
    ``headline``); who waits for whom is drawn on ``/fleetsim/stuck`` at the last step. ``contacts``: the
    run's contacts (as in ``result.json``), each marked on ``/fleetsim/contacts`` from the step it began in.
    """
    if every < 1:
        msg = f"every={every!r} must be a whole number of steps >= 1"
        raise ValueError(msg)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = partial_path(path)
    try:
        with partial.open("wb") as stream:
            bag = _Bag(stream)
            orders = OrderTracker.of_trace(trace_lines)
            with collector_paused():  # hundreds of thousands of markers, points and bytes, no cycles
                frames = _write_frames(bag, scenario, replay(scenario, trace_lines), every, stuck, contacts, orders)
            bag.writer.finish()  # type: ignore[no-untyped-call]  # mcap's Writer.finish has no annotations
        os.replace(partial, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            partial.unlink()
    return Recording(path, bag.count, frames, path.stat().st_size)
