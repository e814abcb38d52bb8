"""``fleetsim run --json`` of shipped scenarios with a ``vda5050:`` planner, in a process of its own, as a
user types it: shared by the tests that drive fleetsim with a master control it starts."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SUITE = "scenario_suites/examples.fleetsim.yaml"


def run_command(scenario: str, spec: str) -> list[str]:
    """The command line that runs the shipped example ``scenario`` with planner ``spec``."""
    return [sys.executable, "-m", "fleetsim", "run", f"{SUITE}::{scenario}", "--planner", spec, "--json"]


def run_example(scenario: str, spec: str, **environment: str) -> subprocess.CompletedProcess[str]:
    """Run it from the repository's root (``environment`` added to this one's), at most 120 s."""
    return subprocess.run(
        run_command(scenario, spec),
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, **environment},
        check=False,
    )
