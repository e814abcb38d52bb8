"""Segment labels in the SVG pictures: placed without overlap on dense maps, every one on sparse maps, and the
site's own names drawn when the map has them."""

from __future__ import annotations

import itertools
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from scenario_factory import make_scenario

from fleetsim import load_scenario, load_suite
from fleetsim.cli.main import main
from fleetsim.layout.layout import Layout, build_layout
from fleetsim.planners import ReservingPlanner
from fleetsim.recording.labels import LabelSpace, box_around, nearest_point, spots_beside
from fleetsim.recording.picture import render_frame_svg
from fleetsim.recording.replay import frame_at
from fleetsim.recording.svg import _frame, render_layout_svg
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.strategies import geometry

ROOT = Path(__file__).resolve().parents[2]
SUITES = ROOT / "scenario_suites"
Box = tuple[float, float, float, float]


def scenario_of(suite_file: str, name: str) -> Scenario:
    suite = load_suite(SUITES / suite_file)
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)


def labels(svg: str) -> list[ET.Element]:
    root = ET.fromstring(svg.encode("utf-8"))
    return [e for e in root.iter() if e.get("class") == "segment-label"]


def drawn_box(label: ET.Element) -> Box:
    """The box a label covers as drawn: centred text, at most 0.6 em a character, 1.2 em a line."""
    x, y, font = float(label.get("x", "0")), float(label.get("y", "0")), float(label.get("font-size", "0"))
    half_width, half_height = 0.3 * font * len(label.text or ""), 0.6 * font
    return x - half_width, y - half_height, x + half_width, y + half_height


def overlapping(boxes: list[tuple[str, Box]]) -> list[tuple[str, str]]:
    return [
        (a, b)
        for (a, p), (b, q) in itertools.combinations(boxes, 2)
        if p[0] < q[2] - 1e-6 and q[0] < p[2] - 1e-6 and p[1] < q[3] - 1e-6 and q[1] < p[3] - 1e-6
    ]


def warehouse(junctions: int) -> Layout:
    return build_layout(geometry.quantized(geometry.warehouse(junctions)), vehicle_radius=0.5)


# -- dense maps -----------------------------------------------------------------------------------


def test_a_warehouse_map_is_dense_enough_that_labels_at_their_segments_middles_overlap() -> None:
    # What the placement is for: at each segment's middle, left side (where a label goes first), the
    # labels of a generated warehouse's junctions run into each other.
    layout = warehouse(3)
    letter = 0.24  # the map picture's letter height in metres (0.6 * 0.4 m)
    first = [
        (str(sid), box_around(spots_beside(s, [0.9 * letter])[0], str(sid), letter))
        for sid, s in layout.segments.items()
    ]
    assert len(overlapping(first)) >= 5


@pytest.mark.parametrize("junctions", [3, 5])
def test_no_two_segment_labels_overlap_on_a_generated_warehouse_map(junctions: int) -> None:
    layout = warehouse(junctions)
    drawn = labels(render_layout_svg(layout))
    assert overlapping([(label.get("data-segment", ""), drawn_box(label)) for label in drawn]) == []
    # Fewer labels only where there is no room: most segments keep theirs.
    assert len(drawn) >= 0.9 * len(layout.segments)
    assert len({label.get("data-segment") for label in drawn}) == len(drawn)


def test_no_two_segment_labels_overlap_in_a_failure_picture_of_a_warehouse(tmp_path: Path) -> None:
    segments = tuple(geometry.quantized(geometry.warehouse(3)))
    scenario = make_scenario(tmp_path, segments, "1,1,forward,,agv\n", "1,20,\n")
    result = run_scenario(scenario, ReservingPlanner(), keep_trace=True)
    assert result.trace is not None
    svg = render_frame_svg(scenario, frame_at(scenario, result.trace.lines, 0), caption="t")
    drawn = labels(svg)
    assert len(drawn) >= 0.8 * len(segments)
    assert overlapping([(label.get("data-segment", ""), drawn_box(label)) for label in drawn]) == []


# -- sparse maps ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["crossing", "loop-one-way", "mixed-shapes", "corridor-passing-bay"])
def test_every_segment_of_a_sparse_map_is_labelled_beside_its_middle(name: str) -> None:
    # The narrow negative: where there is room, no label is dropped or moved from its first spot.
    layout = scenario_of("examples.fleetsim.yaml", name).layout
    drawn = labels(render_layout_svg(layout))
    assert [label.text for label in drawn] == [str(sid) for sid in sorted(layout.segments)]  # Tiled: no names
    frame = _frame(layout, margin=1.5, pixels_per_metre=40.0)
    for label in drawn:
        segment = layout.segments[int(label.get("data-segment", "0"))]
        letter = float(label.get("font-size", "0")) / frame.scale
        x, y = frame.point(spots_beside(segment, [0.9 * letter])[0])  # 0.9 letters left of the middle
        assert (float(label.get("x", "0")), float(label.get("y", "0"))) == pytest.approx((x, y), abs=0.01)


# -- site names -----------------------------------------------------------------------------------


def test_an_rmf_maps_lane_names_appear_in_its_picture(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "clinic.svg"
    assert main(["render", str(SUITES / "sites" / "clinic" / "map.building.yaml"), "-o", str(out)]) == 0
    texts = [label.text for label in labels(out.read_text(encoding="utf-8"))]
    assert "1 (lobby--v1)" in texts and "3 (v2--pharmacy)" in texts and "6 (ward_a--ward_b)" in texts
    assert len(texts) == 9  # the first level's lanes of graph 0


def test_a_lif_maps_edge_ids_appear_in_its_failure_picture() -> None:
    scenario = scenario_of("sites.fleetsim.yaml", "packing-hall-lif")
    result = run_scenario(scenario, ReservingPlanner(), keep_trace=True)
    assert result.trace is not None
    svg = render_frame_svg(scenario, frame_at(scenario, result.trace.lines, 10), caption="t")
    texts = {label.text for label in labels(svg)}
    names = {f"{sid} ({segment.name})" for sid, segment in scenario.layout.segments.items() if segment.name}
    assert names and names <= texts


# -- the shared placement -------------------------------------------------------------------------


def test_a_label_takes_the_first_free_spot_and_none_when_every_spot_is_taken() -> None:
    layout = warehouse(1)
    segment = layout.segments[1]
    space = LabelSpace(1.0)
    spots = spots_beside(segment, [0.3, 0.6])
    assert len(spots) == 4 and spots[0][1] > spots[1][1]  # left (north of an eastward straight) first
    assert space.place(spots, "12", 0.25) == (0, box_around(spots[0], "12", 0.25))
    assert space.place(spots, "12", 0.25) == (1, box_around(spots[1], "12", 0.25))
    assert space.place(spots, "12", 0.25) == (2, box_around(spots[2], "12", 0.25))
    space.place(spots, "12", 0.25)
    assert space.place(spots, "12", 0.25) is None and len(space.boxes) == 4
    assert nearest_point((0.0, 0.0, 2.0, 1.0), (5.0, 0.5)) == (2.0, 0.5)
