"""The ``gap`` lint: a dangling end within a vehicle length of another segment's end, and the 0.5 m gap
map end to end through ``fleetsim validate`` and ``fleetsim inspect``."""

from __future__ import annotations

from pathlib import Path

import pytest

from fleetsim.cli import main
from fleetsim.enums import Direction, Shape
from fleetsim.layout import Layout, Segment, build_layout
from fleetsim.load import load_scenario, load_suite
from fleetsim.load.tiled.writer import write_map

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"


def straight(sid: int, a: tuple[float, float], b: tuple[float, float]) -> Segment:
    return Segment(sid, Shape.STRAIGHT, Direction.BOTH, (a, b))


def apart(gap: float) -> tuple[Segment, Segment]:
    """Two straights in a line whose facing ends are ``gap`` metres apart."""
    half = gap / 2
    return straight(1, (-4.0 - half, 0.0), (-half, 0.0)), straight(2, (half, 0.0), (4.0 + half, 0.0))


def layout_of(*segments: Segment) -> Layout:
    return build_layout(segments, vehicle_radius=0.5)


def codes(layout: Layout, vehicle_length: float | None) -> list[str]:
    return [finding.code for finding in layout.lint(vehicle_length)]


def test_a_dangling_end_within_a_vehicle_length_of_another_end_is_a_gap_naming_both_ends_and_the_distance() -> None:
    gaps = [f for f in layout_of(*apart(0.5)).lint(1.0) if f.code == "gap"]
    assert [(f.severity, f.segments, f.message) for f in gaps] == [
        (
            "warning",
            (1, 2),
            "the last end of segment 1 at (-0.250, 0.000) is a dead end 0.50 m from the first end of segment 2 "
            "at (0.250, 0.000), within a vehicle length (1 m): did you mean to connect them?",
        )
    ]


def test_without_a_vehicle_length_the_layout_lints_without_gaps() -> None:
    assert "gap" not in codes(layout_of(*apart(0.5)), None)
    assert codes(layout_of(*apart(0.5)), None).count("dangling-end") == 4


def test_ends_farther_apart_than_a_vehicle_length_are_no_gap() -> None:
    assert "gap" not in codes(layout_of(*apart(1.2)), 1.0)
    assert "gap" in codes(layout_of(*apart(1.2)), 1.4)


def test_ends_within_ten_connection_tolerances_are_a_near_miss_and_not_also_a_gap() -> None:
    found = codes(layout_of(*apart(0.3)), 1.0)
    assert "near-miss" in found and "gap" not in found


def test_ends_within_the_connection_tolerance_connect_and_are_neither() -> None:
    found = codes(layout_of(*apart(0.04)), 1.0)
    assert "gap" not in found and "near-miss" not in found
    assert found.count("dangling-end") == 2  # the two outer ends


def test_a_dangling_end_short_of_a_junction_is_a_gap_to_the_nearest_end_there() -> None:
    # Segments 2 and 3 meet at (5, 0); segment 1 stops 0.6 m short of that junction.
    layout = layout_of(
        straight(1, (0.0, 0.0), (4.4, 0.0)), straight(2, (5.0, 0.0), (9.0, 0.0)), straight(3, (5.0, 0.0), (5.0, 4.0))
    )
    gaps = [f for f in layout.lint(1.0) if f.code == "gap"]
    assert [f.segments for f in gaps] == [(1, 2)]
    assert "0.60 m" in gaps[0].message


def test_a_short_segments_own_other_end_is_no_gap() -> None:
    assert "gap" not in codes(layout_of(straight(1, (0.0, 0.0), (0.5, 0.0))), 1.0)


def test_no_shipped_scenario_has_a_gap() -> None:
    for suite_path in sorted(SUITES.glob("*.fleetsim.yaml")):
        suite = load_suite(suite_path)
        for spec in suite.scenarios:
            if spec.generate is None:
                scenario = load_scenario(spec, suite)
                assert "gap" not in codes(scenario.layout, scenario.vehicle_length), spec.name


# -- the 0.5 m gap map, end to end ---------------------------------------------------------------


@pytest.fixture
def gap_suite(tmp_path: Path) -> Path:
    folder = tmp_path / "gap"
    folder.mkdir()
    write_map(folder / "map.json", apart(0.5))
    (folder / "vehicles.csv").write_text("vehicle_id,start_segment_id,segment_orientation\n1,1,forward\n")
    (folder / "tasks.csv").write_text("vehicle_id,goal_segment_id,goal_progress_direction\n1,2,\n")
    suite = tmp_path / "gap.fleetsim.yaml"
    suite.write_text("fleetsim: 1\nname: gap\nscenarios:\n  - name: half-metre-gap\n    dir: gap/\n")
    return suite


def test_validate_of_the_gap_map_warns_with_the_distance_and_refuses_the_task_at_its_row(
    gap_suite: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["validate", str(gap_suite)]) == 1
    out = capsys.readouterr().out
    tasks = gap_suite.parent / "gap" / "tasks.csv"
    assert f"  FAIL half-metre-gap\n       {tasks}:2: field 'goal_segment_id': vehicle 1 cannot reach segment 2" in out
    assert "the closest dangling end is the last end of segment 1 at (-0.250, 0.000), 0.50 m from" in out
    assert (
        "       warning gap: the last end of segment 1 at (-0.250, 0.000) is a dead end 0.50 m from the first end "
        "of segment 2 at (0.250, 0.000), within a vehicle length (1 m): did you mean to connect them?\n"
    ) in out
    assert out.endswith("1 suite(s): 0 scenario(s) valid, 1 failed, 6 lint warning(s)\n")


def test_validate_of_the_gap_map_without_the_task_warns_and_passes(
    gap_suite: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (gap_suite.parent / "gap" / "tasks.csv").write_text("vehicle_id,goal_segment_id\n")
    assert main(["validate", str(gap_suite)]) == 0
    out = capsys.readouterr().out
    assert "  ok   half-metre-gap:" in out and "warning gap: " in out and "0.50 m" in out


def test_inspect_of_a_bare_map_measures_gaps_against_the_default_vehicle(
    gap_suite: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["inspect", str(gap_suite.parent / "gap" / "map.json")]) == 0
    assert "warning gap: " in capsys.readouterr().out
