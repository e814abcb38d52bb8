"""The plugin is found through the ``pytest11`` entry point of an installed fleetsim."""

from __future__ import annotations

from importlib.metadata import version

import pytest


def test_plugin_is_registered_and_reports_its_version(pytester: pytest.Pytester) -> None:
    pytester.makepyfile("def test_nothing():\n    pass\n")
    result = pytester.runpytest_subprocess()
    result.stdout.fnmatch_lines([f"fleetsim: {version('fleetsim')}, planner: (none given)"])
    result.assert_outcomes(passed=1)


def test_plugin_can_be_disabled_by_name(pytester: pytest.Pytester) -> None:
    pytester.makepyfile("def test_nothing():\n    pass\n")
    result = pytester.runpytest_subprocess("-p", "no:fleetsim")
    result.stdout.no_fnmatch_line("fleetsim: *")
    result.assert_outcomes(passed=1)


HEAVY = (
    "numpy",
    "hypothesis",
    "rosbags",
    "networkx",
    "jsonschema",
    "mcap",
    "fleetsim.sim",
    "fleetsim.layout",
    "fleetsim.load",
)
REPORT_IMPORTS = f"""
import sys

def test_report_what_is_imported():
    heavy = sorted(m for m in sys.modules if m.split(".")[0] in {HEAVY!r} or m.startswith({HEAVY!r}))
    print("HEAVY:", ",".join(heavy) or "-")
"""


def test_a_session_without_suites_does_not_import_the_harness(pytester: pytest.Pytester) -> None:
    """The plugin loads in every pytest session of an environment where fleetsim is installed: a project
    with no fleetsim suite must not pay for the simulator, NumPy, Hypothesis or the recorders."""
    pytester.makepyfile(REPORT_IMPORTS)
    result = pytester.runpytest_subprocess("-s", "-p", "no:hypothesispytest")
    result.stdout.fnmatch_lines(["*HEAVY: -"])
    result.assert_outcomes(passed=1)


def test_a_session_with_a_fleetsim_option_loads_the_harness_before_any_test(pytester: pytest.Pytester) -> None:
    """The narrow other side: an option such as --planner is checked at once, which needs the harness."""
    pytester.makepyfile(REPORT_IMPORTS)
    result = pytester.runpytest_subprocess(
        "-s", "-p", "no:hypothesispytest", "--planner", "fleetsim.planners:BFSPlanner"
    )
    result.stdout.fnmatch_lines(["fleetsim: *, planner: fleetsim.planners:BFSPlanner", "*HEAVY: *fleetsim.sim*"])
    result.assert_outcomes(passed=1)


def test_a_bad_planner_option_is_a_usage_error_before_any_test(pytester: pytest.Pytester) -> None:
    pytester.makepyfile("def test_nothing():\n    pass\n")
    result = pytester.runpytest_subprocess("--planner", "no_such_module:Planner")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    result.stderr.fnmatch_lines(["*--planner: *no_such_module*"])
