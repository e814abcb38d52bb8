"""What a pytest session that runs scenarios imports: Hypothesis only for a generated entry, the exec
protocol only for an ``exec:`` planner, the recording libraries only for a run that leaves a recording; and
fleetsim's library is not assertion-rewritten (pytest marks a plugin's whole distribution, and rewrites a
marked module on every start where it cannot keep bytecode).

A conftest dumps ``sys.modules`` at the session's end (``pytest_sessionfinish`` runs before the terminal
summary, where Hypothesis's own plugin imports Hypothesis in every session whatever was collected).
"""

from __future__ import annotations

import sys

import pytest
from plugin_helpers import RESERVING, copy_example_suites

DUMP_MODULES = """\
import sys


def pytest_sessionfinish(session):
    with open("modules.txt", "w", encoding="utf-8") as dump:
        dump.write("\\n".join(sorted(sys.modules)))
"""

GENERATED = """\
fleetsim: 1
name: hunting
vehicle_types:
  agv: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}
scenarios:
  - name: random-loop
    generate: {layout: loop, size: [1, 1], vehicles: [1, 1], tasks: [1, 1], examples: 1}
"""


def all_imported(pytester: pytest.Pytester, *args: str, status: int = pytest.ExitCode.OK) -> set[str]:
    """Every module a pytest subprocess run with ``args`` imported, by the end of its session."""
    pytester.makeconftest(DUMP_MODULES)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", *args)
    assert result.ret == status, result.stdout.str()
    return set((pytester.path / "modules.txt").read_text(encoding="utf-8").split())


def imported(pytester: pytest.Pytester, *args: str) -> set[str]:
    """The top-level names and ``fleetsim.exec`` modules imported by a pytest subprocess run with ``args``."""
    modules = all_imported(pytester, *args)
    return {m for m in modules if m.split(".")[0] == "hypothesis" or m.split(".")[:2] == ["fleetsim", "exec"]}


RECORDING = {"mcap", "rosbags", "fleetsim.recording.recorder", "fleetsim.recording.picture"}


def test_runs_that_pass_load_no_recording_and_a_failing_one_does(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("CI", raising=False)
    copy_example_suites(pytester)
    assert not RECORDING & all_imported(pytester, "--planner", RESERVING, "-k", "crossing")
    greedy = all_imported(
        pytester, "--planner", "fleetsim.planners:GreedyPlanner", "-k", "corridor", status=pytest.ExitCode.TESTS_FAILED
    )
    assert greedy >= RECORDING  # its failure picture and recording were written


MARK_THE_LIBRARY = """import pytest


@pytest.hookimpl(tryfirst=True)
def pytest_configure(config):
    # What an ordinary (not editable) install of fleetsim has pytest do: mark the distribution's packages.
    config.pluginmanager.rewrite_hook.mark_rewrite("fleetsim")
"""

REWRITTEN = """import fleetsim.cli.run  # a module with asserts, imported by no plugin before this test


def test_rewritten():
    print("REWRITTEN", "@py_builtins" in vars(fleetsim.cli.run))
"""


@pytest.mark.parametrize(("plugin", "rewritten"), [((), "False"), (("-p", "no:fleetsim"), "True")])
def test_the_library_is_not_assertion_rewritten_while_the_plugin_is_loaded(
    pytester: pytest.Pytester, plugin: tuple[str, ...], rewritten: str
) -> None:
    pytester.makeconftest(MARK_THE_LIBRARY)
    pytester.makepyfile(test_rewritten=REWRITTEN)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-s", *plugin)
    assert result.ret == pytest.ExitCode.OK, result.stdout.str()
    result.stdout.fnmatch_lines([f"*REWRITTEN {rewritten}"])


def test_a_plain_scenario_under_pytest_imports_neither_hypothesis_nor_the_exec_protocol(
    pytester: pytest.Pytester,
) -> None:
    copy_example_suites(pytester)
    assert imported(pytester, "--planner", RESERVING, "-k", "crossing") == set()


def test_a_generated_entry_does_import_hypothesis(pytester: pytest.Pytester) -> None:
    pytester.makefile(".fleetsim.yaml", hunting=GENERATED)
    found = imported(pytester, "--planner", RESERVING)
    assert "hypothesis" in found
    assert not {m for m in found if m.startswith("fleetsim.exec")}


def test_an_exec_planner_does_import_the_exec_protocol(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("CI", raising=False)  # its exec planner has no recorded hash: not recorded, not failed
    copy_example_suites(pytester)
    found = imported(pytester, "--planner", f"exec:{sys.executable} -m fleetsim.exec {RESERVING}", "-k", "crossing")
    assert {"fleetsim.exec.process", "fleetsim.exec.protocol"} <= found
    assert "hypothesis" not in found


def test_the_plugin_reads_exec_specs_by_the_prefix_the_exec_package_defines() -> None:
    from fleetsim.exec.spec import EXEC_PREFIX
    from pytest_fleetsim import _planner

    assert _planner.EXEC_PREFIX == EXEC_PREFIX
