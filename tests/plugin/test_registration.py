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
