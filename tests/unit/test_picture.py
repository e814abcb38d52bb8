"""The still picture of a run's moment: map, plans, vehicles, alerts in orange, caption; vehicle colours."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim import load_scenario, load_suite
from fleetsim.planners import BFSPlanner, ReservingPlanner
from fleetsim.planning.plans import FleetLeg, FleetPlan
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
    texts = of_class(root, "caption-text")
    assert [t.text for t in texts] == ['t = 0.20 s — a <b> & "c"', "second line"]
    map_top = min(y for e in of_class(root, "segment") for _, y in corners(e))
    assert all(float(t.get("y", "0")) < map_top for t in texts)


def test_a_long_caption_wraps_and_leaves_the_picture_as_wide_as_the_map(
    crossing: Scenario, collided: RunResult
) -> None:
    short = parse(render_frame_svg(crossing, frame(crossing, collided, 1), caption="t = 0.20 s — short"))
    long = parse(render_frame_svg(crossing, frame(crossing, collided, 1), caption="t = 0.20 s — " + "word " * 200))
    assert long.get("width") == short.get("width")
    lines = of_class(long, "caption-text")
    assert len(lines) > 5 and all(len(line.text or "") * 0.6 * 16 <= float(long.get("width", "0")) for line in lines)
    # The map keeps its size and place relative to the picture's width; only the caption grows down.
    short_xs = sorted(x for e in of_class(short, "segment") for x, _ in corners(e))
    long_xs = sorted(x for e in of_class(long, "segment") for x, _ in corners(e))
    assert short_xs == long_xs


def test_one_vehicle_shape_per_vehicle_with_nose_and_id(crossing: Scenario, collided: RunResult) -> None:
    root = parse(render_frame_svg(crossing, frame(crossing, collided, 1), caption="x"))
    vehicles = of_class(root, "vehicle")
    assert [v.get("data-vehicle") for v in vehicles] == ["1", "2"]
    for group in vehicles:
        [body] = of_class(group, "vehicle-body")
        [nose] = of_class(group, "vehicle-nose")
        [label] = of_class(group, "vehicle-label")
        assert (len(corners(body)), len(corners(nose)), label.text) == (4, 3, group.get("data-vehicle"))


def test_a_vehicle_is_drawn_lengthwise_along_its_heading_with_the_nose_in_front(
    crossing: Scenario, collided: RunResult
) -> None:
    moment = frame(crossing, collided, 1)
    assert moment.poses[2].heading == pytest.approx(math.pi / 2)  # vehicle 2 drives north (up the picture)
    root = parse(render_frame_svg(crossing, moment, caption="x"))
    [group] = [g for g in of_class(root, "vehicle") if g.get("data-vehicle") == "2"]
    [body], [nose] = of_class(group, "vehicle-body"), of_class(group, "vehicle-nose")
    xs, ys = zip(*corners(body), strict=True)
    vehicle_type = next(v.type for v in crossing.vehicles if v.id == 2)
    assert (max(ys) - min(ys), max(xs) - min(xs)) == pytest.approx(
        (40 * vehicle_type.length, 40 * vehicle_type.width), abs=0.02
    )
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


def test_failure_picture_is_the_step_of_the_first_collision_with_its_caption(
    crossing: Scenario, collided: RunResult
) -> None:
    picture = failure_picture(crossing, collided)
    assert picture is not None
    step, svg = picture
    assert step == 1  # the alerts appear in the reservation check of step 1, stamped with its end (0.2 s)
    assert any(event[0] == "alert" for event in frame(crossing, collided, step).events)
    assert frame(crossing, collided, step).time == pytest.approx(collided.collisions[0].time)
    root = parse(svg)
    [caption] = of_class(root, "caption-text")
    # The message says what it is: no "collision: possible collision".
    assert caption.text == "t = 0.20 s — possible collision on segment 2: primary 1; secondary 2"
    assert {int(e.get("data-segment", "0")) for e in of_class(root, "alert")} == {2, 3, 6, 7}


def test_no_failure_picture_for_a_passed_run_or_a_run_without_its_trace(crossing: Scenario) -> None:
    passed = run_scenario(crossing, ReservingPlanner(), keep_trace=True)
    assert passed.passed and failure_picture(crossing, passed) is None
    untraced = run_scenario(crossing, BFSPlanner(), keep_trace=False)
    assert not untraced.passed and failure_picture(crossing, untraced) is None


@pytest.mark.parametrize(
    ("failures", "step", "which"),
    [
        ([Failure("collision", 0.2, "")], 1, 0),  # every event is stamped with the end of its step
        ([Failure("rejection", 0.1, "")], 0, 0),
        ([Failure("deadlock", 9.0, "")], 89, 0),
        ([Failure("expectation", 0.0, "")], 0, 0),  # time 0 is step 0
        ([Failure("timeout", 300.0, "")], 100, 0),  # clamped to the trace's last step
        ([Failure("expectation", 3.0, ""), Failure("rejection", 1.0, "")], 9, 1),  # the earliest
        ([Failure("collision", 1.0, "a"), Failure("expectation", 1.0, "b")], 9, 0),  # a tie: listed first
        (
            [Failure("hash-mismatch", 0.5, "h"), Failure("deadlock", 47.0, "d")],
            100,
            1,
        ),  # a hash has no moment: the deadlock (clamped to the last step)
        ([Failure("hash-missing", 3.0, "h")], 100, 0),  # nothing but a hash failure: the last step
    ],
)
def test_failure_step_maps_failure_times_to_trace_steps(failures: list[Failure], step: int, which: int) -> None:
    assert failure_step(failures, time_step=0.1, last_step=100) == (step, failures[which])


def test_failure_step_of_no_failures_is_none() -> None:
    assert failure_step([], time_step=0.1, last_step=5) is None


def test_failure_caption_uses_the_first_line_of_the_message() -> None:
    failure = Failure("timeout", 12.3, "2 of 3 tasks completed\nmore ...")
    assert failure_caption(failure) == "t = 12.30 s — timeout: 2 of 3 tasks completed"


def test_a_deadlock_caption_does_not_repeat_the_word() -> None:
    failure = Failure("deadlock", 47.0, "vehicles 1 and 2 wait for each other (1 -> 2 -> 1) over segments 1 and 3")
    assert (
        failure_caption(failure)
        == "t = 47.00 s — deadlock: vehicles 1 and 2 wait for each other (1 -> 2 -> 1) over segments 1 and 3"
    )
    assert (
        failure_caption(Failure("rejection", 1.0, "plan rejected: wrong-way: vehicle 1"))
        == "t = 1.00 s — plan rejected: wrong-way: vehicle 1"
    )


def test_a_hash_failure_beside_a_deadlock_goes_into_the_deadlock_pictures_caption() -> None:
    hash_failure = Failure(
        "hash-mismatch", 0.5, "the trace hash differs from the recorded one since t = 0.5-1.0 s\nrecord ..."
    )
    deadlock = Failure("deadlock", 47.0, "vehicles 1 and 2 wait for each other")
    step, chosen = failure_step([hash_failure, deadlock], time_step=0.1, last_step=500) or (0, hash_failure)
    assert (step, chosen) == (469, deadlock)
    assert failure_caption(chosen, [hash_failure, deadlock]).splitlines() == [
        "t = 47.00 s — deadlock: vehicles 1 and 2 wait for each other",
        "also hash-mismatch: the trace hash differs from the recorded one since t = 0.5-1.0 s",
    ]


def test_a_hash_failure_alone_is_captioned_at_the_pictures_time() -> None:
    failure = Failure(
        "hash-missing", 0.0, "no trace hash is recorded for planner 'p' in this scenario; record it with: pytest ..."
    )
    assert failure_caption(failure, [failure], at=12.0) == (
        "t = 12.00 s — hash-missing: no trace hash is recorded for planner 'p' in this scenario; record it with: pytest ..."
    )


class _Disconnected(BFSPlanner):
    """Vehicle 1's first plan jumps to a segment its start does not lead to: a not-connected rejection."""

    def plan_routes(self, task, fleet, layout):  # type: ignore[no-untyped-def]
        if task.vehicle_id == 1 and fleet.time == 0.0:
            legs = fleet.plans[1].legs
            last = legs[-1]
            nearby = {sid for sid, _, _ in layout.successors(last.segment, last.traverse)} | {last.segment}
            far = min(sid for sid in layout.segments if sid not in nearby)
            return [FleetPlan(1, (*legs, FleetLeg(far, last.traverse, last.progress, False)))]
        return super().plan_routes(task, fleet, layout)


def test_a_rejection_picture_draws_the_refused_plan_with_its_offending_leg_marked(crossing: Scenario) -> None:
    result = run_scenario(crossing, _Disconnected(), keep_trace=True)
    [rejection] = [f for f in result.failures if f.kind == "rejection"]
    picture = failure_picture(crossing, result)
    assert picture is not None and picture[0] == 0
    root = parse(picture[1])
    [group] = of_class(root, "rejected-plan")
    assert (group.get("data-vehicle"), group.get("data-code")) == ("1", "not-connected")
    legs = of_class(root, "rejected-leg-path")
    assert [int(e.get("data-segment", "0")) for e in legs] == [leg["segment"] for leg in rejection.details["plan"]]
    [offending] = of_class(root, "rejected-leg")
    assert int(offending.get("data-leg", "-1")) == rejection.details["leg_index"] == len(legs) - 1
    assert any("the rejected plan" in (e.text or "") for e in of_class(root, "legend"))


def test_a_collision_picture_draws_no_rejected_plan(crossing: Scenario, collided: RunResult) -> None:
    picture = failure_picture(crossing, collided)
    assert picture is not None
    assert of_class(parse(picture[1]), "rejected-plan") == []
