"""``fleetsim run --json`` in fresh processes: trace hashes do not depend on the hash seed (SPEC §10)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from fleetsim import load_suite

pytestmark = pytest.mark.integration

ROOT = Path(__file__).resolve().parents[2]
# Exactly what the ``fleetsim`` console script runs (python -m fleetsim.cli.main warns, as the package
# imports the module before runpy executes it).
FLEETSIM = [sys.executable, "-c", "import sys; from fleetsim.cli import main; sys.exit(main())"]


def run_suites(hash_seed: str, folder: Path) -> dict[str, str]:
    # CI set: the generated entry's hunt is derandomised too, so every result is reproducible. Run in a
    # folder of its own: the hunt's counterexample goes to ./fleetsim-results, which other tests write too.
    env = {**os.environ, "PYTHONHASHSEED": hash_seed, "CI": "true"}
    suites = str(ROOT / "scenario_suites")
    command = [*FLEETSIM, "run", suites, "--planner", "fleetsim.planners:ReservingPlanner", "--json"]
    done = subprocess.run(command, cwd=folder, env=env, capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    results = [json.loads(line) for line in done.stdout.splitlines()]
    assert all(result["status"] == "passed" for result in results if result["xfail"] is None)
    return {result["scenario"]: result["trace_hash"] for result in results}


def test_trace_hashes_are_the_same_under_different_hash_seeds(tmp_path: Path) -> None:
    first = run_suites("0", tmp_path)
    second = run_suites("12345", tmp_path)
    assert sorted(first) == sorted([
        "clinic-rmf", "corridor-head-on", "corridor-passing-bay", "crossing", "crossing-collides", "generated-layouts",
        "loop-one-way", "mixed-shapes", "packing-hall-lif", "late-crossing-stop", "late-crossing-hunt",
        *(spec.name for spec in load_suite(ROOT / "scenario_suites" / "disturbances.fleetsim.yaml").scenarios),
        *(spec.name for spec in load_suite(ROOT / "scenario_suites" / "warehouse.fleetsim.yaml").scenarios),
        *(spec.name for spec in load_suite(ROOT / "scenario_suites" / "movingai.fleetsim.yaml").scenarios),
        *(spec.name for spec in load_suite(ROOT / "scenario_suites" / "lorr.fleetsim.yaml").scenarios),
    ])  # fmt: skip
    assert first == second
