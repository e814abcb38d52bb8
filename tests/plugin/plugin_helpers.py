"""Shared set-up for the pytester tests of the plugin: the shipped suites in a pytester folder."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

SUITES = Path(__file__).resolve().parents[2] / "scenario_suites"
RESERVING = "fleetsim.planners:ReservingPlanner"
BFS = "fleetsim.planners:BFSPlanner"


def copy_example_suites(pytester: pytest.Pytester, *suites: str, locks: bool = True) -> None:
    """Copy the shipped suites named (default ``examples``), their scenario folders and the Tiled
    templates into the pytester folder; with ``locks`` also their lock files (recorded hashes for
    ReservingPlanner in ``examples``, BFSPlanner in ``caught-bugs``)."""
    root = pytester.path
    for folder in ("examples", "tiled", "caught-bugs"):
        if not (root / folder).exists():
            shutil.copytree(SUITES / folder, root / folder)
    for suite in suites or ("examples",):
        shutil.copy(SUITES / f"{suite}.fleetsim.yaml", root)
        if locks:
            shutil.copy(SUITES / f"{suite}.fleetsim.lock.json", root)


def record_hashes(pytester: pytest.Pytester, *args: str) -> pytest.RunResult:
    """Run pytest with ``--fleetsim-update-hashes`` and ``args`` in-process; fail unless all passed."""
    result = pytester.runpytest_inprocess("--fleetsim-update-hashes", *args)
    assert result.ret == pytest.ExitCode.OK, result.stdout.str()
    return result
