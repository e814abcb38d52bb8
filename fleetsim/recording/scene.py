"""What a recording's markers show: the map, labels, plans, alerts, sim time, disturbances, who waits for whom,
transport orders.

:class:`Scene` makes the marker arrays of one scenario's recording (SPEC §11), computing its geometry once:
segment points are packed once per segment, each vehicle's plan markers are sent again only when their
legs change. What is written when, and to which topic, is :mod:`fleetsim.recording.recorder`'s.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from fleetsim.enums import Traverse
from fleetsim.layout.segment import Point
from fleetsim.planning.plans import FleetPlan
from fleetsim.planning.reservations import CollisionAlert
from fleetsim.recording import messages as m
from fleetsim.recording.colours import ALERT, CONTESTED, CYCLE, DISTURBED, MAP_RVIZ, WAITS, vehicle_colours, with_alpha
from fleetsim.recording.labels import Label, LabelLayout, Placed, nearest_point, spots_beside
from fleetsim.recording.orders import OrderTracker
from fleetsim.recording.rviz import framed_view
from fleetsim.recording.stuck import contested_segments, root_vehicles, stuck_relations
from fleetsim.scenario import Scenario

__all__ = ["Scene", "alert_label", "frame_name"]

_WHITE = (1.0, 1.0, 1.0, 1.0)
_AMBER = (1.0, 179 / 255, 0.0, 1.0)  # orders waiting at a station
_ROOT_RED = with_alpha(CYCLE, 0.45)
_PURPLE = with_alpha(CONTESTED, 0.8)
_FIXED_WIDTH, _PLANNED_WIDTH, _MAP_WIDTH, _ALERT_WIDTH, _LEADER_WIDTH = 0.18, 0.06, 0.05, 0.35, 0.04


def frame_name(vehicle_id: int) -> str:
    """The TF frame (and URDF link) of a vehicle: ``vehicle_<id>``."""
    return f"vehicle_{vehicle_id}"


class Scene:
    """Marker content of one scenario: geometry computed once, plans sent for the vehicles they changed."""

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.colours = vehicle_colours(scenario)
        self.ids = tuple(sorted(v.id for v in scenario.vehicles))
        self.transforms = m.FleetTransforms("map", [frame_name(vehicle_id) for vehicle_id in self.ids])
        view = framed_view(scenario)
        self.letter = view.letter
        self.top_left = (view.min_x, view.max_y + 2.0 * self.letter)
        self._points: dict[tuple[int, float], m.Points] = {}
        self._shown: dict[int, FleetPlan] = {}  # the plan each vehicle's markers show
        self._sent: dict[tuple[str, int], tuple[tuple[int, Traverse], ...]] = {}  # (namespace, vehicle) -> legs drawn
        # (segment, traverse, z) -> the leg's points in driving order, and the same without the first
        self._paths: dict[tuple[int, Traverse, float], tuple[m.Points, m.Points]] = {}
        self._alert_labels = LabelLayout(8.0 * self.letter, self.letter)  # kept from step to step
        self._offsets = [k * 1.4 * self.letter for k in range(1, 12)]
        self._beside: dict[int, tuple[list[Point], Point]] = {}  # segment -> label spots beside it, its middle
        # The last step's alert markers (at time 0, id 0) by segment, label text and spot taken
        self._alert_shapes: dict[tuple[int, str, int], tuple[m.Marker, ...]] = {}

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
        return m.marker_array([m.line_list(time, "segments", 0, pairs, _MAP_WIDTH, MAP_RVIZ)])

    def labels(self, time: m.Stamp) -> m.MarkerArray:
        markers = []
        for vehicle in sorted(self.scenario.vehicles, key=lambda v: v.id):
            at = (0.0, 0.0, vehicle.type.height + 0.4)
            size = max(0.25, 0.6 * vehicle.type.width)
            markers.append(
                m.text_marker(
                    time, frame_name(vehicle.id), "labels", vehicle.id, str(vehicle.id), at, size, _WHITE, True
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

        Labels are placed by :mod:`fleetsim.recording.labels`, each at the first spot beside its segment's
        middle where it overlaps no label placed before it (every spot taken: the farthest). A label
        pushed further out than the spots right beside the middle gets a thin orange leader line
        (namespace ``alert_leaders``, same id) from its nearest edge to the segment's middle. The full
        thesis text goes to ``/rosout``.
        """
        markers = [m.delete_all(time, "")]
        texts = [alert_label(alert) for alert in alerts]
        labels = [
            Label((alert.segment, text), self._spots(alert.segment)[0], text)
            for alert, text in zip(alerts, texts, strict=True)
        ]
        places = self._alert_labels.place(labels)
        drawn: dict[tuple[int, str, int], tuple[m.Marker, ...]] = {}
        for number, (alert, text, place) in enumerate(zip(alerts, texts, places, strict=True)):
            key = (alert.segment, text, place.spot)  # the spot gives the box
            shapes = self._alert_shapes.get(key)
            if shapes is None:
                shapes = self._alert_markers(alert.segment, text, place)
            drawn[key] = shapes
            markers += [shape.restamped(time, number) for shape in shapes]
        self._alert_shapes = drawn  # the last step's only: most alerts stay from one step to the next
        return m.marker_array(markers)

    def _alert_markers(self, segment: int, text: str, place: Placed) -> tuple[m.Marker, ...]:
        """An alert's segment, label and leader line (if it has one), at time 0 with id 0."""
        time = m.stamp(0)
        box = place.box
        centre = ((box[0] + box[2]) / 2, (box[1] + box[3]) / 2, 1.0)
        shapes = [
            m.line_list(time, "alert_segments", 0, self.points([segment], 0.05), _ALERT_WIDTH, ALERT),
            m.text_marker(time, "map", "alert_text", 0, text, centre, self.letter, ALERT),
        ]
        if place.spot >= 2:  # the first two spots are beside the middle, left and right
            mx, my = self._spots(segment)[1]
            ex, ey = nearest_point(box, (mx, my))
            ends = m.Points.of([(ex, ey, 1.0), (mx, my, 0.05)])
            shapes.append(m.line_list(time, "alert_leaders", 0, ends, _LEADER_WIDTH, ALERT))
        return tuple(shapes)

    def _spots(self, segment_id: int) -> tuple[list[Point], Point]:
        """The label spots beside a segment's middle, nearest first, and the middle (each worked out once)."""
        known = self._beside.get(segment_id)
        if known is None:
            segment = self.scenario.layout.segments[segment_id]
            mx, my, _ = segment.pose_at(segment.length / 2, Traverse.FORWARD)
            known = self._beside[segment_id] = (spots_beside(segment, self._offsets), (mx, my))
        return known

    def stuck(self, time: m.Stamp, poses: Mapping[int, Any], stuck: Mapping[str, Any]) -> m.MarkerArray:
        """Who waits for whom at the end of a stuck run (the failure's details, as in result.json)."""
        markers = [m.delete_all(time, "")]
        contested = [s for s in contested_segments(stuck) if s in self.scenario.layout.segments]
        if contested:
            markers.append(m.line_list(time, "contested", 0, self.points(contested, 0.04), 0.4, _PURPLE))
        numbers: dict[str, int] = {}
        for source, target, waits, cycle in stuck_relations(stuck):
            if source not in poses or target not in poses:
                continue
            namespace = ("wait_for_cycle" if cycle else "wait_for") if waits else "planned_near"
            numbers[namespace] = numbers.get(namespace, -1) + 1
            a, b = poses[source], poses[target]
            start, end = (a.x, a.y, 0.6), (b.x, b.y, 0.6)
            colour = CYCLE if cycle else WAITS
            markers.append(m.arrow(time, namespace, numbers[namespace], start, end, 0.12 if waits else 0.05, colour))
        radius = {v.id: v.type.swept_radius for v in self.scenario.vehicles}
        roots = [v for v in root_vehicles(stuck) if v in poses]
        for number, vid in enumerate(roots):
            markers.append(
                m.disc(time, "root_cause", number, (poses[vid].x, poses[vid].y, 0.02), 2 * radius[vid] + 0.5, _ROOT_RED)
            )
        x, y = self.top_left
        headline = str(stuck.get("headline", ""))
        if headline:
            markers.append(
                m.text_marker(
                    time, "map", "stuck_text", 0, headline, (x, y + 1.5 * self.letter, 0.0), self.letter, CYCLE
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
            markers.append(m.line_strip(time, "disturbed", vid, outline, 0.08, DISTURBED, frame=frame_name(vid)))
            at = (0.0, 0.0, types[vid].height + 0.9)
            markers.append(
                m.text_marker(time, frame_name(vid), "disturbed_label", vid, kind.upper(), at, 0.4, DISTURBED, True)
            )
        return m.marker_array(markers)

    def contacts(self, time: m.Stamp, contacts: Sequence[Mapping[str, Any]]) -> m.MarkerArray:
        """A red disc where each contact so far began, and ``contact 1 ⟂ 2`` above it."""
        markers = [m.delete_all(time, "")]
        for index, contact in enumerate(contacts):
            x, y = float(contact["x"]), float(contact["y"])
            a, b = contact["vehicles"]
            markers.append(m.disc(time, "contact", index, (x, y, 0.06), 0.7, CYCLE))
            markers.append(
                m.text_marker(
                    time, "map", "contact_label", index, f"contact {a} \u27c2 {b}", (x, y, 1.2), self.letter, CYCLE
                )
            )
        return m.marker_array(markers)

    def orders(self, time: m.Stamp, orders: OrderTracker) -> m.MarkerArray:
        """The transport orders now: an amber disc and ``3 waiting: s4 s7 s9`` at each station where orders
        wait (``waiting``, ``waiting_text``), and each vehicle's order above it, locked to its frame
        (``order_labels``: ``s12 1/2``, ``loaded``, ``dwell``, ``STALLED``), in its colour."""
        markers = [m.delete_all(time, "")]
        state = orders.state()
        layout = self.scenario.layout
        number = 0
        for segment, waiting in state.waiting.items():
            if segment not in layout.segments:
                continue
            x, y, _ = layout.segments[segment].pose_at(layout.segments[segment].length / 2, Traverse.FORWARD)
            shown = " ".join(waiting[:5]) + (" ..." if len(waiting) > 5 else "")
            markers.append(m.disc(time, "waiting", number, (x, y, 0.03), 0.8, _AMBER))
            text = f"{len(waiting)} waiting: {shown}"
            at = (x, y + 1.2 * self.letter, 0.8)
            markers.append(m.text_marker(time, "map", "waiting_text", number, text, at, self.letter, _AMBER))
            number += 1
        types = {v.id: v.type for v in self.scenario.vehicles}
        for vid, carry in state.carry.items():
            words = []
            if carry.orders:
                words.append(carry.orders[0] + (f" {carry.stop + 1}/{carry.stops}" if carry.stops else ""))
                words += ["loaded"] if carry.loaded else []
                words += ["dwell"] if carry.dwell is not None else []
            words += ["STALLED"] if carry.stalled else []
            at = (0.0, 0.0, types[vid].height + 1.4)
            colour = CYCLE if carry.stalled else self.colours[vid]
            markers.append(
                m.text_marker(time, frame_name(vid), "order_labels", vid, " ".join(words), at, 0.4, colour, True)
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
