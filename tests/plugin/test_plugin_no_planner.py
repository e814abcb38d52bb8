"""No silent pass: a pytest session that collects scenarios needing a planner, and has none, is a usage
error before any test runs; every way of giving a planner, or of not needing one, still runs."""

from __future__ import annotations

import pytest
from plugin_helpers import RESERVING, copy_example_suites

NO_PLANNER_START = "ERROR: no planner to test: run pytest with --planner module:Planner"

PLAIN_TEST = """\
def test_plain():
    assert True
"""

SUITE_WITH_ITS_PLANNER = f"""\
fleetsim: 1
name: own
planner: {RESERVING}
vehicle_types:
  agv: {{length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}}
defaults:
  vehicle_type: agv
scenarios:
  - name: crossing-with-its-planner
    dir: examples/crossing/
"""


@pytest.fixture(autouse=True)
def _not_in_ci(monkeypatch: pytest.MonkeyPatch) -> None:
    """The runs here record no hashes; under CI a missing hash would fail the scenarios that run."""
    monkeypatch.delenv("CI", raising=False)


def test_scenarios_without_a_planner_are_a_usage_error_before_any_test_runs(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    pytester.makepyfile(test_plain=PLAIN_TEST.replace("assert True", "open('ran', 'w').close()"))
    result = pytester.runpytest_inprocess()
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    errors = result.stderr.str()
    assert NO_PLANNER_START in errors, errors
    assert "4 collected scenario(s) need one (examples.fleetsim.yaml::crossing, " in errors, errors
    assert "--fleetsim-skip-without-planner" in errors and "fleetsim_skip_without_planner = true" in errors
    assert not (pytester.path / "ran").exists()  # not even the plain test ran
    assert not (pytester.path / "fleetsim-results").exists()


def test_the_error_names_only_the_scenarios_left_after_deselection(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    result = pytester.runpytest_inprocess("-k", "crossing or loop")
    assert result.ret == pytest.ExitCode.USAGE_ERROR
    assert "2 collected scenario(s) need one (examples.fleetsim.yaml::crossing, " in result.stderr.str()


@pytest.mark.parametrize("how", ["option", "ini"])
def test_the_opt_out_skips_them_instead(pytester: pytest.Pytester, how: str) -> None:
    copy_example_suites(pytester)
    if how == "ini":
        pytester.makeini("[pytest]\nfleetsim_skip_without_planner = true\n")
    result = pytester.runpytest_inprocess(*(["--fleetsim-skip-without-planner"] if how == "option" else []))
    assert result.ret == pytest.ExitCode.OK, result.stdout.str()
    result.assert_outcomes(skipped=4)


def test_the_ini_opt_out_set_false_keeps_the_error(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    pytester.makeini("[pytest]\nfleetsim_skip_without_planner = false\n")
    assert pytester.runpytest_inprocess().ret == pytest.ExitCode.USAGE_ERROR


@pytest.mark.parametrize("how", ["--planner", "ini"])
def test_a_planner_from_the_option_or_the_ini_runs_them(pytester: pytest.Pytester, how: str) -> None:
    copy_example_suites(pytester)
    if how == "ini":
        pytester.makeini(f"[pytest]\nfleetsim_planner = {RESERVING}\n")
    result = pytester.runpytest_inprocess(*(["--planner", RESERVING] if how == "--planner" else []), "-k", "crossing")
    result.assert_outcomes(passed=1)


def test_an_overriding_fixture_is_a_planner(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    pytester.makeconftest(
        "import pytest\nfrom fleetsim.planners import ReservingPlanner\n\n\n"
        "@pytest.fixture\ndef fleetsim_planner():\n    return ReservingPlanner\n"
    )
    result = pytester.runpytest_inprocess("-k", "crossing")
    result.assert_outcomes(passed=1)


def test_an_override_in_one_folder_leaves_the_others_needing_a_planner(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    served = pytester.mkpydir("served")
    (served / "conftest.py").write_text(
        "import pytest\nfrom fleetsim.planners import ReservingPlanner\n\n\n"
        "@pytest.fixture\ndef fleetsim_planner():\n    return ReservingPlanner\n"
    )
    own = SUITE_WITH_ITS_PLANNER.replace(f"planner: {RESERVING}\n", "").replace("examples/", "../examples/")
    (served / "own.fleetsim.yaml").write_text(own)
    result = pytester.runpytest_inprocess("served")
    result.assert_outcomes(passed=1)  # the folder's override serves its suite
    result = pytester.runpytest_inprocess()
    assert result.ret == pytest.ExitCode.USAGE_ERROR  # the top-level suite has no override
    assert "4 collected scenario(s) need one" in result.stderr.str()


def test_a_suite_naming_its_planner_needs_none_from_the_session(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    pytester.makefile(".fleetsim.yaml", own=SUITE_WITH_ITS_PLANNER)
    result = pytester.runpytest_inprocess("own.fleetsim.yaml")
    result.assert_outcomes(passed=1)


def test_collect_only_and_sessions_without_scenarios_are_not_affected(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    pytester.makepyfile(test_plain=PLAIN_TEST)
    assert pytester.runpytest_inprocess("--collect-only").ret == pytest.ExitCode.OK
    result = pytester.runpytest_inprocess("test_plain.py")
    result.assert_outcomes(passed=1)
    result = pytester.runpytest_inprocess("-k", "plain")  # every scenario deselected
    result.assert_outcomes(passed=1)


def test_under_pytest_xdist_the_session_ends_with_the_same_usage_error(pytester: pytest.Pytester) -> None:
    copy_example_suites(pytester)
    result = pytester.runpytest_subprocess("-n", "2", "-p", "no:cacheprovider", timeout=120)
    assert result.ret == pytest.ExitCode.USAGE_ERROR, result.stdout.str()
    output = result.stdout.str()
    assert "no planner to test: run pytest with --planner module:Planner" in output, output
    assert "INTERNALERROR" not in output + result.stderr.str()
    assert "passed" not in output and "skipped" not in output
    result = pytester.runpytest_subprocess(
        "-n", "2", "-p", "no:cacheprovider", "--fleetsim-skip-without-planner", timeout=120
    )
    assert result.ret == pytest.ExitCode.OK
    result.assert_outcomes(skipped=4)
