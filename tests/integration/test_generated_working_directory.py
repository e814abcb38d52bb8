"""A hunt in a fresh process writes nothing into the working directory but the documented artifact folder.

Hypothesis keeps caches in ``.hypothesis/`` under the working directory the first time a process
generates anything, so only a fresh process shows whether a hunt leaves one behind.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.integration

SUITE = """\
fleetsim: 1
name: hunting
vehicle_types:
  agv: {length: 1.0, width: 0.6, height: 0.4, max_speed: 1.0, acceleration: 0.5, turn_capability: in_place}
defaults:
  time_limit: 120
scenarios:
  - name: random-loops
    generate: {layout: loop, size: [1, 2], vehicles: [1, 2], tasks: [1, 2], examples: 5}
"""
FLEETSIM = [sys.executable, "-c", "import sys; from fleetsim.cli import main; sys.exit(main())"]
PYTEST = [
    sys.executable,
    "-m",
    "pytest",
    "-p",
    "no:cacheprovider",
    "-p",
    "no:benchmark",
]  # both write folders of their own


def _run(command: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {key: value for key, value in os.environ.items() if key != "HYPOTHESIS_STORAGE_DIRECTORY"}
    return subprocess.run(
        command, cwd=cwd, env={**env, "CI": "1"}, capture_output=True, text=True, timeout=300, check=False
    )


@pytest.mark.parametrize("planner", ["BFSPlanner", "ReservingPlanner"])
def test_fleetsim_run_hunts_without_writing_a_hypothesis_folder(tmp_path: Path, planner: str) -> None:
    (tmp_path / "hunting.fleetsim.yaml").write_text(SUITE, encoding="utf-8")
    done = _run([*FLEETSIM, "run", "hunting.fleetsim.yaml", "--planner", f"fleetsim.planners:{planner}"], tmp_path)
    assert done.returncode == (1 if planner == "BFSPlanner" else 0), done.stdout + done.stderr
    expected = {"hunting.fleetsim.yaml", *(("fleetsim-results",) if planner == "BFSPlanner" else ())}
    assert {p.name for p in tmp_path.iterdir()} == expected


def test_pytest_hunts_without_writing_a_hypothesis_folder(tmp_path: Path) -> None:
    (tmp_path / "hunting.fleetsim.yaml").write_text(SUITE, encoding="utf-8")
    done = _run([*PYTEST, "--planner", "fleetsim.planners:BFSPlanner", "hunting.fleetsim.yaml"], tmp_path)
    assert done.returncode == 1, done.stdout + done.stderr
    assert {p.name for p in tmp_path.iterdir()} == {"hunting.fleetsim.yaml", "fleetsim-results"}
