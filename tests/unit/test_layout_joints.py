"""Joint kinds (SPEC §4): the angle between the segments' "away" vectors at each connection."""

from __future__ import annotations

import math

import pytest

from fleetsim.enums import Direction, JointKind, Shape, Traverse
from fleetsim.layout import Layout, Segment, Step, build_layout

Points = tuple[tuple[float, float], ...]


def onward(layout: Layout, segment: int, traverse: Traverse) -> tuple[Step, ...]:
    """``layout.successors`` onto other segments only: the joints between two segments, not the U-turns."""
    return tuple(step for step in layout.successors(segment, traverse) if step[0] != segment)


def _arc(cx: float, cy: float, radius: float, start_deg: float, end_deg: float, n: int = 10) -> Points:
    angles = [math.radians(start_deg + k * (end_deg - start_deg) / (n - 1)) for k in range(n)]
    return tuple((cx + radius * math.cos(a), cy + radius * math.sin(a)) for a in angles)


def _s_curve(x0: float, y0: float, dx: float, dy: float, rise: float, n: int = 9) -> Points:
    """An S from (x0, y0) along (dx, dy) for 4 m, ending ``rise`` m to the left, tangent at both ends."""
    points = []
    for k in range(n):
        s = 4.0 * k / (n - 1)
        offset = rise * 0.5 * (1.0 - math.cos(math.pi * s / 4.0))
        points.append((x0 + s * dx - offset * dy, y0 + s * dy + offset * dx))
    return tuple(points)


def _reversed(points: Points) -> Points:
    return tuple(reversed(points))


# Each case: (shape, waypoints) of segment 1, which ends at the origin, and of segment 2, which starts there.
CASES = {
    "straight-straight continuation": (
        (Shape.STRAIGHT, ((-4.0, 0.0), (0.0, 0.0))),
        (Shape.STRAIGHT, ((0.0, 0.0), (4.0, 0.0))),
        JointKind.SAME,
    ),
    "straight-curve tangent": (
        (Shape.STRAIGHT, ((-4.0, 0.0), (0.0, 0.0))),
        (Shape.CURVE, _arc(0.0, 1.0, 1.0, -90.0, 0.0)),
        JointKind.SAME,
    ),
    "straight-s_curve right-angle corner": (
        (Shape.STRAIGHT, ((0.0, -4.0), (0.0, 0.0))),
        (Shape.S_CURVE, _s_curve(0.0, 0.0, 1.0, 0.0, 1.0)),
        JointKind.TURN_IN_PLACE,
    ),
    "curve-curve cusp": (
        (Shape.CURVE, _arc(0.0, 1.0, 1.0, 180.0, 270.0)),  # arrives heading +x
        (Shape.CURVE, _arc(0.0, -1.0, 1.0, 90.0, 180.0)),  # leaves heading -x: back the way it came
        JointKind.OPPOSITE,
    ),
    "curve-s_curve tangent": (
        (Shape.CURVE, _arc(0.0, 1.0, 1.0, 180.0, 270.0)),
        (Shape.S_CURVE, _s_curve(0.0, 0.0, 1.0, 0.0, -1.0)),
        JointKind.SAME,
    ),
    "s_curve-s_curve right-angle corner": (
        (Shape.S_CURVE, _reversed(_s_curve(0.0, 0.0, -1.0, 0.0, 1.0))),  # arrives heading +x
        (Shape.S_CURVE, _s_curve(0.0, 0.0, 0.0, 1.0, 1.0)),  # leaves heading +y
        JointKind.TURN_IN_PLACE,
    ),
}


@pytest.mark.parametrize("case", list(CASES), ids=list(CASES))
def test_joint_kind_for_every_pair_of_shapes(case: str) -> None:
    (shape_a, points_a), (shape_b, points_b), expected = CASES[case]
    a = Segment(1, shape_a, Direction.BOTH, points_a)
    b = Segment(2, shape_b, Direction.BOTH, points_b)
    layout = build_layout([a, b], vehicle_radius=0.3)
    assert onward(layout, 1, Traverse.FORWARD) == ((2, Traverse.FORWARD, expected),)
    assert onward(layout, 2, Traverse.BACKWARD) == ((1, Traverse.BACKWARD, expected),)
    assert layout.joint(1, Traverse.FORWARD, 2, Traverse.FORWARD) is expected


def test_joint_between_two_states_agrees_with_successors_and_is_none_where_they_do_not_connect() -> None:
    layout = build_layout(
        [
            Segment(1, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (4.0, 0.0))),
            Segment(2, Shape.STRAIGHT, Direction.BOTH, ((4.0, 0.0), (4.0, 4.0))),
            Segment(3, Shape.STRAIGHT, Direction.BOTH, ((4.0, 0.0), (8.0, 0.0))),
        ],
        vehicle_radius=0.3,
    )
    for segment in layout.segments:
        for traverse in Traverse:
            for onto, onto_traverse, joint in layout.successors(segment, traverse):
                assert layout.joint(segment, traverse, onto, onto_traverse) is joint
    assert layout.joint(1, Traverse.FORWARD, 3, Traverse.FORWARD) is JointKind.SAME
    assert layout.joint(1, Traverse.FORWARD, 3, Traverse.BACKWARD) is None  # 3 driven backwards ends there
    assert layout.joint(1, Traverse.BACKWARD, 3, Traverse.FORWARD) is None  # leaving 1 at its other end
    assert layout.joint(1, Traverse.FORWARD, 99, Traverse.FORWARD) is None


@pytest.mark.parametrize(
    ("shape", "points"),
    [
        (Shape.STRAIGHT, ((-4.0, 0.0), (0.0, 0.0))),
        (Shape.CURVE, _arc(0.0, 1.0, 1.0, 180.0, 270.0)),
        (Shape.S_CURVE, _s_curve(0.0, 0.0, 1.0, 0.0, 1.0)),
    ],
    ids=["straight", "curve", "s_curve"],
)
def test_u_turn_at_a_segment_end_is_a_cusp_whatever_the_shape(shape: Shape, points: Points) -> None:
    layout = build_layout([Segment(1, shape, Direction.BOTH, points)], vehicle_radius=0.3)
    assert layout.successors(1, Traverse.FORWARD) == ((1, Traverse.BACKWARD, JointKind.OPPOSITE),)
    assert layout.successors(1, Traverse.BACKWARD) == ((1, Traverse.FORWARD, JointKind.OPPOSITE),)


def _bend(deviation_deg: float, tolerance: float = 30.0) -> JointKind:
    """Joint between a straight ending at the origin and one leaving it ``deviation_deg`` off straight on."""
    angle = math.radians(deviation_deg)
    a = Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-4.0, 0.0), (0.0, 0.0)))
    b = Segment(2, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (4.0 * math.cos(angle), 4.0 * math.sin(angle))))
    layout = build_layout([a, b], vehicle_radius=0.3, joint_angle_tolerance=tolerance)
    (step,) = onward(layout, 1, Traverse.FORWARD)
    return step[2]


@pytest.mark.parametrize(
    ("deviation", "expected"),
    [
        (0.0, JointKind.SAME),
        (29.0, JointKind.SAME),
        (31.0, JointKind.TURN_IN_PLACE),
        (90.0, JointKind.TURN_IN_PLACE),
        (149.0, JointKind.TURN_IN_PLACE),
        (151.0, JointKind.OPPOSITE),
        (180.0, JointKind.OPPOSITE),
    ],
)
def test_joint_kind_changes_at_the_angle_tolerance(deviation: float, expected: JointKind) -> None:
    assert _bend(deviation) == expected


def test_joint_angle_tolerance_is_configurable() -> None:
    assert _bend(40.0, tolerance=45.0) == JointKind.SAME
    assert _bend(40.0, tolerance=35.0) == JointKind.TURN_IN_PLACE


def test_waypoints_repeated_at_the_joint_do_not_hide_the_direction() -> None:
    a = Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-4.0, 0.0), (0.0, 0.0), (0.0, 0.0)))
    b = Segment(2, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (0.01, 0.0), (4.0, 0.0)))
    layout = build_layout([a, b], vehicle_radius=0.3)
    assert onward(layout, 1, Traverse.FORWARD) == ((2, Traverse.FORWARD, JointKind.SAME),)


def test_joint_with_a_segment_collapsed_to_a_point_is_a_turn_in_place() -> None:
    a = Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-4.0, 0.0), (0.0, 0.0)))
    b = Segment(2, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.0), (0.0, 0.0)))
    layout = build_layout([a, b], vehicle_radius=0.3)
    assert (2, Traverse.FORWARD, JointKind.TURN_IN_PLACE) in layout.successors(1, Traverse.FORWARD)


def test_joint_of_ends_within_tolerance_uses_each_segments_own_end() -> None:
    a = Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-4.0, 0.0), (0.0, 0.0)))
    b = Segment(2, Shape.STRAIGHT, Direction.BOTH, ((0.0, 0.04), (4.0, 0.04)))
    layout = build_layout([a, b], vehicle_radius=0.3)
    assert onward(layout, 1, Traverse.FORWARD) == ((2, Traverse.FORWARD, JointKind.SAME),)
