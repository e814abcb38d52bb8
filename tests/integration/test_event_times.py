"""One clock for events: what result.json reports at time t is in the recording at exactly t.

A reviewer who reads "collision at t = 0.20 s" and seeks to 0.20 s in RViz or Foxglove must see the
alert, its log line and the fleet of that moment; the same for rejections, route errors and planner
errors. Read back with the mcap library's own ROS 2 decoder.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from fleetsim import load_scenario, load_suite
from fleetsim.enums import Traverse
from fleetsim.layout import Layout
from fleetsim.planners import BFSPlanner
from fleetsim.planning.plans import FleetLeg, FleetPlan, Response, RouteError
from fleetsim.planning.snapshot import FleetSnapshot
from fleetsim.recording.artifacts import write_run_artifacts
from fleetsim.recording.rviz import framed_view
from fleetsim.scenario import Scenario, Task
from fleetsim.sim.loop import run_scenario

SUITE = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"


def example(name: str, **settings: Any) -> Scenario:
    suite = load_suite(SUITE)
    scenario = load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)
    return replace(scenario, settings=replace(scenario.settings, **settings))


class Troubled(BFSPlanner):
    """BFS routes, but vehicle 2 first gets route errors for 0.3 s and then one plan the checks refuse."""

    def plan_routes(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        if task.vehicle_id == 2 and fleet.time < 0.25:
            return [RouteError(2, "map not ready")]
        if task.vehicle_id == 2 and fleet.time < 0.35:
            current = fleet.plans[2].legs
            return [FleetPlan(2, (*current, FleetLeg(999, current[-1].traverse, current[-1].progress, False)))]
        return super().plan_routes(task, fleet, layout)


class Raises(BFSPlanner):
    def fix_legs(self, task: Task, fleet: FleetSnapshot, layout: Layout) -> Response:
        if fleet.time > 0.45:
            raise ValueError("planner bug")
        return super().fix_legs(task, fleet, layout)


def recorded(
    tmp_path: Path, scenario: Scenario, planner: Any
) -> tuple[dict[str, Any], list[tuple[str, int, Any]], Path]:
    result = run_scenario(scenario, planner)
    paths = write_run_artifacts(tmp_path / "run", result, scenario=scenario)
    document = json.loads(Path(paths["result"]).read_text(encoding="utf-8"))
    with open(paths["mcap"], "rb") as stream:
        messages = [
            (channel.topic, message.log_time, decoded)
            for _, channel, message, decoded in make_reader(
                stream, decoder_factories=[DecoderFactory()]
            ).iter_decoded_messages()
        ]
    return document, messages, Path(paths["folder"])


def ns(seconds: float) -> int:
    return round(seconds * 1e9)


def test_each_alert_is_on_the_alerts_topic_first_at_exactly_its_reported_time(tmp_path: Path) -> None:
    document, messages, _ = recorded(tmp_path, example("crossing", stop_on=()), BFSPlanner())
    assert document["collisions"]
    shown: dict[int, int] = {}  # segment -> first time a label shows it
    for topic, time, message in messages:
        if topic == "/fleetsim/alerts":
            for marker in message.markers:
                if marker.ns == "alert_text":
                    segment = int(marker.text.split(":")[0].removeprefix("segment "))
                    shown.setdefault(segment, time)
    firsts: dict[int, float] = {}
    for alert in document["collisions"]:
        firsts.setdefault(alert["segment"], alert["time"])
    assert {segment: ns(time) for segment, time in firsts.items()} == shown
    for alert in document["collisions"]:
        lines = [m.msg for topic, time, m in messages if topic == "/rosout" and time == ns(alert["time"])]
        assert alert["text"] in lines
    # The clock and the fleet's transforms are there at that moment too.
    first = ns(document["collisions"][0]["time"])
    assert {topic for topic, time, _ in messages if time == first} >= {"/clock", "/tf", "/fleetsim/alerts", "/rosout"}


def test_rejections_and_route_errors_are_logged_at_exactly_their_reported_times(tmp_path: Path) -> None:
    document, messages, _ = recorded(tmp_path, example("crossing", stop_on=()), Troubled())
    logs = [(time, m.msg) for topic, time, m in messages if topic == "/rosout"]
    assert len(document["route_errors"]) == 3 and len(document["rejections"]) == 1
    for error in document["route_errors"]:
        assert (ns(error["time"]), f"route error for vehicle {error['vehicle']}: {error['message']}") in logs
    [rejection] = document["rejections"]
    assert (rejection["time"], rejection["code"]) == (pytest.approx(0.4), "unknown-segment")
    assert (ns(rejection["time"]), f"plan rejected: unknown-segment (vehicle 2, leg {rejection['leg_index']})") in logs
    failure = next(f for f in document["failures"] if f["kind"] == "rejection")
    assert failure["time"] == rejection["time"] and failure["plan"][-1]["segment"] == 999


def test_a_planner_error_is_logged_at_its_reported_time_and_ends_the_recording(tmp_path: Path) -> None:
    document, messages, _ = recorded(tmp_path, example("crossing", stop_on=()), Raises())
    [failure] = [f for f in document["failures"] if f["kind"] == "planner-error"]
    errors = [time for topic, time, m in messages if topic == "/rosout" and m.level == 40]
    assert errors == [ns(failure["time"])]
    assert max(time for _, time, _ in messages) == ns(failure["time"]) == ns(document["sim_time"])


def test_the_rviz_layout_frames_the_scenarios_map_and_says_to_use_sim_time(tmp_path: Path) -> None:
    scenario = example("crossing")
    _, _, folder = recorded(tmp_path, scenario, BFSPlanner())
    text = (folder / "fleetsim.rviz").read_text(encoding="utf-8")
    assert "use_sim_time:=true" in text.split("Panels:")[0]
    view = yaml.safe_load(text)["Visualization Manager"]["Views"]["Current"]
    xs = [x for s in scenario.layout.segments.values() for x, _ in s.waypoints]
    ys = [y for s in scenario.layout.segments.values() for _, y in s.waypoints]
    assert (view["X"], view["Y"]) == (
        pytest.approx((min(xs) + max(xs)) / 2, abs=1e-3),
        pytest.approx((min(ys) + max(ys)) / 2, abs=1e-3),
    )
    # The whole map fits the render area, and fills a good part of it.
    span = max((max(xs) - min(xs)) * view["Scale"] / 1050, (max(ys) - min(ys)) * view["Scale"] / 800)
    assert 0.5 < span <= 1.0


def test_a_large_map_far_from_the_origin_is_framed_too(tmp_path: Path) -> None:
    scenario = example("mixed-shapes")
    moved = replace(
        scenario.layout,
        segments={
            sid: replace(s, waypoints=tuple((x + 500.0, y - 300.0) for x, y in s.waypoints))
            for sid, s in scenario.layout.segments.items()
        },
    )
    view = framed_view(replace(scenario, layout=moved))
    assert view.centre[0] > 400 and view.centre[1] < -200
    assert view.letter * view.scale >= 14.0  # legible at the framed view


def test_alert_labels_sit_beside_their_segments_middles_and_do_not_overlap(tmp_path: Path) -> None:
    scenario = example("crossing", stop_on=())
    _, messages, _ = recorded(tmp_path, scenario, BFSPlanner())
    letter = framed_view(scenario).letter
    for topic, _, message in messages:
        if topic != "/fleetsim/alerts":
            continue
        labels = [m for m in message.markers if m.ns == "alert_text"]
        boxes = []
        for label in labels:
            segment = scenario.layout.segments[int(label.text.split(":")[0].removeprefix("segment "))]
            mx, my, _ = segment.pose_at(segment.length / 2, Traverse.FORWARD)
            x, y = label.pose.position.x, label.pose.position.y
            assert 0 < ((x - mx) ** 2 + (y - my) ** 2) ** 0.5 < 12 * 1.4 * letter + 1e-6  # beside its middle
            assert label.scale.z == pytest.approx(letter) and len(label.text) < 30
            half_w, half_h = 0.3 * letter * len(label.text), 0.6 * letter
            boxes.append((x - half_w, y - half_h, x + half_w, y + half_h))
        for i, a in enumerate(boxes):
            for b in boxes[i + 1 :]:
                assert not (a[0] < b[2] - 1e-9 and b[0] < a[2] - 1e-9 and a[1] < b[3] - 1e-9 and b[1] < a[3] - 1e-9)
