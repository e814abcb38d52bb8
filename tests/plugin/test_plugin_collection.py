"""The plugin end to end through pytester: suites collected as tests, how the planner under test is
chosen, and what a broken planner looks like in a pytest report."""

from __future__ import annotations

import glob
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from plugin_helpers import BFS, RESERVING, SUITES, copy_example_suites, record_hashes

NAMES = ["crossing", "loop-one-way", "corridor-passing-bay", "mixed-shapes"]

BROKEN_PLANNERS = """\
from fleetsim.planners import ReservingPlanner


class RaisingAtJunction(ReservingPlanner):
    # ReservingPlanner, except for the crossing's first task (the only one to segment 4 there).
    def plan_routes(self, task, fleet, layout):
        if task.goal_segment == 4:
            raise ValueError("no route through the junction")
        return super().plan_routes(task, fleet, layout)


class RaisingInFixLegs(ReservingPlanner):
    def fix_legs(self, task, fleet, layout):
        raise ValueError("cannot fix legs")


class ReturningDict(ReservingPlanner):
    def plan_routes(self, task, fleet, layout):
        return {"vehicle": task.vehicle_id}


class FailingConstructor(ReservingPlanner):
    def __init__(self):
        raise RuntimeError("no licence for the route server")
"""

CONFTEST_PLANNER = """\
import pytest

from fleetsim.planners import ReservingPlanner


class ConftestPlanner(ReservingPlanner):
    "The reference planner under its own name, so the lock file shows which override ran."


def make_planner():
    return ConftestPlanner()


@pytest.fixture
def fleetsim_planner():
    return {value}
"""


def line_of(snippet: str, text: str = BROKEN_PLANNERS) -> int:
    return next(number for number, line in enumerate(text.splitlines(), 1) if snippet in line)


def output(result: pytest.RunResult) -> str:
    return result.stdout.str() + result.stderr.str()


def collected_ids(result: pytest.RunResult) -> list[str]:
    """The test ids of a ``--collect-only -q`` run, in collection order."""
    return [line for line in result.stdout.lines if "::" in line]


def scenario_line(suite: Path, name: str) -> int:
    lines = suite.read_text(encoding="utf-8").splitlines()
    return next(number for number, line in enumerate(lines, 1) if line.strip() == f"- name: {name}")


def write_suite(path: Path, *names: str, folder: str = "examples/crossing/") -> None:
    """A minimal suite whose scenarios ``names`` all drive the folder ``folder``."""
    entries = "".join(f"  - name: {name}\n    dir: {folder}\n" for name in names)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"fleetsim: 1\nname: {path.stem}\nscenarios:\n{entries}", encoding="utf-8")


def lock_as(pytester: pytest.Pytester, identity: str) -> None:
    """The shipped ReservingPlanner hashes of the examples suite, recorded for ``identity`` instead:
    for a planner that behaves like ReservingPlanner on the scenarios it is expected to pass."""
    lock = json.loads((SUITES / "examples.fleetsim.lock.json").read_text(encoding="utf-8"))
    lock["hashes"] = {identity: lock["hashes"][RESERVING]}
    (pytester.path / "examples.fleetsim.lock.json").write_text(json.dumps(lock), encoding="utf-8")


def recorded_identities(pytester: pytest.Pytester) -> dict[str, list[str]]:
    lock = json.loads((pytester.path / "examples.fleetsim.lock.json").read_text(encoding="utf-8"))
    return {identity: sorted(scenarios) for identity, scenarios in lock["hashes"].items()}


@pytest.fixture
def wide_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    """Short test summary lines are cut to the terminal's width; make room for a whole first line."""
    monkeypatch.setenv("COLUMNS", "300")


@pytest.fixture
def broken_planners(pytester: pytest.Pytester) -> str:
    """The examples suite (with its lock file) and an importable module of broken planners."""
    copy_example_suites(pytester)
    pytester.makepyfile(broken_planners=BROKEN_PLANNERS)
    pytester.syspathinsert()
    return "broken_planners"


# -- collection -----------------------------------------------------------------------------------


def test_each_scenario_is_one_test_named_by_suite_path_and_scenario_in_file_order(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester, locks=False)
    write_suite(
        pytester.path / "suites" / "order.fleetsim.yaml", "zeta", "alpha", "mid", folder="../examples/crossing/"
    )
    result = pytester.runpytest_inprocess("--collect-only", "-q", "suites")
    assert collected_ids(result) == [f"suites/order.fleetsim.yaml::{name}" for name in ("zeta", "alpha", "mid")]


def test_the_shipped_examples_are_collected_in_file_order(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    result = pytester.runpytest_inprocess("--collect-only", "-q")
    assert collected_ids(result) == [f"examples.fleetsim.yaml::{name}" for name in NAMES]


def test_the_suite_patterns_ini_option_replaces_the_default_pattern(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester, locks=False)
    pytester.makeini("[pytest]\nfleetsim_suite_patterns = *.suite.yaml\n")
    write_suite(pytester.path / "mine.suite.yaml", "chosen")
    write_suite(pytester.path / "default.fleetsim.yaml", "ignored")
    write_suite(pytester.path / "other.yaml", "not-a-suite")
    result = pytester.runpytest_inprocess("--collect-only", "-q")
    assert collected_ids(result) == ["mine.suite.yaml::chosen"]


def test_k_selects_scenarios_by_name(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    result = pytester.runpytest_inprocess("--collect-only", "-q", "-k", "loop-one-way or mixed")
    assert collected_ids(result) == ["examples.fleetsim.yaml::loop-one-way", "examples.fleetsim.yaml::mixed-shapes"]


def test_suite_tags_are_markers_that_m_selects_and_strict_markers_accepts(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)  # crossing carries `tags: [smoke]`
    result = pytester.runpytest_inprocess("--collect-only", "-q", "-m", "smoke", "--strict-markers")
    assert result.ret == pytest.ExitCode.OK, output(result)
    assert collected_ids(result) == ["examples.fleetsim.yaml::crossing"]
    assert "3 deselected" in result.stdout.str()
    assert "PytestUnknownMarkWarning" not in output(result) and "warnings summary" not in output(result)


def test_a_suite_xfail_turns_a_failing_scenario_into_xfailed_and_a_passing_one_into_xpassed(
    pytester: pytest.Pytester,
) -> None:
    copy_example_suites(pytester)
    suite = pytester.path / "examples.fleetsim.yaml"
    text = suite.read_text(encoding="utf-8")
    assert text.count("    tags: [smoke]\n") == 1  # the crossing's entry
    suite.write_text(
        text.replace("    tags: [smoke]\n", "    tags: [smoke]\n    xfail: BFSPlanner collides at the junction\n"),
        encoding="utf-8",
    )

    failing = pytester.runpytest_inprocess("--planner", BFS, "-k", "crossing", "-rx")
    failing.assert_outcomes(xfailed=1)
    failing.stdout.fnmatch_lines(["XFAIL examples.fleetsim.yaml::crossing*BFSPlanner collides at the junction"])
    row = next(line.split() for line in failing.stdout.lines if line.startswith("crossing "))
    assert row[1] == "xfailed" and row[4] != "0", row  # it failed for the collision alert

    passing = pytester.runpytest_inprocess("--planner", RESERVING, "-k", "crossing")
    passing.assert_outcomes(xpassed=1)
    passing.stdout.fnmatch_lines(["crossing *xpassed *2/2 *"])


@pytest.mark.parametrize(
    ("entry", "line", "message"),
    [
        ("  - name: a\n    dir: examples/crossing/\n    colour: red\n", 6, "scenarios[0]: unknown key 'colour'"),
        (
            "  - name: a\n    dir: examples/crossing/\n  - name: b\n    dir: examples/nowhere/\n",
            7,
            "scenarios[1].dir: no such directory",
        ),
    ],
    ids=["unknown-key", "missing-folder"],
)
def test_a_bad_suite_fails_collection_at_its_file_and_line_without_a_harness_traceback(
    pytester: pytest.Pytester, entry: str, line: int, message: str
) -> None:
    copy_example_suites(pytester, locks=False)
    (pytester.path / "bad.fleetsim.yaml").write_text(f"fleetsim: 1\nname: bad\nscenarios:\n{entry}", encoding="utf-8")
    result = pytester.runpytest_inprocess("--planner", RESERVING)
    assert result.ret == pytest.ExitCode.INTERRUPTED
    result.stdout.fnmatch_lines(
        ["*ERROR collecting bad.fleetsim.yaml*", f"*bad.fleetsim.yaml:{line}:*: {glob.escape(message)}*"]
    )
    text = output(result)
    assert "Traceback" not in text
    assert "fleetsim/load" not in text and "pytest_fleetsim/" not in text


# -- choosing the planner -------------------------------------------------------------------------


@pytest.mark.parametrize("how", ["--planner", "--fleetsim-planner", "ini"])
def test_the_planner_comes_from_the_option_its_alias_or_the_ini_file(pytester: pytest.Pytester, how: str) -> None:
    copy_example_suites(pytester)  # its lock file holds ReservingPlanner's hashes
    if how == "ini":
        pytester.makeini(f"[pytest]\nfleetsim_planner = {RESERVING}\n")
        args: tuple[str, ...] = ()
    else:
        args = (how, RESERVING)
    result = pytester.runpytest_inprocess(*args, "-k", "crossing")
    result.stdout.fnmatch_lines([f"fleetsim: *, planner: {RESERVING}"])
    result.assert_outcomes(passed=1)


def test_skipping_without_a_planner_skips_each_scenario_saying_how_to_pass_one(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    result = pytester.runpytest_inprocess("-rs", "--fleetsim-skip-without-planner")
    result.assert_outcomes(skipped=4)
    skipped = [line for line in result.stdout.lines if line.startswith("SKIPPED")]
    assert len(skipped) == 4, skipped  # one per scenario, each at its own line of the suite
    for line in skipped:
        assert "no planner to test: run pytest with --planner module:Planner" in line and "fleetsim_planner" in line


def test_the_no_planner_skip_points_at_the_suite_not_at_the_harness(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    result = pytester.runpytest_inprocess("-rs", "-k", "crossing", "--fleetsim-skip-without-planner")
    skipped = [line for line in result.stdout.lines if line.startswith("SKIPPED")]
    assert skipped and all("examples.fleetsim.yaml" in line and "_state.py" not in line for line in skipped), skipped


@pytest.mark.parametrize(
    ("spec", "problem"),
    [
        ("no_such_planner_module:Planner", "no module named 'no_such_planner_module'"),
        ("fleetsim.planners:NoSuchPlanner", "'fleetsim.planners' has no attribute 'NoSuchPlanner'"),
        ("collections:OrderedDict", "class OrderedDict has no plan_routes or fix_legs method"),
        ("os:sep", "names '/' of type str, which is not callable"),
    ],
    ids=["no-module", "no-attribute", "no-planner-methods", "not-callable"],
)
def test_a_planner_spec_that_gives_no_planner_is_a_usage_error(
    pytester: pytest.Pytester, spec: str, problem: str
) -> None:
    copy_example_suites(pytester)
    result = pytester.runpytest_inprocess("--planner", spec)
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines([f"ERROR: --planner: planner spec {spec!r}*{problem}*"])
    assert "Traceback" not in output(result)


@pytest.mark.parametrize(
    ("value", "identity"),
    [
        ("ConftestPlanner", "conftest:ConftestPlanner"),
        ("make_planner", "conftest:make_planner"),
        ("ConftestPlanner()", "conftest:ConftestPlanner"),
    ],
    ids=["class", "factory", "instance"],
)
def test_a_conftest_fixture_override_is_used_instead_of_planner_and_keys_the_lock_file(
    pytester: pytest.Pytester, value: str, identity: str
) -> None:
    copy_example_suites(pytester, locks=False)
    pytester.makeconftest(CONFTEST_PLANNER.format(value=value))
    # --planner names BFSPlanner, which collides on the crossing: only the override could pass.
    result = record_hashes(pytester, "--planner", BFS, "-k", "crossing")
    result.assert_outcomes(passed=1)
    assert recorded_identities(pytester) == {identity: ["crossing"]}
    pytester.runpytest_inprocess("--planner", BFS, "-k", "crossing").assert_outcomes(passed=1)


def test_a_conftest_autouse_fixture_runs_for_every_scenario(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    pytester.makeconftest(
        """
        import pytest

        @pytest.fixture(autouse=True)
        def note_scenario(request):
            with open("ran.txt", "a") as notes:
                notes.write(request.node.nodeid + "\\n")
        """
    )
    result = pytester.runpytest_inprocess("--planner", RESERVING, "-k", "crossing or corridor")
    result.assert_outcomes(passed=2)
    ran = (pytester.path / "ran.txt").read_text(encoding="utf-8").splitlines()
    assert ran == ["examples.fleetsim.yaml::crossing", "examples.fleetsim.yaml::corridor-passing-bay"]


def test_a_fixture_value_that_is_not_a_planner_fails_the_scenario_saying_what_it_must_be(
    pytester: pytest.Pytester,
) -> None:
    copy_example_suites(pytester)
    pytester.makeconftest("import pytest\n\n@pytest.fixture\ndef fleetsim_planner():\n    return 42\n")
    result = pytester.runpytest_inprocess("-k", "crossing")
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            "*the fleetsim_planner fixture returned 42; it must return a planner (an object with plan_routes and fix_legs)*"
        ]
    )
    assert "Traceback" not in output(result)


def test_a_suite_pinned_to_a_planner_runs_with_it_whatever_planner_names(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester, "caught-bugs")  # pinned to BFSPlanner; its lock holds BFSPlanner's hashes
    result = pytester.runpytest_inprocess("caught-bugs.fleetsim.yaml", "--planner", RESERVING, "--junitxml=junit.xml")
    result.assert_outcomes(passed=3, xfailed=2)  # ReservingPlanner would raise no collision alert here
    cases = ET.parse(pytester.path / "junit.xml").getroot().iter("testcase")
    planners = {
        prop.get("value") for case in cases for prop in case.iter("property") if prop.get("name") == "fleetsim_planner"
    }
    assert planners == {BFS}


# -- broken planners ------------------------------------------------------------------------------


@pytest.mark.usefixtures("wide_terminal")
def test_a_raising_planner_fails_its_scenario_with_its_own_traceback_and_the_next_scenario_still_runs(
    pytester: pytest.Pytester, broken_planners: str
) -> None:
    spec = f"{broken_planners}:RaisingAtJunction"
    lock_as(pytester, spec)  # elsewhere it behaves as ReservingPlanner
    result = pytester.runpytest_inprocess("--planner", spec, "-k", "crossing or corridor", "-rf")
    result.assert_outcomes(failed=1, passed=1)
    line = scenario_line(pytester.path / "examples.fleetsim.yaml", "crossing")
    result.stdout.fnmatch_lines(
        [
            "planner-error at t=*: plan_routes() for vehicle 1 raised ValueError: no route through the junction",
            f"fleetsim scenario 'crossing' (examples.fleetsim.yaml:{line}) with planner {spec}",
            "*Traceback (most recent call last):",
            f'*File "*{broken_planners}.py", line {line_of("no route through")}, in plan_routes',
            '*raise ValueError("no route through the junction")',
            "*ValueError: no route through the junction",
        ]
    )
    result.stdout.fnmatch_lines(
        [
            "FAILED examples.fleetsim.yaml::crossing - planner-error at t=*: plan_routes() for vehicle 1 raised "
            "ValueError: no route through the junction",
        ]
    )
    text = output(result)
    assert "fleetsim/sim/" not in text and "pytest_fleetsim/" not in text
    assert "corridor-passing-bay  passed" in text


def test_a_planner_raising_in_fix_legs_shows_the_raise_line_of_fix_legs(
    pytester: pytest.Pytester, broken_planners: str
) -> None:
    result = pytester.runpytest_inprocess("--planner", f"{broken_planners}:RaisingInFixLegs", "-k", "crossing")
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            "planner-error at t=*: fix_legs() for vehicle * raised ValueError: cannot fix legs",
            f'*File "*{broken_planners}.py", line {line_of("cannot fix legs")}, in fix_legs',
            '*raise ValueError("cannot fix legs")',
        ]
    )
    assert "fleetsim/sim/loop.py" not in output(result)


@pytest.mark.usefixtures("wide_terminal")
def test_a_planner_returning_garbage_fails_naming_the_method_the_vehicle_and_the_value(
    pytester: pytest.Pytester, broken_planners: str
) -> None:
    result = pytester.runpytest_inprocess("--planner", f"{broken_planners}:ReturningDict", "-k", "crossing", "-rf")
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            "FAILED examples.fleetsim.yaml::crossing - planner-error at t=*: plan_routes() for vehicle 1 returned {'vehicle': 1}*"
        ]
    )


def test_a_planner_whose_constructor_raises_fails_with_the_constructors_error(
    pytester: pytest.Pytester, broken_planners: str
) -> None:
    result = pytester.runpytest_inprocess("--planner", f"{broken_planners}:FailingConstructor", "-k", "crossing")
    result.assert_outcomes(failed=1)
    line = scenario_line(pytester.path / "examples.fleetsim.yaml", "crossing")
    result.stdout.fnmatch_lines(
        [
            "planner-error: *FailingConstructor() raised RuntimeError: no licence for the route server "
            f"(*{broken_planners}.py:{line_of('no licence')})",
            f"fleetsim scenario 'crossing' (examples.fleetsim.yaml:{line}) with planner*",
            '*raise RuntimeError("no licence for the route server")',
        ]
    )
    assert "fleetsim/sim/" not in output(result)


@pytest.mark.usefixtures("wide_terminal")
@pytest.mark.parametrize(
    ("fixture_value", "problem"),
    [
        (None, "*FailingConstructor() raised RuntimeError: no licence for the route server*"),
        ("42", "*the fleetsim_planner fixture returned 42*"),
    ],
    ids=["constructor", "fixture-value"],
)
def test_the_short_summary_of_a_planner_that_cannot_be_made_says_what_went_wrong(
    pytester: pytest.Pytester, broken_planners: str, fixture_value: str | None, problem: str
) -> None:
    args: tuple[str, ...] = ("--planner", f"{broken_planners}:FailingConstructor")
    if fixture_value is not None:
        pytester.makeconftest(
            f"import pytest\n\n@pytest.fixture\ndef fleetsim_planner():\n    return {fixture_value}\n"
        )
        args = ()
    result = pytester.runpytest_inprocess(*args, "-k", "crossing", "-rf")
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines([f"FAILED examples.fleetsim.yaml::crossing - {problem}"])
