"""A scenario with an unreachable task fails its own test with the located message, before any run."""

from __future__ import annotations

import pytest
from plugin_helpers import RESERVING, copy_example_suites

from fleetsim.enums import Direction, Shape
from fleetsim.layout import Segment
from fleetsim.load.tiled.writer import write_map

SUITE = """\
fleetsim: 1
name: gap
scenarios:
  - name: half-metre-gap
    dir: gap/
"""


def test_an_unreachable_task_fails_its_scenario_naming_the_row_and_the_gap_and_the_others_still_run(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "400")  # the short summary keeps the whole first line
    copy_example_suites(pytester)  # the shipped examples, with their hashes: they still pass
    folder = pytester.path / "gap"
    folder.mkdir()
    write_map(
        folder / "map.json",
        (
            Segment(1, Shape.STRAIGHT, Direction.BOTH, ((-4.25, 0.0), (-0.25, 0.0))),
            Segment(2, Shape.STRAIGHT, Direction.BOTH, ((0.25, 0.0), (4.25, 0.0))),
        ),
    )
    (folder / "vehicles.csv").write_text("vehicle_id,start_segment_id,segment_orientation\n1,1,forward\n")
    (folder / "tasks.csv").write_text("vehicle_id,goal_segment_id\n1,2\n")
    (pytester.path / "gap.fleetsim.yaml").write_text(SUITE, encoding="utf-8")
    result = pytester.runpytest_inprocess("--planner", RESERVING, "-rf")
    result.assert_outcomes(passed=4, failed=1)
    located = "*gap/tasks.csv:2: field 'goal_segment_id': vehicle 1 cannot reach segment 2, the goal of task 1, from its start on segment 1 *"
    result.stdout.fnmatch_lines(
        [
            "*_ scenario half-metre-gap _*",
            located + "0.50 m from the first end of segment 2 at (0.250, 0.000)",
            "fleetsim scenario 'half-metre-gap' (gap.fleetsim.yaml:4)*",
            "*short test summary info*",
            "FAILED gap.fleetsim.yaml::half-metre-gap - " + located,
        ]
    )
    assert "Traceback" not in result.stdout.str()
