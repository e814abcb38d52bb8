"""``fleetsim run --json`` in fresh processes: trace hashes do not depend on the hash seed (SPEC §10)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from fleetsim import load_suite

pytestmark = pytest.mark.integration

ROOT = Path(__file__).resolve().parents[2]
# Exactly what the ``fleetsim`` console script runs (python -m fleetsim.cli.main warns, as the package
# imports the module before runpy executes it).
FLEETSIM = [sys.executable, "-c", "import sys; from fleetsim.cli import main; sys.exit(main())"]


def run_suites(hash_seed: str, folder: Path, *targets: str) -> list[dict[str, Any]]:
    # CI set: the generated entry's hunt is derandomised too, so every result is reproducible. Run in a
    # folder of its own: the hunt's counterexample goes to ./fleetsim-results, which other tests write too.
    env = {**os.environ, "PYTHONHASHSEED": hash_seed, "CI": "true"}
    command = [*FLEETSIM, "run", *targets, "--planner", "fleetsim.planners:ReservingPlanner", "--json"]
    done = subprocess.run(command, cwd=folder, env=env, capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    results = [json.loads(line) for line in done.stdout.splitlines()]
    assert all(result["status"] == "passed" for result in results if result["xfail"] is None)
    return results


def _recorded(result: dict[str, Any]) -> str | None:
    """The hash the suite's shipped lock file records for this result's scenario and planner, if any."""
    lock = ROOT / result["suite"].replace(".fleetsim.yaml", ".fleetsim.lock.json")
    hashes = json.loads(lock.read_text(encoding="utf-8"))["hashes"].get(result["planner"], {})
    entry = hashes.get(result["scenario"])
    return None if entry is None else str(entry["hash"])


def test_trace_hashes_are_the_same_under_different_hash_seeds(tmp_path: Path) -> None:
    # The lock files were recorded in processes of other hash seeds: a run under one seed gives their
    # hashes; what they do not record (the hunts) is run again under a second seed.
    suites = ROOT / "scenario_suites"
    results = run_suites("12345", tmp_path, str(suites))
    assert sorted(result["scenario"] for result in results) == sorted([
        "clinic-rmf", "corridor-head-on", "corridor-passing-bay", "crossing", "crossing-collides", "generated-layouts",
        "loop-one-way", "mixed-shapes", "packing-hall-lif", "late-crossing-stop", "late-crossing-hunt",
        *(spec.name for spec in load_suite(suites / "disturbances.fleetsim.yaml").scenarios),
        *(spec.name for spec in load_suite(suites / "warehouse.fleetsim.yaml").scenarios),
        *(spec.name for spec in load_suite(suites / "movingai.fleetsim.yaml").scenarios),
        *(spec.name for spec in load_suite(suites / "lorr.fleetsim.yaml").scenarios),
    ])  # fmt: skip
    unrecorded = [result for result in results if _recorded(result) is None]
    assert len(unrecorded) < len(results) // 4
    for result in results:
        if _recorded(result) is not None:
            assert result["trace_hash"] == _recorded(result), result["scenario"]
    again = run_suites("0", tmp_path, *(f"{suites / Path(r['suite']).name}::{r['scenario']}" for r in unrecorded))
    assert [(r["scenario"], r["trace_hash"]) for r in again] == [(r["scenario"], r["trace_hash"]) for r in unrecorded]
