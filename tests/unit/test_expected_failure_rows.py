"""A scenario that expects a failure says in its summary row that the failure happened, in `fleetsim run`
and in pytest's table, worded from what the run showed; a plain pass says only ``passed``; an xfailed
row says what failed it (issue: reports that say where the trouble is, point 6)."""

from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

import pytest

from fleetsim.cli import main
from fleetsim.load.suites.scenario import load_scenario
from fleetsim.load.suites.suite import load_suite
from fleetsim.planners import BFSPlanner, GreedyPlanner, ReservingPlanner
from fleetsim.planning.checks import Rejection, RejectionCode
from fleetsim.scenario import Expectations
from fleetsim.sim.loop import run_scenario
from fleetsim.sim.report import expected_failures, outcome_cell, outcome_notes
from fleetsim.sim.result import RejectionEvent, RunResult

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
CAUGHT = SUITES / "caught-bugs.fleetsim.yaml"
EXAMPLES = SUITES / "examples.fleetsim.yaml"


def run_entry(suite: Path, name: str, planner: object, **expect: object) -> tuple[Expectations, RunResult]:
    loaded = load_suite(suite)
    [spec] = [spec for spec in loaded.scenarios if spec.name == name]
    scenario = load_scenario(spec, loaded)
    if expect:
        scenario = replace(scenario, expect=replace(scenario.expect, **expect))
    result = run_scenario(scenario, planner, keep_trace=False)  # type: ignore[arg-type]
    return scenario.expect, result


# -- the words --------------------------------------------------------------------------------------


def test_expected_collisions_are_said_to_have_happened() -> None:
    expect, result = run_entry(CAUGHT, "crossing-collides", BFSPlanner())
    assert result.passed and result.tasks_completed == 0 and len(result.collisions) == 4
    assert expected_failures(expect, result) == "expected collisions happened"
    named = replace(expect, collisions=(2, 3))
    assert expected_failures(named, result) == "expected collisions on segments 2, 3 happened"
    assert expected_failures(replace(expect, collisions=(2,)), replace(result, collisions=result.collisions[:1])) == (
        "expected collision on segment 2 happened"
    )


def test_expected_collisions_and_contacts_are_both_named() -> None:
    expect, result = run_entry(CAUGHT, "corridor-head-on", BFSPlanner())
    assert expected_failures(expect, result) == "expected collisions and contact happened"


def test_an_expected_deadlock_is_said_to_have_happened() -> None:
    expect, result = run_entry(EXAMPLES, "corridor-passing-bay", GreedyPlanner(), deadlock=True, tasks=0)
    assert result.passed and result.deadlock is not None
    assert expected_failures(expect, result) == "expected deadlock happened"


def test_expected_rejections_are_named_by_their_codes_or_counted() -> None:
    expect, result = run_entry(EXAMPLES, "crossing", ReservingPlanner())
    rejection = Rejection(RejectionCode.GOAL_DIRECTION, 1, 1, 2, "reaches the goal the wrong way")
    rejected = replace(result, rejections=(RejectionEvent(1.0, rejection), RejectionEvent(2.0, rejection)))
    assert expected_failures(replace(expect, rejections="any"), rejected) == "expected rejections happened"
    codes = replace(expect, rejections=("goal-direction",))
    assert expected_failures(codes, rejected) == "expected goal-direction rejection happened"


def test_fewer_tasks_than_all_alone_are_said_to_be_as_expected() -> None:
    expect, result = run_entry(EXAMPLES, "corridor-passing-bay", GreedyPlanner(), tasks=0, deadlock=True)
    assert expected_failures(replace(expect, deadlock=False), replace(result, deadlock=None)) == (
        "0 of 2 tasks, as expected"
    )


def test_a_plain_pass_adds_nothing() -> None:
    expect, result = run_entry(EXAMPLES, "crossing", ReservingPlanner())
    assert result.passed and expected_failures(expect, result) == ""
    assert outcome_cell("passed", outcome_notes(expect, result).get("passed", "")) == "passed"


def test_an_xfailed_row_says_what_failed_it() -> None:
    expect, result = run_entry(EXAMPLES, "crossing", BFSPlanner())
    notes = outcome_notes(expect, result)
    assert not result.passed and "passed" not in notes
    assert outcome_cell("xfailed", notes["xfailed"]) == "xfailed (failed: collision)"


# -- fleetsim run ---------------------------------------------------------------------------------


def test_fleetsim_run_says_the_expected_failure_happened_in_the_row_and_the_progress_line(
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = [
        "run",
        f"{CAUGHT}::crossing-collides",
        f"{EXAMPLES}::crossing",
        "--planner",
        "fleetsim.planners:ReservingPlanner",
    ]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    rows = {line.split()[0]: line for line in out.splitlines() if "::" in line.partition(" ")[0]}
    caught, plain = rows["caught-bugs.fleetsim.yaml::crossing-collides"], rows["examples.fleetsim.yaml::crossing"]
    assert "  passed (expected collisions happened)  0/2  " in caught
    assert plain.split()[1:3] == ["passed", "2/2"]  # a plain pass: nothing between outcome and tasks
    assert "crossing-collides: passed (expected collisions happened; tasks 0/2, t=0.2 s)" in err
    assert "crossing: passed (tasks 2/2, t=22.0 s)" in err


# -- pytest ---------------------------------------------------------------------------------------


def test_pytests_table_says_the_expected_failure_happened(pytester: pytest.Pytester) -> None:
    for folder in ("examples", "tiled", "caught-bugs"):
        shutil.copytree(SUITES / folder, pytester.path / folder)
    for suite in ("examples", "caught-bugs"):
        shutil.copy(SUITES / f"{suite}.fleetsim.yaml", pytester.path)
        shutil.copy(SUITES / f"{suite}.fleetsim.lock.json", pytester.path)
    result = pytester.runpytest_inprocess(
        "--planner",
        "fleetsim.planners:ReservingPlanner",
        "-k",
        "collides or head-on or crossing-stop or (examples and crossing)",
    )
    result.assert_outcomes(passed=4)
    result.stdout.re_match_lines(
        [
            r"caught-bugs.fleetsim.yaml::crossing-collides +passed \(expected collisions happened\) +0/2 ",
            r"caught-bugs.fleetsim.yaml::corridor-head-on +passed \(expected collisions and contact happened\) +2/2 ",
            r"caught-bugs.fleetsim.yaml::late-crossing-stop +passed \(expected collisions on segments 2, 3 happened\) +0/2 ",
            r"examples.fleetsim.yaml::crossing +passed +2/2 ",
        ]
    )


def test_pytests_xfailed_row_says_what_failed_it(pytester: pytest.Pytester) -> None:
    shutil.copytree(SUITES / "examples", pytester.path / "examples")
    shutil.copytree(SUITES / "tiled", pytester.path / "tiled")
    suite = (SUITES / "examples.fleetsim.yaml").read_text()
    line = "    dir: examples/corridor/\n"
    (pytester.path / "examples.fleetsim.yaml").write_text(suite.replace(line, f"{line}    xfail: gets stuck\n"))
    result = pytester.runpytest_inprocess(
        "--planner", "fleetsim.planners:GreedyPlanner", "-k", "corridor", "--fleetsim-record", "none"
    )
    result.assert_outcomes(xfailed=1)
    result.stdout.re_match_lines([r"corridor-passing-bay +xfailed \(failed: deadlock\) +0/2 "])
