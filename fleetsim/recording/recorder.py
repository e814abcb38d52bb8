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
  (``segment 7: 1 ⟂ 2``) beside its middle, placed so that labels do not overlap.
- ``/fleetsim/sim_time``: a text marker with the simulated time.
- ``/fleetsim/disturbed``: a magenta outline and ``STOP``/``SLOW`` round each vehicle a disturbance
  stops or slows, locked to its frame, replaced whenever a disturbance begins or ends.
- ``/fleetsim/stuck``: at the end of a run that deadlocked or ran out of time with tasks pending, who waits
  for whom (namespace ``wait_for``, arrows; ``wait_for_cycle`` red; ``planned_near`` thin), the root-cause
  vehicles (``root_cause``, red discs), the contested segments (``contested``, purple) and the headline
  (``stuck_text``).
- ``/rosout``: rejections, route errors, alerts and an interruption (warnings), planner errors (errors),
  completed tasks.

The file is written under a temporary name and renamed when complete, so an interrupted recording never
leaves a half-written file where a reviewer looks.
"""

from __future__ import annotations

import contextlib
import math
import os
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

from mcap.writer import CompressionType, Writer

from fleetsim import __version__
from fleetsim.enums import Traverse
from fleetsim.layout.segment import Segment
from fleetsim.planning.protocol import FleetPlan
from fleetsim.planning.reservations import CollisionAlert
from fleetsim.recording import messages as m
from fleetsim.recording.cdr import pack_clock
from fleetsim.recording.colours import vehicle_colours
from fleetsim.recording.replay import Frame, replay
from fleetsim.recording.rviz import framed_view
from fleetsim.scenario import Scenario

__all__ = [
    "QOS_TRANSIENT_LOCAL",
    "QOS_VOLATILE",
    "TOPICS",
    "Recording",
    "alert_label",
    "fleet_urdf",
    "partial_path",
    "record_mcap",
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
    "/rosout": ("rcl_interfaces/msg/Log", False),
}

_MAP_GREY = (0.55, 0.58, 0.65, 1.0)
_ORANGE = (1.0, 0.55, 0.0, 1.0)
_WHITE = (1.0, 1.0, 1.0, 1.0)
_WAITS = (0.17, 0.24, 0.31, 1.0)
_CYCLE_RED = (0.82, 0.0, 0.11, 1.0)
_ROOT_RED = (0.82, 0.0, 0.11, 0.45)
_PURPLE = (0.56, 0.27, 0.68, 0.8)
_MAGENTA = (0.9, 0.0, 0.5, 1.0)
_FIXED_WIDTH, _PLANNED_WIDTH, _MAP_WIDTH, _ALERT_WIDTH = 0.18, 0.06, 0.05, 0.35
_INFO, _WARN, _ERROR = 20, 30, 40


@dataclass(frozen=True, slots=True)
class Recording:
    """What a recording wrote."""

    path: Path
    messages: int
    frames: int  # steps recorded in full (with every vehicle's transform)
    size: int  # bytes


def _frame_name(vehicle_id: int) -> str:
    return f"vehicle_{vehicle_id}"


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
        name = _frame_name(vehicle.id)
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


class _Scene:
    """Marker content of one scenario: geometry computed once, plans sent for the vehicles they changed."""

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.colours = vehicle_colours(scenario)
        self.ids = tuple(sorted(v.id for v in scenario.vehicles))
        self.transforms = m.FleetTransforms("map", [_frame_name(vehicle_id) for vehicle_id in self.ids])
        view = framed_view(scenario)
        self.letter = view.letter
        self.top_left = (view.min_x, view.max_y + 2.0 * self.letter)
        self._points: dict[tuple[int, float], m.Points] = {}
        self._shown: dict[int, FleetPlan] = {}  # the plan each vehicle's markers show
        self._sent: dict[tuple[str, int], tuple[tuple[int, Traverse], ...]] = {}  # (namespace, vehicle) -> legs drawn
        # (segment, traverse, z) -> the leg's points in driving order, and the same without the first
        self._paths: dict[tuple[int, Traverse, float], tuple[m.Points, m.Points]] = {}

    def points(self, segments: Iterable[int], z: float) -> m.Points:
        """LINE_LIST points of ``segments`` at height ``z`` (each segment's packed once)."""
        parts: list[m.Points] = []
        for segment in segments:
            cached = self._points.get((segment, z))
            if cached is None:
                cached = self._points[(segment, z)] = m.points(self.scenario.layout.segments[segment].waypoints, z)
            parts.append(cached)
        return m.Points.joined(parts)

    def path(self, legs: Iterable[tuple[int, Traverse]], z: float) -> m.Points:
        """LINE_STRIP points along consecutive legs in driving order (each joint once)."""
        parts: list[m.Points] = []
        for segment, traverse in legs:
            cached = self._paths.get((segment, traverse, z))
            if cached is None:
                waypoints = self.scenario.layout.segments[segment].waypoints
                ordered = m.path_points(waypoints if traverse is Traverse.FORWARD else waypoints[::-1], z)
                cached = self._paths[(segment, traverse, z)] = (ordered, ordered.rest())
            parts.append(cached[1] if parts else cached[0])
        return m.Points.joined(parts)

    def map_markers(self, time: m.Stamp) -> m.MarkerArray:
        pairs = self.points(sorted(self.scenario.layout.segments), 0.0)
        return m.marker_array([m.line_list(time, "segments", 0, pairs, _MAP_WIDTH, _MAP_GREY)])

    def labels(self, time: m.Stamp) -> m.MarkerArray:
        markers = []
        for vehicle in sorted(self.scenario.vehicles, key=lambda v: v.id):
            at = (0.0, 0.0, vehicle.type.height + 0.4)
            size = max(0.25, 0.6 * vehicle.type.width)
            markers.append(
                m.text_marker(
                    time, _frame_name(vehicle.id), "labels", vehicle.id, str(vehicle.id), at, size, _WHITE, True
                )
            )
        return m.marker_array(markers)

    def plans(self, time: m.Stamp, plans: Mapping[int, FleetPlan], replanned: Iterable[int]) -> m.MarkerArray | None:
        """Markers for the plans that changed since the last call (``None``: none did).

        ``replanned``: the vehicles whose plans may have changed since the last call, in id order (every
        vehicle at the first call). Each vehicle has two markers, its fixed legs and its planned legs;
        only a marker whose segments changed is sent again (passing a leg changes the fixed ones only),
        an emptied one is deleted.
        """
        markers = [] if self._shown else [m.delete_all(time, "")]
        for vehicle_id in replanned:
            plan = plans[vehicle_id]
            if self._shown.get(vehicle_id) is plan:
                continue
            self._shown[vehicle_id] = plan
            for namespace, fixed, width in (("fixed", True, _FIXED_WIDTH), ("planned", False, _PLANNED_WIDTH)):
                legs = tuple((leg.segment, leg.traverse) for leg in plan.legs if leg.fixed is fixed)
                key = (namespace, vehicle_id)
                if self._sent.get(key, ()) == legs:
                    continue
                self._sent[key] = legs
                if legs:
                    path = self.path(legs, 0.02)
                    markers.append(m.line_strip(time, namespace, vehicle_id, path, width, self.colours[vehicle_id]))
                else:
                    markers.append(m.delete(time, namespace, vehicle_id))
        return m.marker_array(markers) if markers else None

    def alerts(self, time: m.Stamp, alerts: Sequence[CollisionAlert]) -> m.MarkerArray:
        """The alert segments in orange and a short label each (``segment 7: 1 ⟂ 2``) beside its middle.

        Labels are placed one by one, each at the first spot near its segment's middle where it does not
        overlap a label placed before it (the full thesis text goes to ``/rosout``).
        """
        markers = [m.delete_all(time, "")]
        placed: list[tuple[float, float, float, float]] = []
        for number, alert in enumerate(alerts):
            markers.append(
                m.line_list(time, "alert_segments", number, self.points([alert.segment], 0.05), _ALERT_WIDTH, _ORANGE)
            )
            text = alert_label(alert)
            x, y = self._free_spot(self.scenario.layout.segments[alert.segment], text, placed)
            markers.append(m.text_marker(time, "map", "alert_text", number, text, (x, y, 1.0), self.letter, _ORANGE))
        return m.marker_array(markers)

    def _free_spot(
        self, segment: Segment, text: str, placed: list[tuple[float, float, float, float]]
    ) -> tuple[float, float]:
        """A spot beside ``segment``'s middle where ``text`` overlaps no box in ``placed`` (which it joins)."""
        mx, my, heading = segment.pose_at(segment.length / 2, Traverse.FORWARD)
        half_w, half_h = 0.3 * self.letter * len(text), 0.6 * self.letter
        nx, ny = -math.sin(heading), math.cos(heading)  # left of the segment
        step = 1.4 * self.letter
        spots = [(mx + side * k * step * nx, my + side * k * step * ny) for k in range(1, 12) for side in (1, -1)]
        box = (0.0, 0.0, 0.0, 0.0)
        for x, y in spots:
            box = (x - half_w, y - half_h, x + half_w, y + half_h)
            if not any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3] for b in placed):
                break
        placed.append(box)
        return (box[0] + box[2]) / 2, (box[1] + box[3]) / 2

    def stuck(self, time: m.Stamp, poses: Mapping[int, Any], stuck: Mapping[str, Any]) -> m.MarkerArray:
        """Who waits for whom at the end of a stuck run (the failure's details, as in result.json)."""
        markers = [m.delete_all(time, "")]
        contested = sorted(
            {int(s) for f in stuck.get("vehicles", ()) for s in f.get("contested", ())}
            & set(self.scenario.layout.segments)
        )
        if contested:
            markers.append(m.line_list(time, "contested", 0, self.points(contested, 0.04), 0.4, _PURPLE))
        in_cycle = {(int(c[i]), int(c[(i + 1) % len(c)])) for c in stuck.get("cycles", ()) for i in range(len(c))}
        numbers: dict[str, int] = {}
        for finding in stuck.get("vehicles", ()):
            source = int(finding["vehicle"])
            relations = [(int(b), True) for b in finding.get("blocked_by", ())] + [
                (int(b), False) for b in finding.get("planned_near", ())
            ]
            for target, waits in relations:
                if source not in poses or target not in poses:
                    continue
                cycle = (source, target) in in_cycle
                namespace = ("wait_for_cycle" if cycle else "wait_for") if waits else "planned_near"
                numbers[namespace] = numbers.get(namespace, -1) + 1
                a, b = poses[source], poses[target]
                start, end = (a.x, a.y, 0.6), (b.x, b.y, 0.6)
                colour = _CYCLE_RED if cycle else _WAITS
                markers.append(
                    m.arrow(time, namespace, numbers[namespace], start, end, 0.12 if waits else 0.05, colour)
                )
        radius = {v.id: v.type.swept_radius for v in self.scenario.vehicles}
        roots = sorted({int(v) for root in stuck.get("roots", ()) for v in root.get("vehicles", ())} & set(poses))
        for number, vid in enumerate(roots):
            markers.append(
                m.disc(time, "root_cause", number, (poses[vid].x, poses[vid].y, 0.02), 2 * radius[vid] + 0.5, _ROOT_RED)
            )
        x, y = self.top_left
        headline = str(stuck.get("headline", ""))
        if headline:
            markers.append(
                m.text_marker(
                    time, "map", "stuck_text", 0, headline, (x, y + 1.5 * self.letter, 0.0), self.letter, _CYCLE_RED
                )
            )
        return m.marker_array(markers)

    def disturbed(self, time: m.Stamp, disturbed: Mapping[int, str]) -> m.MarkerArray:
        """A magenta outline round each disturbed vehicle and STOP/SLOW above it, locked to its frame."""
        markers = [m.delete_all(time, "")]
        types = {v.id: v.type for v in self.scenario.vehicles}
        for vid, kind in disturbed.items():
            half_length, half_width = 0.5 * types[vid].length + 0.25, 0.5 * types[vid].width + 0.25
            corners = [
                (half_length, half_width),
                (-half_length, half_width),
                (-half_length, -half_width),
                (half_length, -half_width),
            ]
            outline = m.path_points([*corners, corners[0]], 0.05)
            markers.append(m.line_strip(time, "disturbed", vid, outline, 0.08, _MAGENTA, frame=_frame_name(vid)))
            at = (0.0, 0.0, types[vid].height + 0.9)
            markers.append(
                m.text_marker(time, _frame_name(vid), "disturbed_label", vid, kind.upper(), at, 0.4, _MAGENTA, True)
            )
        return m.marker_array(markers)

    def sim_time(self, time: m.Stamp, seconds: float) -> m.MarkerArray:
        x, y = self.top_left
        return m.marker_array(
            [m.text_marker(time, "map", "sim_time", 0, f"t = {seconds:.2f} s", (x, y, 0.0), self.letter, _WHITE)]
        )


def alert_label(alert: CollisionAlert) -> str:
    """``segment 7: 1 ⟂ 2``: the segment, its primary holders, then the others (the short form)."""
    primary = ",".join(map(str, alert.primary))
    secondary = ",".join(map(str, alert.secondary))
    return (
        f"segment {alert.segment}: {primary} \u27c2 {secondary}" if secondary else f"segment {alert.segment}: {primary}"
    )


def _log_lines(event: Sequence[Any]) -> tuple[int, str] | None:
    kind = event[0]
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
    bag: _Bag, scenario: Scenario, frames: Iterable[Frame], every: int, stuck: Mapping[str, Any] | None = None
) -> int:
    """Write the frames; the number written in full (with ``/tf``).

    Every ``every``-th step, the first and the last are written in full: the clock, every vehicle's
    transform, the sim time. Steps in between write the clock and what changed (plans, alerts, log
    lines) and nothing else, so a change is shown when it happened whatever the rate.
    """
    scene = _Scene(scenario)
    full = 0
    shown_alerts: tuple[CollisionAlert, ...] | None = None
    for frame, last in _with_last(frames):
        first = shown_alerts is None
        tick = first or last or frame.step % every == 0
        alerts_changed = frame.alerts != shown_alerts
        if tick or frame.plans_changed or frame.events or alerts_changed:
            _write_frame(bag, scene, frame, first=first, tick=tick, alerts_changed=alerts_changed)
            shown_alerts = frame.alerts
            full += tick
        if last and stuck:
            time_ns = round(frame.time * 1e9)
            time = m.stamp(time_ns)
            bag.write("/fleetsim/stuck", time_ns, scene.stuck(time, frame.poses, stuck))
            if stuck.get("headline"):
                bag.write("/rosout", time_ns, m.log(time, _ERROR, str(stuck["headline"])))
    return full


def _write_frame(bag: _Bag, scene: _Scene, frame: Frame, *, first: bool, tick: bool, alerts_changed: bool) -> None:
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
    for event in frame.events:
        line = _log_lines(event)
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
) -> Recording:
    """Write the run of ``scenario`` whose trace is ``trace_lines`` to ``path`` (``.mcap``).

    ``every``: record every N-th step in full (the first and the last always); the steps between write
    only what changed in them (plans, alerts, log lines), so no change is lost at a lower rate.
    ``stuck``: the details of the run's deadlock or timeout failure (as in ``result.json``, with its
    ``headline``); who waits for whom is drawn on ``/fleetsim/stuck`` at the last step.
    """
    if every < 1:
        msg = f"every={every!r} must be a whole number of steps >= 1"
        raise ValueError(msg)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = partial_path(path)
    try:
        with partial.open("wb") as stream:
            bag = _Bag(stream)
            frames = _write_frames(bag, scenario, replay(scenario, trace_lines), every, stuck)
            bag.writer.finish()  # type: ignore[no-untyped-call]  # mcap's Writer.finish has no annotations
        os.replace(partial, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            partial.unlink()
    return Recording(path, bag.count, frames, path.stat().st_size)
