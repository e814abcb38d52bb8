"""MCAP recordings (SPEC §11) read back by two independent readers: mcap + mcap_ros2, and rosbags."""

from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import sys
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from fleetsim import load_scenario, load_suite
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.recording import messages as m
from fleetsim.recording.recorder import TOPICS, record_mcap
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "scenario_suites" / "examples.fleetsim.yaml"
LATCHED = {"/tf_static", "/robot_description", "/fleetsim/map", "/fleetsim/labels"}


def example(name: str) -> Scenario:
    suite = load_suite(EXAMPLES)
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)


@dataclass
class Decoded:
    topic: str
    schema: str
    log_time: int
    publish_time: int
    message: Any


def read_mcap(path: Path) -> tuple[Any, list[Decoded]]:
    """Every message in file order, decoded by mcap_ros2 from the schemas in the file."""
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        decoded = [
            Decoded(channel.topic, schema.name, message.log_time, message.publish_time, value)
            for schema, channel, message, value in reader.iter_decoded_messages(log_time_order=False)
        ]
        return (reader.get_header(), summary), decoded


def raw_messages(path: Path, topics: tuple[str, ...]) -> list[tuple[str, int, bytes]]:
    with path.open("rb") as stream:
        return [
            (channel.topic, message.log_time, message.data)
            for _, channel, message in make_reader(stream).iter_messages(topics=list(topics))
        ]


@pytest.fixture(scope="module")
def collision_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Scenario, Path, Any]:
    scenario = example("crossing")
    result = run_scenario(scenario, BFSPlanner())
    assert result.collisions, "the BFS planner collides on the crossing"
    path = tmp_path_factory.mktemp("collision") / "run.mcap"
    assert result.trace is not None
    recording = record_mcap(path, scenario, result.trace.lines)
    return scenario, path, recording


@pytest.fixture(scope="module")
def long_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Scenario, Path, Any]:
    scenario = example("mixed-shapes")
    result = run_scenario(scenario, ReservingPlanner())
    assert result.trace is not None
    path = tmp_path_factory.mktemp("long") / "run.mcap"
    return scenario, path, record_mcap(path, scenario, result.trace.lines)


def both_runs(collision_run: Any, long_run: Any) -> Iterator[tuple[Scenario, Path]]:
    for scenario, path, _ in (collision_run, long_run):
        yield scenario, path


def test_profile_encodings_schema_names_and_statistics(collision_run: Any, long_run: Any) -> None:
    for _, path in both_runs(collision_run, long_run):
        (header, summary), messages = read_mcap(path)
        assert header.profile == "ros2"
        assert summary.statistics is not None and summary.statistics.message_count == len(messages)
        assert {channel.topic for channel in summary.channels.values()} == set(TOPICS)
        for channel in summary.channels.values():
            assert channel.message_encoding == "cdr"
            schema = summary.schemas[channel.schema_id]
            assert schema.encoding == "ros2msg"
            assert re.fullmatch(r"[a-z0-9_]+/msg/[A-Za-z0-9]+", schema.name)
            assert schema.name == TOPICS[channel.topic][0]
        assert {message.schema for message in messages} <= {name for name, _ in TOPICS.values()}


def test_every_channel_offers_qos_in_the_integer_yaml_form(collision_run: Any) -> None:
    (_, summary), _ = read_mcap(collision_run[1])
    for channel in summary.channels.values():
        profiles = yaml.safe_load(channel.metadata["offered_qos_profiles"])
        assert isinstance(profiles, list) and len(profiles) == 1
        profile = profiles[0]
        for key in ("history", "depth", "reliability", "durability", "liveliness"):
            assert type(profile[key]) is int, (channel.topic, key)
        for key in ("deadline", "lifespan", "liveliness_lease_duration"):
            assert set(profile[key]) == {"sec", "nsec"} and all(type(v) is int for v in profile[key].values())
        assert profile["avoid_ros_namespace_conventions"] is False
        assert profile["durability"] == (1 if channel.topic in LATCHED else 2), channel.topic
        assert profile["reliability"] == 1


def _stamp_ns(stamp: Any) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def _stamps(message: Decoded) -> list[int]:
    value = message.message
    if message.topic == "/clock":
        return [_stamp_ns(value.clock)]
    if message.schema == "tf2_msgs/msg/TFMessage":
        return [_stamp_ns(t.header.stamp) for t in value.transforms]
    if message.schema == "visualization_msgs/msg/MarkerArray":
        return [_stamp_ns(marker.header.stamp) for marker in value.markers]
    if message.topic == "/rosout":
        return [_stamp_ns(value.stamp)]
    return []


def test_log_time_is_the_header_stamp_and_the_clock_never_zero_never_decreasing(
    collision_run: Any, long_run: Any
) -> None:
    for _, path in both_runs(collision_run, long_run):
        _, messages = read_mcap(path)
        clock = {message.log_time for message in messages if message.topic == "/clock"}
        previous = 0
        for message in messages:
            assert message.log_time > 0
            assert message.log_time >= previous, "file order is time order"
            previous = message.log_time
            assert message.publish_time == message.log_time
            assert message.log_time in clock, f"{message.topic} at a time with no /clock"
            assert all(stamp == message.log_time for stamp in _stamps(message)), message.topic


def _markers(messages: list[Decoded]) -> Iterator[tuple[str, Any]]:
    for message in messages:
        if message.schema == "visualization_msgs/msg/MarkerArray":
            for marker in message.message.markers:
                yield message.topic, marker


def test_markers_are_visible_well_formed_and_line_lists_have_pairs(collision_run: Any, long_run: Any) -> None:
    for _, path in both_runs(collision_run, long_run):
        _, messages = read_mcap(path)
        kinds = set()
        for topic, marker in _markers(messages):
            if marker.action in (2, 3):  # DELETE / DELETEALL
                continue
            kinds.add(marker.type)
            assert marker.color.a > 0, (topic, marker.ns)
            q = marker.pose.orientation
            assert math.isclose(q.x**2 + q.y**2 + q.z**2 + q.w**2, 1.0, rel_tol=1e-9)
            if marker.type == 5:
                assert len(marker.points) % 2 == 0 and marker.points, (topic, marker.ns)
            if marker.type == 4:
                assert len(marker.points) >= 2
            if marker.type == 9:
                assert marker.text and marker.scale.z > 0
            else:
                assert marker.scale.x > 0
        assert {4, 5, 9} <= kinds


def test_transforms_are_unit_quaternions_for_every_vehicle_every_step(long_run: Any) -> None:
    scenario, path, recording = long_run
    _, messages = read_mcap(path)
    frames = {f"vehicle_{v.id}" for v in scenario.vehicles}
    tf = [message.message for message in messages if message.topic == "/tf"]
    assert len(tf) == recording.frames
    for message in tf:
        assert {t.child_frame_id for t in message.transforms} == frames
        for t in message.transforms:
            assert t.header.frame_id == "map"
            q = t.transform.rotation
            assert math.isclose(q.x**2 + q.y**2 + q.z**2 + q.w**2, 1.0, rel_tol=1e-9)


def test_the_urdf_has_a_root_and_one_floating_jointed_link_per_vehicle(long_run: Any) -> None:
    scenario, path, _ = long_run
    _, messages = read_mcap(path)
    [description] = [message.message.data for message in messages if message.topic == "/robot_description"]
    robot = ET.fromstring(description)
    links = {link.get("name"): link for link in robot.iter("link")}
    assert set(links) == {"fleet"} | {f"vehicle_{v.id}" for v in scenario.vehicles}
    joints = list(robot.iter("joint"))
    assert len(joints) == len(scenario.vehicles)
    assert all(j.get("type") == "floating" and j.find("parent").get("link") == "fleet" for j in joints)  # type: ignore[union-attr]
    for vehicle in scenario.vehicles:
        visuals = links[f"vehicle_{vehicle.id}"].findall("visual")
        assert [v.find("geometry")[0].tag for v in visuals] == ["box", "cylinder"]  # type: ignore[index]
        alpha = float(visuals[0].find("material/color").get("rgba").split()[3])  # type: ignore[union-attr]
        assert alpha > 0
    [static] = [message.message for message in messages if message.topic == "/tf_static"]
    assert [(t.header.frame_id, t.child_frame_id) for t in static.transforms] == [("map", "fleet")]


def test_collision_alerts_show_orange_segments_and_are_logged(collision_run: Any) -> None:
    _, path, _ = collision_run
    _, messages = read_mcap(path)
    alert_markers = [
        marker for topic, marker in _markers(messages) if topic == "/fleetsim/alerts" and marker.action == 0
    ]
    assert any(marker.ns == "alert_segments" for marker in alert_markers)
    texts = [marker.text for marker in alert_markers if marker.type == 9]
    assert texts and all(re.fullmatch(r"segment \d+: [\d,]+( \u27c2 [\d,]+)?", text) for text in texts)
    orange = [marker.color for marker in alert_markers if marker.ns == "alert_segments"]
    assert all(c.r == 1.0 and 0.4 < c.g < 0.7 and c.b == 0.0 for c in orange)
    logs = [message.message for message in messages if message.topic == "/rosout"]
    assert any(log.level == 30 and log.msg.startswith("COLLISION ALERT") for log in logs)


def test_rosbags_reads_every_message_too(collision_run: Any, long_run: Any) -> None:
    for _, path in both_runs(collision_run, long_run):
        _, expected = read_mcap(path)
        seen = []
        with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
            for connection, timestamp, raw in reader.messages():
                message = reader.deserialize(raw, connection.msgtype)
                assert message.__msgtype__ == connection.msgtype
                seen.append((connection.topic, timestamp))
        assert sorted(seen) == sorted((message.topic, message.log_time) for message in expected)


def test_recording_every_nth_step_keeps_changes_and_the_last_step(tmp_path: Path) -> None:
    scenario = example("loop-one-way")
    result = run_scenario(scenario, ReservingPlanner())
    assert result.trace is not None
    every_step = record_mcap(tmp_path / "all.mcap", scenario, result.trace.lines)
    sparse = record_mcap(tmp_path / "sparse.mcap", scenario, result.trace.lines, every=10)
    assert every_step.frames == result.steps
    assert sparse.frames < every_step.frames / 2
    _, messages = read_mcap(tmp_path / "sparse.mcap")
    clock = [message.log_time for message in messages if message.topic == "/clock"]
    assert clock[-1] == round(result.sim_time * 1e9), "the last step is always recorded"
    tf = [message.log_time for message in messages if message.topic == "/tf"]
    assert len(tf) == sparse.frames and tf[-1] == clock[-1]
    steps = [round(time / 1e8) - 1 for time in tf]  # a step of 0.1 s ends at (step + 1) * 0.1 s
    assert steps == sorted({*range(0, result.steps, 10), result.steps - 1})
    changes = ("/fleetsim/plans", "/fleetsim/alerts", "/rosout")  # kept whatever the rate, byte for byte
    assert raw_messages(tmp_path / "sparse.mcap", changes) == raw_messages(tmp_path / "all.mcap", changes)
    with pytest.raises(ValueError, match="every=0 must be"):
        record_mcap(tmp_path / "bad.mcap", scenario, result.trace.lines, every=0)


def test_messages_are_strict_a_missing_or_misspelt_field_raises() -> None:
    colour = m._type("std_msgs/msg/ColorRGBA")
    with pytest.raises(TypeError):
        colour(r=1.0, g=0.5, b=0.0)  # no alpha: must not become an invisible 0
    with pytest.raises(TypeError):
        colour(r=1.0, g=0.5, b=0.0, alpah=1.0)


def test_the_packed_tf_message_is_byte_identical_to_the_typestores() -> None:
    children = [f"vehicle_{k}" for k in (1, 7, 12, 100, 3, 12345)]
    fast = m.FleetTransforms("map", children)
    poses = [(1.5 * k, -0.25 * k, 0.1 * k - 2.0) for k in range(len(children))]
    assert fast._fast
    assert fast.serialise(3_141_592_653, poses) == fast._slow(3_141_592_653, poses)
    with pytest.raises(ValueError, match="one pose per frame"):
        fast.serialise(1, poses[:-1])


KILLER = """
import os, signal, sys
from pathlib import Path
from mcap.writer import Writer
from fleetsim import load_scenario, load_suite
from fleetsim.planners import ReservingPlanner
from fleetsim.recording.recorder import record_mcap
from fleetsim.sim.loop import run_scenario
suite = load_suite(sys.argv[1])
scenario = load_scenario(next(s for s in suite.scenarios if s.name == "loop-one-way"), suite)
result = run_scenario(scenario, ReservingPlanner())
added = Writer.add_message
count = [0]
def add_then_die(self, *args, **kwargs):
    count[0] += 1
    if count[0] == 40:
        os.kill(os.getpid(), signal.SIGKILL)  # killed midway through writing
    return added(self, *args, **kwargs)
Writer.add_message = add_then_die
record_mcap(Path(sys.argv[2]), scenario, result.trace.lines)
"""


def test_a_recording_killed_midway_never_leaves_a_half_written_file(tmp_path: Path) -> None:
    target = tmp_path / "run.mcap"
    scenario = example("loop-one-way")
    result = run_scenario(scenario, ReservingPlanner())
    assert result.trace is not None
    previous = record_mcap(target, scenario, result.trace.lines[:20])  # an earlier, complete recording
    before = target.read_bytes()
    process = subprocess.run(
        [sys.executable, "-c", KILLER, str(EXAMPLES), str(target)], capture_output=True, text=True, timeout=120
    )
    assert process.returncode == -signal.SIGKILL, process.stderr
    assert target.read_bytes() == before, "the complete file is untouched"
    _, messages = read_mcap(target)
    assert len(messages) == previous.messages
    leftovers = [p.name for p in tmp_path.iterdir() if p.name != "run.mcap"]
    assert leftovers == [".run.mcap.partial"], "only the hidden partial file remains"
    # The next recording replaces both.
    record_mcap(target, scenario, result.trace.lines)
    assert sorted(os.listdir(tmp_path)) == ["run.mcap"]
