"""The still picture of a run's moment: map, plans, vehicles, alerts in orange, caption; vehicle colours."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.recording.colours import palette_colour, svg_colour, vehicle_colours
from fleetsim.recording.picture import failure_caption, failure_picture, failure_step, render_frame_svg
from fleetsim.recording.replay import Frame, frame_at
from fleetsim.scenario import Scenario
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.result import Failure, RunResult

SUITE = Path(__file__).resolve().parents[2] / "scenario_suites" / "examples.fleetsim.yaml"
SVG = "{http://www.w3.org/2000/svg}"
ORANGE = "#ff8c00"


def example(name: str) -> Scenario:
    suite = load_suite(SUITE)
    return load_scenario(next(spec for spec in suite.scenarios if spec.name == name), suite)


@pytest.fixture(scope="module")
def crossing() -> Scenario:
    return example("crossing")


@pytest.fixture(scope="module")
def collided(crossing: Scenario) -> RunResult:
    """BFS plans both vehicles straight across the junction at once: collision alerts in step 1."""
    return run_scenario(crossing, BFSPlanner(), keep_trace=True)


def frame(scenario: Scenario, result: RunResult, step: int) -> Frame:
    assert result.trace is not None
    return frame_at(scenario, result.trace.lines, step)


def parse(svg: str) -> ET.Element:
    return ET.fromstring(svg.encode("utf-8"))


def of_class(root: ET.Element, name: str) -> list[ET.Element]:
    return [e for e in root.iter() if name in e.get("class", "").split()]


def corners(element: ET.Element) -> list[tuple[float, float]]:
    pairs = [pair.split(",") for pair in element.get("points", "").split()]
    return [(float(x), float(y)) for x, y in pairs]


# -- the picture ----------------------------------------------------------------------------------


def test_the_caption_is_the_first_text_on_top_and_is_escaped(crossing: Scenario, collided: RunResult) -> None:
    caption = 't = 0.20 s — a <b> & "c"\nsecond line'
    root = parse(render_frame_svg(crossing, frame(crossing, collided, 1), caption=caption))
    [text] = of_class(root, "caption-text")
    assert text.text == 't = 0.20 s — a <b> & "c" second line'
    map_top = min(y for e in of_class(root, "segment") for _, y in corners(e))
    assert float(text.get("y", "0")) < map_top


def test_one_vehicle_shape_per_vehicle_with_nose_and_id(crossing: Scenario, collided: RunResult) -> None:
    root = parse(render_frame_svg(crossing, frame(crossing, collided, 1), caption="x"))
    vehicles = of_class(root, "vehicle")
    assert [v.get("data-vehicle") for v in vehicles] == ["1", "2"]
    for group in vehicles:
        [body] = of_class(group, "vehicle-body")
        [nose] = of_class(group, "vehicle-nose")
        [label] = of_class(group, "vehicle-label")
        assert (len(corners(body)), len(corners(nose)), label.text) == (4, 3, group.get("data-vehicle"))


def test_a_vehicle_is_drawn_lengthwise_along_its_heading_with_the_nose_in_front(crossing: Scenario, collided: RunResult) -> None:
    moment = frame(crossing, collided, 1)
    assert moment.poses[2].heading == pytest.approx(math.pi / 2)  # vehicle 2 drives north (up the picture)
    root = parse(render_frame_svg(crossing, moment, caption="x"))
    [group] = [g for g in of_class(root, "vehicle") if g.get("data-vehicle") == "2"]
    [body], [nose] = of_class(group, "vehicle-body"), of_class(group, "vehicle-nose")
    xs, ys = zip(*corners(body))
    vehicle_type = next(v.type for v in crossing.vehicles if v.id == 2)
    assert (max(ys) - min(ys), max(xs) - min(xs)) == pytest.approx((40 * vehicle_type.length, 40 * vehicle_type.width), abs=0.02)
    tip = min(corners(nose), key=lambda p: p[1])  # SVG y grows downwards: the top-most point
    assert tip[1] == pytest.approx(min(ys), abs=0.02)


def test_orange_marks_exactly_the_segments_of_alerts_in_force(crossing: Scenario, collided: RunResult) -> None:
    moment = frame(crossing, collided, 1)
    assert {alert.segment for alert in moment.alerts} == {2, 3, 6, 7}
    root = parse(render_frame_svg(crossing, moment, caption="x"))
    orange = [e for e in root.iter() if e.get("stroke") == ORANGE or e.get("fill") == ORANGE]
    assert sorted(int(e.get("data-segment", "-1")) for e in orange) == [2, 3, 6, 7]
    assert all("alert" in e.get("class", "") for e in orange)


def test_without_alerts_nothing_is_orange(crossing: Scenario, collided: RunResult) -> None:
    moment = frame(crossing, collided, 0)
    assert moment.alerts == ()
    root = parse(render_frame_svg(crossing, moment, caption="x"))
    assert not [e for e in root.iter() if ORANGE in (e.get("stroke"), e.get("fill"))]
    assert len(of_class(root, "segment")) == len(crossing.layout.segments)


def test_plans_are_drawn_in_vehicle_colours_fixed_thick_planned_dashed(crossing: Scenario, collided: RunResult) -> None:
    moment = frame(crossing, collided, 1)
    root = parse(render_frame_svg(crossing, moment, caption="x"))
    colours = vehicle_colours(crossing)
    for group in of_class(root, "plan"):
        vid = int(group.get("data-vehicle", "0"))
        assert group.get("stroke") == svg_colour(colours[vid])[0]
        legs = of_class(group, "leg")
        plan = moment.plans[vid]
        assert [int(e.get("data-segment", "0")) for e in legs] == [leg.segment for leg in plan.legs]
        assert ["fixed" in e.get("class", "") for e in legs] == [leg.fixed for leg in plan.legs]
        widths = {("fixed" in e.get("class", "")): float(e.get("stroke-width", "0")) for e in legs}
        assert widths[True] > widths[False]
        assert all((e.get("stroke-dasharray") is None) == ("fixed" in e.get("class", "")) for e in legs)


def test_the_same_moment_gives_the_same_bytes(crossing: Scenario, collided: RunResult) -> None:
    first = render_frame_svg(crossing, frame(crossing, collided, 1), caption="t")
    assert render_frame_svg(crossing, frame(crossing, collided, 1), caption="t") == first
    assert failure_picture(crossing, collided) == failure_picture(crossing, collided)


# -- vehicle colours ------------------------------------------------------------------------------


def test_the_palette_is_fixed_opaque_and_distinct() -> None:
    colours = [palette_colour(position) for position in range(40)]
    assert colours == [palette_colour(position) for position in range(40)]
    assert len(set(colours)) == 40
    assert len({svg_colour(c)[0] for c in colours}) == 40  # distinct once drawn, too
    assert all(c[3] == 1.0 and all(0.0 <= channel <= 1.0 for channel in c) for c in colours)


def test_vehicles_get_palette_colours_in_id_order_unless_their_type_has_one(crossing: Scenario) -> None:
    assert vehicle_colours(crossing) == {1: palette_colour(0), 2: palette_colour(1)}
    red = (1.0, 0.0, 0.0, 0.5)
    painted = replace(
        crossing,
        vehicles=tuple(replace(v, type=replace(v.type, color=red)) if v.id == 2 else v for v in crossing.vehicles),
    )
    assert vehicle_colours(painted) == {1: palette_colour(0), 2: red}
    assert svg_colour(red) == ("#ff0000", 0.5)


# -- the moment of failure ------------------------------------------------------------------------


def test_failure_picture_is_the_step_of_the_first_collision_with_its_caption(crossing: Scenario, collided: RunResult) -> None:
    picture = failure_picture(crossing, collided)
    assert picture is not None
    step, svg = picture
    assert step == 1  # the alerts appear in the reservation check of step 1 (t = 0.1 s)
    assert any(event[0] == "alert" for event in frame(crossing, collided, step).events)
    root = parse(svg)
    [caption] = of_class(root, "caption-text")
    assert caption.text == "t = 0.10 s — collision: possible collision on segment 2: primary 1; secondary 2"
    assert {int(e.get("data-segment", "0")) for e in of_class(root, "alert")} == {2, 3, 6, 7}


def test_no_failure_picture_for_a_passed_run_or_a_run_without_its_trace(crossing: Scenario) -> None:
    passed = run_scenario(crossing, ReservingPlanner(), keep_trace=True)
    assert passed.passed and failure_picture(crossing, passed) is None
    untraced = run_scenario(crossing, BFSPlanner(), keep_trace=False)
    assert not untraced.passed and failure_picture(crossing, untraced) is None


@pytest.mark.parametrize(
    ("failures", "step", "which"),
    [
        ([Failure("collision", 0.1, "")], 1, 0),  # stamped with the start of its step
        ([Failure("rejection", 0.0, "")], 0, 0),
        ([Failure("deadlock", 9.0, "")], 89, 0),  # stamped with the end of its step
        ([Failure("timeout", 0.0, "")], 0, 0),  # time 0 is step 0
        ([Failure("timeout", 300.0, "")], 100, 0),  # clamped to the trace's last step
        ([Failure("expectation", 3.0, ""), Failure("rejection", 1.0, "")], 10, 1),  # the earliest
        ([Failure("collision", 1.0, "a"), Failure("expectation", 1.1, "b")], 10, 0),  # a tie: listed first
    ],
)
def test_failure_step_maps_failure_times_to_trace_steps(failures: list[Failure], step: int, which: int) -> None:
    assert failure_step(failures, time_step=0.1, last_step=100) == (step, failures[which])


def test_failure_step_of_no_failures_is_none() -> None:
    assert failure_step([], time_step=0.1, last_step=5) is None


def test_failure_caption_uses_the_first_line_of_the_message() -> None:
    failure = Failure("hash-mismatch", 12.3, "the trace hash differs\nrecord it with ...")
    assert failure_caption(failure) == "t = 12.30 s — hash-mismatch: the trace hash differs"
