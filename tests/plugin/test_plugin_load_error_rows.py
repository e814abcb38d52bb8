"""Scenarios that never ran have their row in the session's summary table: a load error says so in the
outcome column (and no suite ``xfail`` excuses it), a planner that cannot be made is a failed row; neither
has metrics to compare."""

from __future__ import annotations

import json

import pytest
from plugin_helpers import RESERVING, copy_example_suites

from fleetsim.sim.report import SUMMARY_COLUMNS

NOTHING = ["-"] * (len(SUMMARY_COLUMNS) - 2)  # a row's cells after its scenario and outcome, for no run


def _row(result: pytest.RunResult, name: str) -> list[str]:
    [line] = [line for line in result.stdout.lines if line.startswith(f"{name} ")]
    return line.split()


def _break_the_loop(pytester: pytest.Pytester) -> None:
    (pytester.path / "examples" / "loop" / "tasks.csv").write_text("vehicle_id,goal_segment_id\n1,99\n2,2\n")


def test_a_scenario_that_does_not_load_is_a_load_error_row_and_counted(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("CI", raising=False)
    copy_example_suites(pytester)
    _break_the_loop(pytester)
    result = pytester.runpytest_inprocess("--planner", RESERVING, "--fleetsim-metrics-json", "metrics.json")
    result.assert_outcomes(passed=3, failed=1)
    assert _row(result, "loop-one-way")[1:] == ["load", "error", *NOTHING]
    assert _row(result, "crossing")[1] == "passed"  # narrow: the others are rows of their own outcome
    metrics = json.loads((pytester.path / "metrics.json").read_text())
    ids = sorted(entry["id"] for entry in metrics["scenarios"])
    assert ids == sorted(f"examples.fleetsim.yaml::{n}" for n in ("crossing", "corridor-passing-bay", "mixed-shapes"))


def test_the_count_names_the_load_errors(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("CI", raising=False)
    copy_example_suites(pytester, locks=False)  # no hashes: the count line is shown
    _break_the_loop(pytester)
    result = pytester.runpytest_inprocess("--planner", RESERVING)
    result.stdout.fnmatch_lines(["4 scenarios: 3 passed, 1 load error; 3 trace hashes not recorded*"])


def _xfail(pytester: pytest.Pytester, folder: str) -> None:
    suite = pytester.path / "examples.fleetsim.yaml"
    line = f"    dir: examples/{folder}/\n"
    suite.write_text(suite.read_text().replace(line, f"{line}    xfail: a known bug\n"))


def test_an_xfail_scenario_that_does_not_load_still_fails(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    _break_the_loop(pytester)
    _xfail(pytester, "loop")
    result = pytester.runpytest_inprocess("--planner", RESERVING, "-k", "loop")
    result.assert_outcomes(failed=1)
    assert _row(result, "loop-one-way")[1:3] == ["load", "error"]


def test_an_xfail_scenario_that_fails_its_checks_is_still_xfailed(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    _xfail(pytester, "corridor")
    result = pytester.runpytest_inprocess("--planner", "fleetsim.planners:GreedyPlanner", "-k", "corridor")
    result.assert_outcomes(xfailed=1)  # GreedyPlanner gets stuck in the corridor
    assert _row(result, "corridor-passing-bay")[1] == "xfailed"


def test_a_planner_that_cannot_be_made_is_a_failed_row(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    pytester.makepyfile(
        broken="class Planner:\n    def __init__(self):\n        raise RuntimeError('no licence')\n"
        "    def plan_routes(self, task, fleet, layout): ...\n"
        "    def fix_legs(self, task, fleet, layout): ...\n"
    )
    pytester.syspathinsert()
    result = pytester.runpytest_inprocess("--planner", "broken:Planner", "-k", "crossing")
    result.assert_outcomes(failed=1)
    assert _row(result, "crossing")[1:] == ["failed", *NOTHING]
