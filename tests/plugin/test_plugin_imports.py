"""What a pytest session that runs scenarios imports: Hypothesis only for a generated entry, the exec
protocol only for an ``exec:`` planner (every module imported under pytest is also assertion-rewritten on
each start where bytecode is not written, so an unneeded import costs twice).

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


def imported(pytester: pytest.Pytester, *args: str) -> set[str]:
    """The top-level names and ``fleetsim.exec`` modules imported by a pytest subprocess run with ``args``."""
    pytester.makeconftest(DUMP_MODULES)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", *args)
    assert result.ret == pytest.ExitCode.OK, result.stdout.str()
    modules = (pytester.path / "modules.txt").read_text(encoding="utf-8").split()
    return {m for m in modules if m.split(".")[0] == "hypothesis" or m.split(".")[:2] == ["fleetsim", "exec"]}


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
