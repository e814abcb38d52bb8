"""Runs built on purpose, through real maps (written as Tiled JSON and loaded as a user's are): a junction
crossed 30 s apart, judged by both disciplines."""

from __future__ import annotations

import math
import os
from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim.enums import Direction, Shape
from fleetsim.layout import Segment
from fleetsim.load.suites.scenario import load_scenario_dir
from fleetsim.load.tiled.writer import write_map
from fleetsim.planners import BFSPlanner
from fleetsim.recording.picture import failure_picture
from fleetsim.recording.replay import replay
from fleetsim.scenario import DEFAULT_VEHICLE_TYPE, Checks, Scenario, ScenarioSettings
from fleetsim.sim.loop import run_scenario


def _write(folder: Path, segments: tuple[Segment, ...], vehicles: str, tasks: str) -> None:
    """A scenario folder: the map as Tiled JSON, and ``vehicles.csv`` and ``tasks.csv`` with these rows."""
    folder.mkdir(exist_ok=True)
    write_map(folder / "map.json", segments)
    (folder / "vehicles.csv").write_text(
        "vehicle_id,start_segment_id,segment_orientation,progress_direction\n" + vehicles
    )
    (folder / "tasks.csv").write_text("vehicle_id,goal_segment_id,goal_progress_direction\n" + tasks)


def _crossing_apart(tmp_path: Path, checks: Checks) -> Scenario:
    """A + junction at the origin. Vehicle 1 drives east from (-10, 0) and stops at (2, 0), just past
    it; vehicle 2 comes from (-30, -10), east and then north round a corner, so it reaches the junction
    some 30 s after vehicle 1 has crossed it, and passes 2 m from where vehicle 1 stands."""
    segments = (
        Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-10.0, 0.0), (0.0, 0.0))),
        Segment(2, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (2.0, 0.0))),
        Segment(5, Shape.STRAIGHT, Direction.BOTH, ((-30.0, -10.0), (0.0, -10.0))),
        Segment(3, Shape.STRAIGHT, Direction.BOTH, ((0.0, -10.0), (0.0, 0.0))),
        Segment(4, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (0.0, 10.0))),
    )
    _write(tmp_path, segments, "1,1,forward,forward\n2,5,forward,forward\n", "1,2,\n2,4,\n")
    settings = ScenarioSettings(stop_on=(), time_limit=120.0, checks=checks)
    return load_scenario_dir(tmp_path, settings=settings)


def test_a_junction_crossed_30_s_apart_is_a_reservation_alert_but_no_contact(tmp_path: Path) -> None:
    result = run_scenario(_crossing_apart(tmp_path, Checks()), BFSPlanner())
    assert result.collisions  # both routes reserve the junction from the start: the rule says no
    assert result.contact is not None and result.contact.contacts == ()
    assert [f.kind for f in result.failures] == ["collision"] * len(result.collisions)


def test_with_reservations_off_the_same_run_passes_and_its_clearance_is_as_computed_by_hand(tmp_path: Path) -> None:
    result = run_scenario(_crossing_apart(tmp_path, Checks(reservations=False)), BFSPlanner())
    assert result.passed, [f.message for f in result.failures]
    assert not result.collisions and result.tasks_completed == 2
    # Vehicle 1 (1.0 x 0.6 m) stands centred at (2, 0) facing east: its tail at x = 1.5. Vehicle 2 comes
    # north along x = 0, 0.3 m to either side: the closest is 1.5 - 0.3 = 1.2 m, across y in -0.3..0.3.
    assert result.contact is not None
    clearance = result.contact.clearance
    assert clearance is not None and clearance.vehicles == (1, 2)
    assert clearance.distance == pytest.approx(1.2, abs=1e-6)
    assert result.metrics.clearance == pytest.approx(1.2, abs=1e-6)
    assert result.contact.near_misses == ()  # 1.2 m is no near miss at 0.5 m
    assert clearance.time > 30.0  # when vehicle 2 came by, long after vehicle 1 had crossed


def test_a_near_miss_distance_above_the_clearance_lists_the_pair(tmp_path: Path) -> None:
    result = run_scenario(_crossing_apart(tmp_path, Checks(reservations=False, near_miss=1.5)), BFSPlanner())
    assert result.contact is not None
    [miss] = result.contact.near_misses
    assert miss.vehicles == (1, 2) and miss.distance == pytest.approx(1.2, abs=1e-6)


def test_an_expected_clearance_above_what_the_run_kept_fails_it(tmp_path: Path) -> None:
    scenario = _crossing_apart(tmp_path, Checks(reservations=False))
    strict = replace(scenario, expect=replace(scenario.expect, clearance=1.25))
    [failure] = run_scenario(strict, BFSPlanner()).failures
    assert failure.details["expect"] == "clearance" and "came within 1.200 m" in failure.message


def _meeting(tmp_path: Path) -> Scenario:
    """A + junction at the origin, both vehicles 10 m from it, one from the west and one from the south,
    driving alike straight across: they meet in it. Reservations off."""
    segments = (
        Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-10.0, 0.0), (0.0, 0.0))),
        Segment(2, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (10.0, 0.0))),
        Segment(3, Shape.STRAIGHT, Direction.BOTH, ((0.0, -10.0), (0.0, 0.0))),
        Segment(4, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (0.0, 10.0))),
    )
    _write(tmp_path, segments, "1,1,forward,forward\n2,3,forward,forward\n", "1,2,\n2,4,\n")
    settings = ScenarioSettings(
        stop_on=(), time_limit=60.0, allow_start_conflicts=True, checks=Checks(reservations=False)
    )
    return load_scenario_dir(tmp_path, settings=settings)


def test_two_vehicles_meeting_at_a_junction_touch_at_the_moment_and_place_computed_by_hand(tmp_path: Path) -> None:
    result = run_scenario(_meeting(tmp_path), BFSPlanner())
    assert result.contact is not None
    [contact] = result.contact.contacts
    # Both drive alike, 10 m from the junction: 1.0 x 0.6 m footprints first touch when each centre is
    # 0.5 + 0.3 = 0.8 m from it, corner to corner at (-0.3, -0.3). At 0.5 m/s² up to 1 m/s that is after
    # 1 m in 2 s, then 8.2 m in 8.2 s: t = 10.2 s.
    assert contact.vehicles == (1, 2)
    assert contact.time == pytest.approx(10.2, abs=0.1)  # within a step
    assert (contact.x, contact.y) == pytest.approx((-0.3, -0.3), abs=0.02)
    assert contact.depth > 0.5  # they drove on through each other
    [failure] = [f for f in result.failures if f.kind == "contact"]
    assert failure.time == contact.time


def test_head_on_at_5_m_s_with_half_second_steps_is_caught_between_the_steps(tmp_path: Path) -> None:
    # A corridor; vehicle 1 starts at its west end facing east, vehicle 2 at its east end facing west,
    # each to drive the whole corridor at 5 m/s with 0.5 s steps: they close 5 m a step, five times
    # their length, and at each step's end their footprints are apart.
    start = 3.7375  # metres from the middle: the steps' ends fall 2.5 m before and after they meet
    segments = (
        Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-start, 0.0), (-0.5, 0.0))),
        Segment(2, Shape.STRAIGHT, Direction.BOTH, ((-0.5, 0.0), (0.5, 0.0))),
        Segment(3, Shape.STRAIGHT, Direction.BOTH, ((0.5, 0.0), (start, 0.0))),
        Segment(4, Shape.STRAIGHT, Direction.BOTH, ((start, 0.0), (start + 20.0, 0.0))),
        Segment(5, Shape.STRAIGHT, Direction.BOTH, ((-start - 20.0, 0.0), (-start, 0.0))),
    )
    _write(tmp_path, segments, "1,1,forward,forward\n2,3,backward,forward\n", "1,4,\n2,5,\n")
    fast = replace(DEFAULT_VEHICLE_TYPE, max_speed=5.0, acceleration=1000.0)
    settings = ScenarioSettings(
        time_step=0.5, planning_period=0.5, stop_on=(), time_limit=30.0, allow_start_conflicts=True,
        checks=Checks(reservations=False),
    )  # fmt: skip
    scenario = load_scenario_dir(tmp_path, vehicle_types={"default": fast}, settings=settings)
    result = run_scenario(scenario, BFSPlanner())
    assert result.contact is not None
    [contact] = result.contact.contacts
    # Begun and ended within one step: no step's end shows them overlapping, only the continuous check.
    step_end = math.ceil(contact.time / 0.5 - 1e-9) * 0.5
    assert contact.until == pytest.approx(step_end)
    assert contact.until - contact.time < 0.5
    # Noses meet in the middle, face to face: the place is a point of the touching faces.
    assert contact.x == pytest.approx(0.0, abs=0.05) and abs(contact.y) <= 0.3 + 1e-9


def _lanes(tmp_path: Path, margin: float) -> Scenario:
    """Two parallel one-way lanes 0.7 m apart, centre to centre: 0.6 m wide vehicles side by side, 0.1 m
    between them, driving their lanes at the same pace."""
    segments = (
        Segment(1, Shape.STRAIGHT, Direction.FORWARD, ((-10.0, 0.0), (0.0, 0.0))),
        Segment(2, Shape.STRAIGHT, Direction.FORWARD, ((0.0, 0.0), (10.0, 0.0))),
        Segment(3, Shape.STRAIGHT, Direction.FORWARD, ((-10.0, 0.7), (0.0, 0.7))),
        Segment(4, Shape.STRAIGHT, Direction.FORWARD, ((0.0, 0.7), (10.0, 0.7))),
    )
    _write(tmp_path, segments, "1,1,forward,forward\n2,3,forward,forward\n", "1,2,\n2,4,\n")
    settings = ScenarioSettings(
        stop_on=(), time_limit=60.0, allow_start_conflicts=True, checks=Checks(reservations=False, safety_margin=margin)
    )
    return load_scenario_dir(tmp_path, settings=settings)


def test_parallel_lanes_a_tenth_apart_never_touch_and_a_safety_margin_turns_that_into_a_contact(tmp_path: Path) -> None:
    plain = run_scenario(_lanes(tmp_path, 0.0), BFSPlanner())
    assert plain.passed, [f.message for f in plain.failures]
    assert plain.contact is not None and plain.contact.contacts == ()
    assert plain.metrics.clearance == pytest.approx(0.1, abs=1e-9)
    assert [m.vehicles for m in plain.contact.near_misses] == [(1, 2)]
    narrow = run_scenario(_lanes(tmp_path, 0.04), BFSPlanner())  # 0.1 - 2 x 0.04: 0.02 m to spare
    assert narrow.passed and narrow.metrics.clearance == pytest.approx(0.02, abs=1e-9)
    wide = run_scenario(_lanes(tmp_path, 0.06), BFSPlanner())  # 0.1 - 2 x 0.06 < 0: a contact from the start
    [failure] = wide.failures
    assert failure.kind == "contact" and failure.time == 0.0
    assert failure.details["depth"] == pytest.approx(0.02, abs=1e-4)


def _corner(tmp_path: Path, offset: float) -> Scenario:
    """Vehicle 1 drives east to a corner at the origin, turns 90 degrees on the spot and drives north;
    vehicle 2 stands (no task) facing east with its rear left corner at (offset, offset), clear of
    vehicle 1 before and after the turn (0.1 m at ``offset`` 0.4)."""
    segments = (
        Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-5.0, 0.0), (0.0, 0.0))),
        Segment(2, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (0.0, 5.0))),
        Segment(4, Shape.STRAIGHT, Direction.BOTH, ((0.0, 5.0), (0.0, 10.0))),  # its goal: the turn is whole
        # Vehicle 2's start leg, which it drives to its end: 5 cm, ending where it is to stand.
        Segment(3, Shape.STRAIGHT, Direction.BOTH, ((offset + 0.45, offset + 0.3), (offset + 0.5, offset + 0.3))),
    )
    _write(tmp_path, segments, "1,1,forward,forward\n2,3,forward,forward\n", "1,4,\n")
    settings = ScenarioSettings(
        stop_on=(), time_limit=60.0, allow_start_conflicts=True, checks=Checks(reservations=False)
    )
    return load_scenario_dir(tmp_path, settings=settings)


def test_a_turn_in_place_clips_a_standing_vehicles_corner(tmp_path: Path) -> None:
    result = run_scenario(_corner(tmp_path / "near", 0.4), BFSPlanner())
    assert result.contact is not None
    # Vehicle 1 turns at the origin: its corners sweep a circle of radius hypot(0.5, 0.3) that reaches
    # past (0.4, 0.4). Both of its front corners pass that corner of vehicle 2: the left one about 14
    # degrees into the turn, the right one about 76 degrees in, each clipping it briefly.
    first, second = result.contact.contacts
    for contact in (first, second):
        assert contact.vehicles == (1, 2)
        assert (contact.x, contact.y) == pytest.approx((0.4, 0.4), abs=0.05)
        assert contact.until is not None and 0 < contact.until - contact.time <= 0.1 + 1e-9
        assert 0 < contact.depth < 0.02
    turn_rate = math.radians(DEFAULT_VEHICLE_TYPE.turn_rate)
    assert second.time - first.time == pytest.approx(math.radians(76 - 14) / turn_rate, abs=0.1)
    apart = run_scenario(_corner(tmp_path / "far", 0.55), BFSPlanner())  # beyond the swept circle
    assert apart.contact is not None and apart.contact.contacts == () and apart.passed


@pytest.mark.parametrize(
    ("picture", "build", "kind"),
    [("judgement-reservations.svg", "crossed-apart", "collision"), ("judgement-contact.svg", "meeting", "contact")],
)
def test_the_pictures_of_the_two_judgements_in_the_docs_are_these_runs(
    picture: str, build: str, kind: str, tmp_path: Path
) -> None:
    """docs/contact.md shows the failure pictures of two runs: the junction crossed 30 s apart (a reservation
    alert, though the vehicles never come near) and the junction where they meet (a contact).
    ``FLEETSIM_UPDATE_DOCS=1`` draws them anew."""
    folder = tmp_path / build  # the scenario's name in the picture
    scenario = _crossing_apart(folder, Checks()) if build == "crossed-apart" else _meeting(folder)
    result = run_scenario(scenario, BFSPlanner())
    assert result.failures[0].kind == kind
    found = failure_picture(scenario, result)
    assert found is not None
    svg = found[1].replace(str(tmp_path), "")  # no machine's folder in the page
    shown = Path(__file__).resolve().parents[2] / "docs" / "images" / picture
    if os.environ.get("FLEETSIM_UPDATE_DOCS") == "1":
        shown.write_text(svg, encoding="utf-8")
    assert shown.read_text(encoding="utf-8") == svg, (
        f"docs/images/{picture} is stale: FLEETSIM_UPDATE_DOCS=1 redraws it"
    )


def test_a_replay_shows_alerts_only_where_the_reservation_check_raised_them(tmp_path: Path) -> None:
    """Both plans hold the junction from the start: with reservations on the replay (pictures, MCAP)
    shows that alert; with them off the run raised none, and the replay shows none."""
    off = _meeting(tmp_path / "off")
    on = replace(off, settings=replace(off.settings, checks=Checks()))
    for scenario, judged in ((off, False), (on, True)):
        result = run_scenario(scenario, BFSPlanner())
        assert result.trace is not None and bool(result.collisions) is judged
        shown = [frame.step for frame in replay(scenario, result.trace.lines) if frame.alerts]
        assert bool(shown) is judged
