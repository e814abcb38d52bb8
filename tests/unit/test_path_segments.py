"""Free-form ``path`` segments: any polyline, loaded from Tiled (also through a template) and treated like
every other segment by joints, conflicts, motion, pictures and recordings."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest
from mcap.reader import make_reader
from scenario_factory import make_scenario

from fleetsim.enums import Direction, JointKind, Shape, Traverse
from fleetsim.layout.layout import build_layout
from fleetsim.layout.segment import Segment
from fleetsim.load.tiled.reader import load_map
from fleetsim.load.tiled.writer import write_map
from fleetsim.planners import ReservingPlanner
from fleetsim.recording.recorder import record_mcap
from fleetsim.recording.svg import render_layout_svg
from fleetsim.sim.loop import run_scenario

ASSETS = Path(__file__).resolve().parents[2] / "scenario_suites" / "tiled"

# A zigzag of five pieces (no template shape looks like this), then a straight that continues it.
ZIGZAG = ((0.0, 0.0), (2.0, 0.0), (3.0, 1.0), (4.0, 0.0), (5.0, 1.0), (7.0, 1.0))


def _tiled_json(tmp_path: Path, objects: list[dict[str, object]]) -> Path:
    path = tmp_path / "map.json"
    path.write_text(
        json.dumps(
            {
                "type": "map",
                "orientation": "orthogonal",
                "width": 20,
                "height": 20,
                "tilewidth": 32,
                "tileheight": 32,
                "infinite": False,
                "layers": [{"type": "objectgroup", "name": "segments", "objects": objects}],
            }
        )
    )
    return path


@pytest.mark.parametrize("spelling", ["path", "Path", "PATH"])
def test_a_polyline_of_class_path_is_a_segment_with_all_its_points(tmp_path: Path, spelling: str) -> None:
    points = [{"x": 32 * x, "y": -32 * y} for x, y in ZIGZAG]
    path = _tiled_json(
        tmp_path, [{"id": 4, "type": spelling, "name": "aisle 4", "x": 320, "y": 320, "polyline": points}]
    )
    (segment,) = load_map(path).segments
    assert segment.shape is Shape.PATH and segment.waypoints == ZIGZAG
    assert segment.name == "aisle 4" and segment.names == ("aisle 4",)


def test_an_unnamed_tiled_object_gives_a_segment_without_a_name(tmp_path: Path) -> None:
    path = _tiled_json(
        tmp_path,
        [
            {
                "id": 1,
                "type": "path",
                "name": "",
                "x": 0,
                "y": 0,
                "polyline": [{"x": 0, "y": 0}, {"x": 32, "y": 0}, {"x": 64, "y": 5}],
            }
        ],
    )
    (segment,) = load_map(path).segments
    assert segment.name is None and segment.names == ()


@pytest.mark.parametrize("suffix", [".tmx", ".json"])
def test_the_path_template_places_a_free_polyline_and_instances_rename_it(tmp_path: Path, suffix: str) -> None:
    reference = os.path.relpath(ASSETS / "path.tx", tmp_path)
    path = tmp_path / ("map" + suffix)
    if suffix == ".tmx":
        path.write_text(
            '<map orientation="orthogonal" width="20" height="20" tilewidth="32" tileheight="32">'
            f'<objectgroup><object id="1" name="bend" template="{reference}" x="320" y="320"/>'
            "</objectgroup></map>"
        )
    else:
        path.write_text(
            json.dumps(
                {
                    "orientation": "orthogonal",
                    "width": 20,
                    "height": 20,
                    "tilewidth": 32,
                    "tileheight": 32,
                    "layers": [
                        {
                            "type": "objectgroup",
                            "objects": [{"id": 1, "name": "bend", "template": reference, "x": 320, "y": 320}],
                        }
                    ],
                }
            )
        )
    (segment,) = load_map(path).segments
    assert segment.shape is Shape.PATH and segment.name == "bend"
    assert len(segment.waypoints) == 6 and segment.first == (0.0, 0.0) and segment.last == (6.0, 1.0)


@pytest.mark.parametrize("suffix", [".tmx", ".json"])
def test_written_path_segments_and_names_load_back(tmp_path: Path, suffix: str) -> None:
    segments = (
        Segment(1, Shape.PATH, Direction.FORWARD, ZIGZAG, ("zig & zag",)),
        Segment(2, Shape.STRAIGHT, Direction.BOTH, ((7.0, 1.0), (9.0, 1.0))),
    )
    loaded = load_map(write_map(tmp_path / ("map" + suffix), segments)).segments
    assert [(s.id, s.shape, s.direction, s.names) for s in loaded] == [
        (1, Shape.PATH, Direction.FORWARD, ("zig & zag",)),
        (2, Shape.STRAIGHT, Direction.BOTH, ()),
    ]
    for a, b in zip(loaded[0].waypoints, ZIGZAG, strict=True):
        assert math.dist(a, b) < 1e-9


def _path_layout(radius: float = 0.3):  # type: ignore[no-untyped-def]
    return build_layout(
        (
            Segment(1, Shape.PATH, Direction.BOTH, ZIGZAG),
            Segment(2, Shape.STRAIGHT, Direction.BOTH, ((7.0, 1.0), (9.0, 1.0))),
            Segment(3, Shape.STRAIGHT, Direction.BOTH, ((7.0, 1.0), (7.0, 3.0))),
            # Parallel to the zigzag's middle tooth, 0.5 m above its peak at (3, 1): only the middle is close.
            Segment(4, Shape.STRAIGHT, Direction.BOTH, ((2.5, 1.5 + 0.2), (3.5, 1.5 + 0.2))),
            Segment(5, Shape.STRAIGHT, Direction.BOTH, ((2.5, 3.0), (3.5, 3.0))),
        ),
        vehicle_radius=radius,
    )


def test_joints_of_a_path_use_its_end_pieces() -> None:
    layout = _path_layout()
    assert layout.joint(1, Traverse.FORWARD, 2, Traverse.FORWARD) is JointKind.SAME
    assert layout.joint(1, Traverse.FORWARD, 3, Traverse.FORWARD) is JointKind.TURN_IN_PLACE
    assert layout.joint(2, Traverse.BACKWARD, 1, Traverse.BACKWARD) is JointKind.SAME


def test_conflicts_of_a_path_measure_every_piece_with_swept_circles() -> None:
    # Segment 4 is 0.7 m from the zigzag's peak: within 2r = 0.8 it conflicts, with 2r = 0.6 it does not.
    assert 4 in _path_layout(radius=0.4).conflicts(1)
    assert 4 not in _path_layout(radius=0.3).conflicts(1)
    assert 5 not in _path_layout(radius=0.4).conflicts(1)


def test_motion_follows_every_piece_of_a_path() -> None:
    segment = Segment(1, Shape.PATH, Direction.BOTH, ZIGZAG)
    assert segment.length == pytest.approx(2 + 3 * math.sqrt(2) + 2)
    x, y, heading = segment.pose_at(2 + math.sqrt(2) / 2, Traverse.FORWARD)
    assert (x, y) == pytest.approx((2.5, 0.5)) and heading == pytest.approx(math.pi / 4)
    x, y, heading = segment.pose_at(2 + math.sqrt(2) / 2, Traverse.BACKWARD)
    assert (x, y) == pytest.approx((4.5, 0.5)) and heading == pytest.approx(-3 * math.pi / 4)


def test_a_run_on_a_path_map_is_drawn_and_recorded_like_any_other(tmp_path: Path) -> None:
    segments = (
        Segment(1, Shape.PATH, Direction.BOTH, ZIGZAG, ("zigzag",)),
        Segment(2, Shape.STRAIGHT, Direction.BOTH, ((7.0, 1.0), (9.0, 1.0))),
    )
    scenario = make_scenario(tmp_path / "run", segments, "1,2,backward,,\n", "1,zigzag,\n")
    assert scenario.tasks[0].goal_segment == 1
    result = run_scenario(scenario, ReservingPlanner())
    assert result.tasks_completed == 1, result.failures
    svg = render_layout_svg(scenario.layout)
    drawn = svg.split('data-segment="1" points="')[1].split('"')[0]
    assert len(drawn.split()) == len(ZIGZAG)  # every corner of the path, not only its ends
    assert result.trace is not None
    record_mcap(tmp_path / "run.mcap", scenario, result.trace.lines)
    with (tmp_path / "run.mcap").open("rb") as stream:
        topics = {channel.topic for _, channel, _ in make_reader(stream).iter_messages()}
    assert "/fleetsim/map" in topics
