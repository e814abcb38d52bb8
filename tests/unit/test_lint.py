"""Layout lint: each code fires on its mistake and stays quiet just short of it."""

from __future__ import annotations

import dataclasses
import math

import pytest

from fleetsim.enums import Direction, Shape
from fleetsim.layout import LintFinding, Segment, build_layout


def _straight(sid: int, *points: tuple[float, float], direction: Direction = Direction.BOTH) -> Segment:
    return Segment(sid, Shape.STRAIGHT, direction, tuple(points))


def _codes(segments: list[Segment], code: str) -> list[LintFinding]:
    return [f for f in build_layout(segments, vehicle_radius=0.3).lint() if f.code == code]


def _square(first_id: int = 1, size: float = 4.0) -> list[Segment]:
    """A closed loop of four two-way straights: no dangling ends, every segment reachable."""
    corners = [(0.0, 0.0), (size, 0.0), (size, size), (0.0, size)]
    return [_straight(first_id + k, corners[k], corners[(k + 1) % 4]) for k in range(4)]


def test_a_clean_loop_has_no_findings() -> None:
    assert build_layout(_square(), vehicle_radius=0.3).lint() == ()


def test_dangling_end_names_the_segment_the_end_and_the_point() -> None:
    findings = _codes([_straight(1, (0, 0), (4, 0))], "dangling-end")
    assert [(f.segments, f.severity) for f in findings] == [((1,), "warning"), ((1,), "warning")]
    assert findings[0].message == (
        "the first end of segment 1 at (0.000, 0.000) meets no other segment end (a dead end)"
    )
    assert "the last end of segment 1 at (4.000, 0.000)" in findings[1].message


def test_ends_0_049_apart_are_not_dangling() -> None:
    segments = [_straight(1, (0, 0), (4, 0)), _straight(2, (4.049, 0), (8, 0))]
    messages = [f.message for f in _codes(segments, "dangling-end")]
    assert not any("last end of segment 1" in m or "first end of segment 2" in m for m in messages)


def test_ends_0_051_apart_are_dangling() -> None:
    segments = [_straight(1, (0, 0), (4, 0)), _straight(2, (4.051, 0), (8, 0))]
    messages = [f.message for f in _codes(segments, "dangling-end")]
    assert any("last end of segment 1" in m for m in messages)
    assert any("first end of segment 2" in m for m in messages)


def test_ends_of_a_closed_loop_segment_are_not_dangling() -> None:
    circle = tuple((math.cos(math.radians(a)), math.sin(math.radians(a))) for a in range(0, 361, 10))
    assert _codes([Segment(1, Shape.CURVE, Direction.BOTH, circle)], "dangling-end") == []


def test_segment_off_the_main_loop_is_unreachable() -> None:
    island = _straight(10, (20, 20), (24, 20))
    findings = _codes([*_square(), island], "unreachable")
    assert [f.segments for f in findings] == [(10,)]
    assert findings[0].message == (
        "segment 10 cannot be reached from the main part of the map (the strongly connected part through segment 1)"
    )


def test_one_way_segment_that_only_leads_into_the_loop_is_unreachable() -> None:
    feeder = _straight(10, (-4, 0), (0, 0), direction=Direction.FORWARD)
    assert [f.segments for f in _codes([*_square(), feeder], "unreachable")] == [(10,)]


def test_one_way_segment_that_leads_out_of_the_loop_is_reachable() -> None:
    exit_road = _straight(10, (-4, 0), (0, 0), direction=Direction.BACKWARD)
    assert _codes([*_square(), exit_road], "unreachable") == []


def test_main_component_is_the_one_covering_most_segments() -> None:
    small_loop = _square(first_id=1, size=1.0)
    big_loop = [  # six segments far away: the main part, although its ids are larger
        *_square(first_id=20, size=2.0)[:3],
        _straight(23, (0, 2), (0, 1)),
        _straight(24, (0, 1), (0, 0.5)),
        _straight(25, (0, 0.5), (0, 0)),
    ]
    big_loop = [dataclasses.replace(s, waypoints=tuple((x + 50, y) for x, y in s.waypoints)) for s in big_loop]
    assert [f.segments for f in _codes([*small_loop, *big_loop], "unreachable")] == [(1,), (2,), (3,), (4,)]


def test_ends_0_49_apart_are_a_near_miss() -> None:
    findings = _codes([_straight(1, (0, 0), (4, 0)), _straight(2, (4.49, 0), (8, 0))], "near-miss")
    assert [f.segments for f in findings] == [(1, 2)]
    assert "are 0.490 m apart" in findings[0].message
    assert "the last end of segment 1 and the first end of segment 2" in findings[0].message


@pytest.mark.parametrize("gap", [0.51, 0.049], ids=["too-far", "connected"])
def test_ends_outside_the_near_miss_band_are_not_a_near_miss(gap: float) -> None:
    assert _codes([_straight(1, (0, 0), (4, 0)), _straight(2, (4 + gap, 0), (8, 0))], "near-miss") == []


@pytest.mark.parametrize(
    ("first", "second", "flow"),
    [(Direction.FORWARD, Direction.BACKWARD, "into"), (Direction.BACKWARD, Direction.FORWARD, "out of")],
)
def test_touching_one_ways_that_cannot_connect_are_reported(first: Direction, second: Direction, flow: str) -> None:
    segments = [_straight(1, (0, 0), (4, 0), direction=first), _straight(2, (4, 0), (8, 0), direction=second)]
    findings = _codes(segments, "no-connection")
    assert [f.segments for f in findings] == [(1, 2)]
    expected = f"touch at (4.000, 0.000) but do not connect: both one-way directions lead {flow} the joint"
    assert expected in findings[0].message


def test_touching_one_ways_in_the_same_direction_are_not_reported() -> None:
    segments = [
        _straight(1, (0, 0), (4, 0), direction=Direction.FORWARD),
        _straight(2, (4, 0), (8, 0), direction=Direction.FORWARD),
    ]
    assert _codes(segments, "no-connection") == []


def test_a_one_way_fork_and_merge_are_not_reported() -> None:
    # 1 forks into 2 and 3, which merge into 4: the branches never connect to each other, but each end
    # connects to the lane it forks from or merges into (a lay-by beside an aisle).
    forward = Direction.FORWARD
    segments = [
        _straight(1, (0, 0), (4, 0), direction=forward),
        _straight(2, (4, 0), (8, 0), direction=forward),
        _straight(3, (4, 0), (4, 2), (8, 2), (8, 0), direction=forward),
        _straight(4, (8, 0), (12, 0), direction=forward),
    ]
    assert _codes(segments, "no-connection") == []


def test_a_joint_that_three_one_ways_all_leave_is_reported_pair_by_pair() -> None:
    # As above, but 1 is drawn the other way: all three lead out of the joint, so nothing can pass it.
    forward = Direction.FORWARD
    segments = [
        _straight(1, (4, 0), (0, 0), direction=forward),
        _straight(2, (4, 0), (8, 0), direction=forward),
        _straight(3, (4, 0), (4, 2), direction=forward),
    ]
    findings = _codes(segments, "no-connection")
    assert [f.segments for f in findings] == [(1, 2), (1, 3), (2, 3)]


def test_segment_shorter_than_the_connection_tolerance_is_zero_length() -> None:
    findings = _codes([_straight(1, (0, 0), (0.049, 0))], "zero-length")
    assert [f.message for f in findings] == ["segment 1 is 0.049 m long, shorter than the connection tolerance 0.05 m"]


def test_segment_just_longer_than_the_connection_tolerance_is_not_zero_length() -> None:
    assert _codes([_straight(1, (0, 0), (0.051, 0))], "zero-length") == []


def test_findings_are_sorted_by_code_then_segments() -> None:
    segments = [_straight(3, (0, 0), (0.01, 0)), _straight(1, (10, 0), (14, 0)), _straight(2, (14.3, 0), (18, 0))]
    findings = build_layout(segments, vehicle_radius=0.3).lint()
    keys = [(f.code, f.segments) for f in findings]
    assert keys == sorted(keys)
    assert {f.code for f in findings} == {"dangling-end", "near-miss", "unreachable", "zero-length"}


def test_findings_are_immutable() -> None:
    (finding, *_) = build_layout([_straight(1, (0, 0), (4, 0))], vehicle_radius=0.3).lint()
    with pytest.raises(dataclasses.FrozenInstanceError):
        finding.code = "other"  # type: ignore[misc]
    assert str(finding).startswith("warning: dangling-end: the first end of segment 1")
