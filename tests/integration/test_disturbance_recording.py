"""Disturbances under review (issue 20): the frames, the failure picture and the MCAP recording (read
back by mcap_ros2 and by rosbags) mark a disturbed vehicle for exactly its disturbance's duration."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from fleetsim import load_scenario, load_suite
from fleetsim.planners import BFSPlanner
from fleetsim.recording.picture import failure_picture
from fleetsim.recording.recorder import record_mcap
from fleetsim.recording.replay import replay
from fleetsim.scenario import Disturbance, Expectations, Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import RunResult

CAUGHT = Path(__file__).resolve().parents[2] / "scenario_suites" / "caught-bugs.fleetsim.yaml"


@pytest.fixture(scope="module")
def late_crossing() -> tuple[Scenario, RunResult]:
    suite = load_suite(CAUGHT)
    scenario = load_scenario(next(spec for spec in suite.scenarios if spec.name == "late-crossing-stop"), suite)
    # run on after the first alert, so the stop's end is in the trace too; and slow vehicle 2 a while
    scenario = replace(
        scenario,
        settings=replace(scenario.settings, stop_on=()),
        expect=Expectations(),  # so the alert is a failure, with a picture
        disturbances=(*scenario.disturbances, Disturbance(2, "slow", 5.0, at=2.0, factor=0.5)),
    )
    return scenario, run_scenario(scenario, BFSPlanner())


def test_frames_mark_each_disturbed_vehicle_for_exactly_its_duration(late_crossing: tuple[Scenario, RunResult]) -> None:
    scenario, result = late_crossing
    assert result.trace is not None
    stop, slow = sorted(result.disturbances, key=lambda d: d.kind)
    assert stop.end is not None and slow.end is not None
    marked = 0
    for frame in replay(scenario, result.trace.lines):
        for event in (stop, slow):
            during = event.start + 1e-9 < frame.time <= event.end + 1e-9  # frames are stamped at their step's end
            assert (frame.disturbed.get(event.vehicle) == event.kind) == during, (frame.time, event)
            marked += during
    assert marked == round((stop.end - stop.start) / 0.1) + round((slow.end - slow.start) / 0.1)


def test_the_failure_picture_outlines_and_labels_the_stopped_vehicle(late_crossing: tuple[Scenario, RunResult]) -> None:
    scenario, result = late_crossing
    drawn = failure_picture(scenario, result)
    assert drawn is not None
    _, svg = drawn
    assert svg.count('class="vehicle-disturbed"') == 1 and 'data-disturbed="stop"' in svg
    assert ">STOP</text>" in svg and "magenta dashed outline" in svg
    undisturbed = run_scenario(
        replace(scenario, disturbances=(), settings=replace(scenario.settings, stop_on=("collision",))), BFSPlanner()
    )
    assert undisturbed.passed and failure_picture(scenario, undisturbed) is None


def test_the_recording_marks_disturbed_vehicles_for_two_readers(
    late_crossing: tuple[Scenario, RunResult], tmp_path: Path
) -> None:
    scenario, result = late_crossing
    assert result.trace is not None
    path = tmp_path / "run.mcap"
    record_mcap(path, scenario, result.trace.lines)
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        decoded = [(m.log_time / 1e9, v) for _, c, m, v in reader.iter_decoded_messages(topics=["/fleetsim/disturbed"])]
    shown = [
        (t, sorted((k.ns, k.id, k.text, k.header.frame_id, k.frame_locked) for k in v.markers if k.action == 0))
        for t, v in decoded
    ]
    stop, slow = sorted(result.disturbances, key=lambda d: d.kind)
    assert stop.end is not None and slow.end is not None
    # one message per change: when each disturbance begins and when it ends (a step later: frames end steps)
    times = [round(t, 6) for t, _ in shown]
    assert times == sorted(round(x + 0.1, 6) for x in (stop.start, stop.end, slow.start, slow.end))
    first_marked = dict(shown)[times[0]]
    assert ("disturbed_label", 2, "SLOW", "vehicle_2", True) in first_marked
    assert ("disturbed", 2, "", "vehicle_2", True) in first_marked
    assert dict(shown)[times[-1]] == []  # all cleared at the last end
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    with AnyReader([path], default_typestore=typestore) as bag:
        connections = [c for c in bag.connections if c.topic == "/fleetsim/disturbed"]
        again = [bag.deserialize(raw, c.msgtype) for c, _, raw in bag.messages(connections=connections)]
    assert [sorted(k.text for k in msg.markers if k.action == 0) for msg in again] == [
        sorted(k[2] for k in marks) for _, marks in shown
    ]
    assert all(k.color.a > 0 for msg in again for k in msg.markers if k.action == 0)
