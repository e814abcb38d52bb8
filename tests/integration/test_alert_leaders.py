"""An RViz alert label pushed away from its segment to avoid another label gets a leader line back to it,
read from the MCAP file with mcap + mcap_ros2."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from fleetsim import load_scenario, load_suite
from fleetsim.enums import Traverse
from fleetsim.planners import BFSPlanner
from fleetsim.recording.recorder import record_mcap
from fleetsim.recording.rviz import framed_view
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario

EXAMPLES = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"


def crossing(size: float) -> Scenario:
    """The shipped crossing with its vehicles ``size`` times as long and wide (labels follow their size)."""
    suite = load_suite(EXAMPLES)
    scenario = load_scenario(next(spec for spec in suite.scenarios if spec.name == "crossing"), suite)
    return replace(
        scenario,
        vehicles=tuple(
            replace(v, type=replace(v.type, length=size * v.type.length, width=size * v.type.width))
            for v in scenario.vehicles
        ),
    )


def alert_arrays(scenario: Scenario, folder: Path) -> list[Any]:
    """The ``/fleetsim/alerts`` marker arrays of a BFS run (both vehicles cross at once: four alerts)."""
    result = run_scenario(scenario, BFSPlanner())
    assert result.trace is not None and result.collisions
    path = record_mcap(folder / "run.mcap", scenario, result.trace.lines).path
    with path.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        return [
            value
            for _, channel, _, value in reader.iter_decoded_messages(topics=["/fleetsim/alerts"])
            if channel.topic == "/fleetsim/alerts"
        ]


def labels_and_leaders(scenario: Scenario, array: Any) -> list[tuple[Any, Any, tuple[float, float]]]:
    """Each alert label, its leader line (or None), and its segment's middle."""
    markers = [marker for marker in array.markers if marker.action == 0]
    leaders = {marker.id: marker for marker in markers if marker.ns == "alert_leaders"}
    found = []
    for label in (marker for marker in markers if marker.ns == "alert_text"):
        segment = scenario.layout.segments[int(label.text.split(":")[0].removeprefix("segment "))]
        x, y, _ = segment.pose_at(segment.length / 2, Traverse.FORWARD)
        found.append((label, leaders.pop(label.id, None), (x, y)))
    assert leaders == {}, "a leader line without its label"
    return found


def test_a_displaced_alert_label_has_a_leader_line_to_its_segments_middle(tmp_path: Path) -> None:
    # Vehicles three times the size: 1.05 m letters, and the labels of the crossing's two vertical arms
    # cannot sit beside them without covering the horizontal arms' labels.
    scenario = crossing(3.0)
    letter = framed_view(scenario).letter
    arrays = [a for a in alert_arrays(scenario, tmp_path) if any(m.ns == "alert_text" for m in a.markers)]
    assert arrays
    displaced = beside = 0
    for array in arrays:
        for label, leader, (mx, my) in labels_and_leaders(scenario, array):
            away = math.dist((label.pose.position.x, label.pose.position.y), (mx, my))
            if away > 1.4 * letter + 1e-6:  # further out than the spots right beside the middle
                displaced += 1
                assert leader is not None, label.text
                assert leader.type == 5 and leader.header.frame_id == "map" and len(leader.points) == 2
                assert (leader.color.r, leader.color.g, leader.color.b) == (label.color.r, label.color.g, label.color.b)
                start, end = leader.points
                assert (end.x, end.y) == pytest.approx((mx, my))  # it ends at the segment's middle
                half_w, half_h = 0.3 * letter * len(label.text), 0.6 * letter
                # ... and starts on the label's box, the edge nearest that middle
                assert abs(start.x - label.pose.position.x) <= half_w + 1e-6
                assert abs(start.y - label.pose.position.y) <= half_h + 1e-6
                assert math.dist((start.x, start.y), (mx, my)) < away
            else:
                beside += 1
                assert leader is None, label.text
    assert displaced >= 2 and beside >= 2


def test_labels_beside_their_segments_get_no_leader_line(tmp_path: Path) -> None:
    # The narrow negative: the crossing as shipped has room for all four labels beside their segments.
    scenario = crossing(1.0)
    found = [found for array in alert_arrays(scenario, tmp_path) for found in labels_and_leaders(scenario, array)]
    assert len(found) >= 4
    assert all(leader is None for _, leader, _ in found)
