"""build_layout's checks and the Layout's answers about unknown segments."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from fleetsim.enums import ConflictModel, Direction, Shape, Traverse
from fleetsim.errors import FleetsimError, LayoutError
from fleetsim.layout import Segment, build_layout


def _straight(sid: int, *points: tuple[float, float]) -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, tuple(points))


SEGMENTS = [_straight(1, (0, 0), (4, 0)), _straight(2, (4, 0), (8, 0))]


def test_duplicate_segment_ids_are_rejected_naming_the_id() -> None:
    with pytest.raises(LayoutError, match=r"duplicate segment id 7 in map\.json"):
        twins = [_straight(7, (0, 0), (1, 0)), _straight(7, (2, 0), (3, 0))]
        build_layout(twins, vehicle_radius=0.3, source=Path("map.json"))


def test_non_finite_waypoints_are_rejected() -> None:
    with pytest.raises(LayoutError, match="segment 3 has a non-finite waypoint"):
        build_layout([_straight(3, (0, 0), (math.nan, 0))], vehicle_radius=0.3)


@pytest.mark.parametrize(
    ("setting", "value", "message"),
    [
        ("vehicle_radius", -0.1, r"vehicle_radius=-0\.1 must be a finite number >= 0"),
        ("vehicle_radius", math.inf, r"vehicle_radius=inf must be a finite number >= 0"),
        ("connection_tolerance", -0.01, r"connection_tolerance=-0\.01 must be"),
        ("safety_margin", -1.0, r"safety_margin=-1\.0 must be"),
        ("joint_angle_tolerance", 0.0, r"joint_angle_tolerance=0\.0 must be between 0 and 90 degrees"),
        ("joint_angle_tolerance", 90.0, r"joint_angle_tolerance=90\.0 must be between 0 and 90 degrees"),
        ("joint_angle_tolerance", -5.0, r"joint_angle_tolerance=-5\.0 must be"),
        ("conflict_model", "circles", r"conflict_model='circles' must be one of swept, bbox"),
    ],
)
def test_invalid_settings_are_rejected_with_name_and_value(setting: str, value: object, message: str) -> None:
    settings: dict[str, object] = {"vehicle_radius": 0.3, setting: value}
    with pytest.raises(LayoutError, match=message):
        build_layout(SEGMENTS, **settings)  # type: ignore[arg-type]


def test_settings_are_kept_on_the_layout() -> None:
    layout = build_layout(
        SEGMENTS,
        vehicle_radius=0.4,
        connection_tolerance=0.1,
        joint_angle_tolerance=20.0,
        safety_margin=0.2,
        conflict_model="bbox",  # type: ignore[arg-type]
        source=Path("maps/a.json"),
    )
    assert (layout.vehicle_radius, layout.connection_tolerance, layout.joint_angle_tolerance) == (0.4, 0.1, 20.0)
    assert layout.safety_margin == 0.2
    assert (layout.conflict_model, layout.source) == (ConflictModel.BBOX, Path("maps/a.json"))


@pytest.mark.parametrize("query", ["successors", "predecessors"])
def test_asking_for_steps_of_an_unknown_segment_raises_layout_error(query: str) -> None:
    layout = build_layout(SEGMENTS, vehicle_radius=0.3)
    with pytest.raises(LayoutError, match=r"segment=99 is not in the layout \(2 segments\)"):
        getattr(layout, query)(99, Traverse.FORWARD)


def test_asking_for_conflicts_of_an_unknown_segment_raises_a_value_error() -> None:
    layout = build_layout(SEGMENTS, vehicle_radius=0.3, source=Path("map.json"))
    with pytest.raises(ValueError, match=r"segment=99 is not in the layout of map\.json"):
        layout.conflicts(99)
    with pytest.raises(FleetsimError):
        layout.conflicts(99)


def test_an_empty_layout_is_valid_and_empty() -> None:
    layout = build_layout([], vehicle_radius=0.3)
    assert (len(layout.segments), layout.connections, layout.graph.number_of_nodes(), layout.lint()) == (0, (), 0, ())


def test_repr_is_short() -> None:
    # 1 -> 2 and 2 -> 1 where they meet, plus a U-turn at each end of both two-way segments.
    assert repr(build_layout(SEGMENTS, vehicle_radius=0.3)) == "Layout(2 segments, 6 connections)"
