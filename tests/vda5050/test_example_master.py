"""The shipped example master control (examples/vda5050/master_control.py) drives each shipped example to
its end through ``fleetsim run``, as its README says to run it: every task done, no collision alert, no
rejection. The four runs go in parallel, each its own ``fleetsim run`` with its own embedded broker."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from runs import run_command

ROOT = Path(__file__).resolve().parents[2]
MASTER = ROOT / "examples" / "vda5050" / "master_control.py"
EXAMPLES = {"crossing": 2, "loop-one-way": 4, "corridor-passing-bay": 2, "mixed-shapes": 3}  # name: tasks


@pytest.fixture(scope="module")
def results() -> dict[str, tuple[int, str, dict[str, Any] | None]]:
    """Each example's exit status, stderr and JSON result, run at once."""
    spec = f"vda5050:speed=20,exec={sys.executable} {MASTER}"
    runs = {
        name: subprocess.Popen(
            run_command(name, spec),
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for name in EXAMPLES
    }
    found: dict[str, tuple[int, str, dict[str, Any] | None]] = {}
    for name, run in runs.items():
        out, err = run.communicate(timeout=120)
        lines = [json.loads(line) for line in out.splitlines() if line.strip()]
        found[name] = (run.returncode, err, lines[0] if len(lines) == 1 else None)
    return found


@pytest.mark.parametrize("name", list(EXAMPLES))
def test_the_example_master_control_completes_the_example(
    name: str, results: dict[str, tuple[int, str, dict[str, Any] | None]]
) -> None:
    status, stderr, result = results[name]
    assert status == 0, stderr
    assert result is not None, stderr
    assert result["status"] == "passed", result["failures"]
    assert result["tasks"] == {"total": EXAMPLES[name], "completed": EXAMPLES[name]}
    assert result["collisions"] == [] and result["rejections"] == [] and result["route_errors"] == []
    assert result["deadlock"] is None and result["paced"] == 20.0


def test_started_outside_fleetsim_it_names_what_its_environment_lacks() -> None:
    environment = {k: v for k, v in os.environ.items() if not k.startswith("FLEETSIM_")}
    environment["FLEETSIM_MQTT_URL"] = "mqtt://127.0.0.1:1"
    done = subprocess.run(
        [sys.executable, str(MASTER)], env=environment, capture_output=True, text=True, timeout=30, check=False
    )
    assert done.returncode == 2
    assert "FLEETSIM_VDA5050_INTERFACE, FLEETSIM_VDA5050_MANUFACTURER not set" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_broker_address_that_is_not_mqtt_is_named() -> None:
    environment = {k: v for k, v in os.environ.items() if not k.startswith("FLEETSIM_")}
    environment |= {
        "FLEETSIM_MQTT_URL": "http://127.0.0.1:1883",
        "FLEETSIM_VDA5050_INTERFACE": "uagv",
        "FLEETSIM_VDA5050_MANUFACTURER": "fleetsim",
    }
    done = subprocess.run(
        [sys.executable, str(MASTER)], env=environment, capture_output=True, text=True, timeout=30, check=False
    )
    assert done.returncode == 2
    assert "FLEETSIM_MQTT_URL 'http://127.0.0.1:1883' is not mqtt://host:port" in done.stderr
